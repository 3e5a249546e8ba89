"""Python objectives from several threads: each call takes the GIL, the C++ work between calls runs
without it, so runs on two threads neither deadlock nor differ from the same runs one after another."""
import threading

import numpy as np

import mhbench


def rastrigin(X):
    return 10 * X.shape[1] + (X * X - 10 * np.cos(2 * np.pi * X)).sum(axis=1)


def run(seed):
    return mhbench.minimize("de", rastrigin, bounds=[(-5.12, 5.12)] * 8, budget=4000, seed=seed)


def test_two_threads_give_the_sequential_results():
    seeds = [1, 2, 3, 4]
    sequential = {s: run(s) for s in seeds}
    parallel = {}

    def worker(own):
        for s in own:
            parallel[s] = run(s)

    threads = [threading.Thread(target=worker, args=(seeds[k::2],), daemon=True) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert not any(t.is_alive() for t in threads), "a thread is still running: deadlock"
    for s in seeds:
        assert parallel[s].f == sequential[s].f
        assert np.array_equal(parallel[s].history, sequential[s].history)


def test_the_gil_is_released_while_a_cpp_problem_runs():
    """A Python thread makes progress while minimize works on a C++ problem in another."""
    ticks = []
    done = threading.Event()

    def ticker():
        while not done.is_set():
            ticks.append(1)
            done.wait(0.001)

    t = threading.Thread(target=ticker, daemon=True)
    t.start()
    try:
        result = mhbench.minimize("cmaes", "cec2017_f5", budget=60000, seed=1, problem_options={"dimension": 30})
    finally:
        done.set()
        t.join()
    assert result.evaluations == 60000
    assert len(ticks) > 10
