"""Speed of mhbench.minimize with Python objectives (docs/performance.md):

  PYTHONPATH=build/python python3 tests/benchmarks/python_minimize_benchmark.py

1. The overhead of one batch call into a Python objective beyond the objective itself. random_search
   draws the same points whatever the values, so a run on a C++ problem and a run on a Python objective
   differ only by how the values are computed: overhead per call = (T_python - T_cpp) / calls
   + (the C++ problem's own time per call) - (the Python objective's own time per call), each measured.
2. Evaluations per second of minimize with a numpy sphere at D = 30, beside the same run on the C++ F1.
"""
import time
import timeit

import numpy as np

import mhbench

D = 30
POPULATION = 30


def best_of(repeats, function):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def overhead_per_call(calls=20000):
    budget = calls * POPULATION
    values = np.zeros(POPULATION)

    def returns_values(X):
        return values

    options = {"batch": POPULATION}
    bounds = [(-100.0, 100.0)] * D
    t_python = best_of(5, lambda: mhbench.minimize("random_search", returns_values, bounds, budget=budget, seed=1,
                                                   options=options))
    t_cpp = best_of(5, lambda: mhbench.minimize("random_search", "F1", budget=budget, seed=1, options=options,
                                                problem_options={"dimension": D}))
    # The objectives' own time per call: the Python function called from Python, and F1 on many points at once.
    X = np.random.default_rng(0).uniform(-100, 100, size=(POPULATION, D))
    own_python = min(timeit.repeat(lambda: returns_values(X), number=200000, repeat=5)) / 200000
    many = np.random.default_rng(1).uniform(-100, 100, size=(200000, D))
    f1 = mhbench.Problem("F1", dimension=D)
    own_cpp = best_of(5, lambda: f1.evaluate(many)) / (len(many) / POPULATION)
    return (t_python - t_cpp) / calls + own_cpp - own_python, t_python / calls, t_cpp / calls, own_cpp, own_python


def sphere(X):
    return np.einsum("ij,ij->i", X, X)


def evaluations_per_second(optimizer, budget=300000):
    bounds = [(-100.0, 100.0)] * D
    runs = {}
    for label, fun in (("numpy sphere", sphere), ("C++ F1", "F1")):
        extra = {"problem_options": {"dimension": D}} if fun == "F1" else {}
        seconds = best_of(3, lambda: mhbench.minimize(optimizer, fun, None if fun == "F1" else bounds, budget=budget,
                                                      seed=1, **extra))
        runs[label] = budget / seconds
    return runs


if __name__ == "__main__":
    overhead, per_call_python, per_call_cpp, own_cpp, own_python = overhead_per_call()
    print(f"batch call, D = {D}, {POPULATION} points: overhead {overhead * 1e6:.2f} us per call "
          f"(run per call: Python objective {per_call_python * 1e6:.2f} us, C++ F1 {per_call_cpp * 1e6:.2f} us; "
          f"own time per call: F1 {own_cpp * 1e6:.2f} us, Python objective {own_python * 1e6:.2f} us)")
    for optimizer in ("random_search", "de", "gwo", "cmaes"):
        rates = evaluations_per_second(optimizer)
        print(f"{optimizer:>14}: numpy sphere {rates['numpy sphere'] / 1e6:.2f} M evaluations/s, "
              f"C++ F1 {rates['C++ F1'] / 1e6:.2f} M evaluations/s")
