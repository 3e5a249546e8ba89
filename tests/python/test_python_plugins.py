"""Optimizers and problems written in Python, registered by name beside the C++ ones and used by
minimize and run, also on two threads."""
import numpy as np
import pytest

import mhbench


class ShiftedSphere:
    """sum((x - shift)^2) on [-5, 5]^D, minimum 0"""

    def __init__(self, dimension, shift):
        self.bounds = [(-5.0, 5.0)] * dimension
        self.shift = shift
        self.optimum = 0.0

    def evaluate(self, X):
        return ((X - self.shift) ** 2).sum(axis=1)


class CppF1ThroughPython:
    """F1 as the program computes it, called from Python"""

    def __init__(self, dimension):
        self.problem = mhbench.Problem("F1", dimension=dimension)
        self.bounds = self.problem.bounds

    def evaluate(self, X):
        return self.problem.evaluate(X)


class SometimesFailing:
    """raises on every evaluation when fail is true"""

    def __init__(self, dimension, fail):
        self.bounds = [(-5.0, 5.0)] * dimension
        self.fail = fail

    def evaluate(self, X):
        if self.fail:
            raise ArithmeticError("asked to fail")
        return (X ** 2).sum(axis=1)


class RecordingRandomSearch:
    """uniform points in the box, population at a time; keeps every value it saw"""

    def __init__(self, population):
        self.population = population
        self.seen = []

    def initialize(self, evaluator, rng):
        self.iterate(None, evaluator, rng)

    def iterate(self, progress, evaluator, rng):
        box = evaluator.bounds
        X = box[:, 0] + rng.uniform(size=(self.population, evaluator.dimension)) * (box[:, 1] - box[:, 0])
        f = evaluator.evaluate(X)
        self.seen.extend(f[np.isfinite(f)])
        RecordingRandomSearch.last = self


class Failing:
    def __init__(self):
        pass

    def initialize(self, evaluator, rng):
        raise LookupError("no start")

    def iterate(self, progress, evaluator, rng):
        pass


@pytest.fixture(scope="module", autouse=True)
def registered():
    mhbench.register_problem("py_shifted_sphere", ShiftedSphere, parameters={"dimension": 3, "shift": 1.0})
    mhbench.register_problem("py_f1", CppF1ThroughPython, parameters={"dimension": 4})
    mhbench.register_problem("py_fails", SometimesFailing, parameters={"dimension": 2, "fail": False})
    mhbench.register_optimizer("py_random_search", RecordingRandomSearch, parameters={"population": 10})
    mhbench.register_optimizer("py_failing", Failing)


def test_listed_beside_the_cpp_plugins():
    problems = {p["name"]: p for p in mhbench.problems()}
    assert "F1" in problems and "py_shifted_sphere" in problems
    assert problems["py_shifted_sphere"]["summary"] == "sum((x - shift)^2) on [-5, 5]^D, minimum 0"
    assert {q["name"]: (q["type"], q["default"]) for q in problems["py_shifted_sphere"]["parameters"]} == \
        {"dimension": ("int", 3), "shift": ("real", 1.0)}
    assert "py_random_search" in {p["name"] for p in mhbench.optimizers()}


def test_a_python_problem_by_name_reaches_its_optimum():
    result = mhbench.minimize("cmaes", "py_shifted_sphere", budget=4000, seed=2,
                              problem_options={"dimension": 5, "shift": 0.5})
    assert result.f < 1e-10
    assert np.allclose(result.x, 0.5, atol=1e-4)


def test_a_python_problem_gives_the_same_run_as_the_cpp_one():
    for seed in (1, 2):
        through_python = mhbench.minimize("pso", "py_f1", budget=2000, seed=seed)
        cpp = mhbench.minimize("pso", "F1", budget=2000, seed=seed, problem_options={"dimension": 4})
        assert through_python.f == cpp.f and np.array_equal(through_python.history, cpp.history)


def test_a_python_optimizer_is_counted_and_seeded_by_the_framework():
    result = mhbench.minimize("py_random_search", "F1", budget=95, seed=4, problem_options={"dimension": 3})
    search = RecordingRandomSearch.last
    assert result.evaluations == 95  # the last population is cut at the budget
    assert len(search.seen) == 95
    assert result.f == min(search.seen)
    again = mhbench.minimize("py_random_search", "F1", budget=95, seed=4, problem_options={"dimension": 3})
    other = mhbench.minimize("py_random_search", "F1", budget=95, seed=5, problem_options={"dimension": 3})
    assert again.f == result.f and other.f != result.f


def test_a_python_optimizers_exception_reaches_minimize():
    with pytest.raises(LookupError, match="no start"):
        mhbench.minimize("py_failing", "F1", budget=100, seed=1)


def test_two_threads_give_the_results_of_one(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    config = {
        "name": "python_plugins", "trials": 4, "seed": 9, "budget": {"evaluations": 1500},
        "optimizer": [{"name": "de"}, {"name": "py_random_search", "population": 15}],
        "problem": [{"name": "py_shifted_sphere", "dimension": 4}, {"name": "F1", "dimension": 4}],
    }
    one = mhbench.run(config | {"output": "one"}, threads=1)
    two = mhbench.run(config | {"output": "two"}, threads=2)
    assert one.failed == 0 and two.failed == 0
    order = lambda r: np.lexsort((r.trials["trial"], r.trials["problem"], r.trials["optimizer"]))  # noqa: E731
    for column in ("optimizer", "problem", "trial", "seed", "best_fitness", "evaluations"):
        assert np.array_equal(one.trials[column][order(one)], two.trials[column][order(two)]), column


def test_a_python_exception_in_run_fails_that_trial_only(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    config = {"name": "fails", "trials": 3, "seed": 1, "output": "out", "budget": {"evaluations": 40},
              "optimizer": [{"name": "random_search"}],
              "problem": [{"name": "py_fails", "fail": True}, {"name": "py_fails"}]}
    with pytest.warns(RuntimeWarning, match="3 trial"):
        result = mhbench.run(config, threads=2)
    failed = ~result.trials["ok"]
    assert list(result.trials["problem"][failed]) == ["py_fails(fail=true)"] * 3
    assert all("asked to fail" in e for e in result.trials["error"][failed])
    assert result.failed == 3 and (result.trials["evaluations"][~failed] == 40).all()


def test_names_that_are_taken_are_refused():
    with pytest.raises(mhbench.InputError) as raised:
        mhbench.register_problem("f1", ShiftedSphere)
    assert raised.value.field == "name"
    with pytest.raises(TypeError, match="^cls: "):
        mhbench.register_optimizer("py_not_a_class", 5)
