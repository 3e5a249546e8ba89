"""mhbench.minimize: the command line's trial, to the last bit, on a Python objective; stopping on a
budget, a target, a time or a callback."""
import time

import numpy as np
import pytest

import mhbench

CONFIG = """
name = "python_equality"
trials = 2
seed = 11
output = "out"
[budget]
evaluations = 3000
[[optimizer]]
name = "gwo"
population = 20
[[optimizer]]
name = "de"
[[optimizer]]
name = "cmaes"
[[problem]]
name = "F1"
dimension = 10
[[problem]]
name = "bbob_f8"
dimension = 5
instance = 3
"""

SETTINGS = {  # what the config says, as minimize takes it
    "gwo": {"population": 20}, "de": {}, "cmaes": {},
}
PROBLEMS = {"F1(dimension=10)": ("F1", 10, None), "bbob_f8(dimension=5,instance=3)": ("bbob_f8", 5, 3)}


@pytest.fixture(scope="module")
def cli_records(tmp_path_factory, run_cli, read_records):
    directory = tmp_path_factory.mktemp("equality")
    (directory / "e.toml").write_text(CONFIG)
    run_cli("run", directory / "e.toml", "--no-plots", "--quiet", "--threads", 2)
    return read_records(directory / "out")


def check_same_trial(result, record):
    assert result.f == record["best_fitness"]
    assert np.array_equal(result.x, record["best_position"])
    assert result.evaluations == record["evaluations"]
    assert result.iterations == record["iterations"]
    assert np.array_equal(result.history, record["trace"]["best"])
    assert np.array_equal(result.history_evaluations, record["trace"]["evaluations"])


def test_the_seed_of_a_trial_is_trial_seed(cli_records):
    for (optimizer, problem, trial), record in cli_records.items():
        assert mhbench.trial_seed(11, optimizer, problem, trial) == record["seed"]
    assert len(cli_records) == 12


@pytest.mark.parametrize("batch", [True, False])
def test_python_objective_gives_the_command_lines_trial(cli_records, batch):
    for (optimizer, label, trial), record in cli_records.items():
        name, dimension, instance = PROBLEMS[label]
        problem = mhbench.Problem(name, dimension=dimension, instance=instance)
        fun = problem.evaluate  # the same values as the program's, through a Python call
        result = mhbench.minimize(optimizer.split("(")[0], fun, bounds=problem.bounds, budget=3000, seed=record["seed"],
                                  options=SETTINGS[optimizer.split("(")[0]], batch=batch)
        check_same_trial(result, record)
        assert result.stop == "budget"


def test_problem_by_name_gives_the_command_lines_trial(cli_records):
    for (optimizer, label, trial), record in cli_records.items():
        name, dimension, instance = PROBLEMS[label]
        problem_options = {"dimension": dimension} | ({"instance": instance} if instance else {})
        result = mhbench.minimize(optimizer.split("(")[0], name, budget=3000, seed=record["seed"],
                                  options=SETTINGS[optimizer.split("(")[0]], problem_options=problem_options)
        check_same_trial(result, record)


def numpy_sphere(X):
    return np.einsum("ij,ij->i", X, X)


def test_reaches_the_known_optimum_and_stops_exactly_at_the_budget():
    result = mhbench.minimize("cmaes", numpy_sphere, bounds=[(-5, 5)] * 10, budget=6000, seed=4)
    assert result.f < 1e-10  # the sphere's minimum is 0 at the origin
    assert np.abs(result.x).max() < 1e-4
    assert result.evaluations == 6000
    assert result.f == numpy_sphere(result.x[None, :])[0]
    assert np.all(np.diff(result.history) <= 0) and result.history[-1] == result.f


def test_same_seed_same_result_other_seed_other_result():
    runs = [mhbench.minimize("pso", numpy_sphere, bounds=[(-5, 5)] * 6, budget=1500, seed=s) for s in (8, 8, 9)]
    assert runs[0].f == runs[1].f and np.array_equal(runs[0].x, runs[1].x)
    assert runs[0].f != runs[2].f


def test_iterations_budget():
    result = mhbench.minimize("gwo", numpy_sphere, bounds=[(-1, 1)] * 3, iterations=7, seed=1,
                              options={"population": 10})
    assert result.iterations == 7 and result.stop == "iterations"
    assert result.evaluations == 10 * 8  # the initial population and 7 iterations of 10 wolves


def test_target_stops_early():
    result = mhbench.minimize("cmaes", numpy_sphere, bounds=[(-5, 5)] * 5, budget=100000, target=1e-3, seed=2)
    assert result.stop == "target"
    assert result.f <= 1e-3
    assert result.history[-2] > 1e-3  # it stopped after the first iteration that reached the target
    assert result.evaluations < 100000


def test_callback_sees_each_iteration_and_stops_the_run():
    seen = []

    def callback(state):
        seen.append((state.iteration, state.evaluations, state.f, state.x.copy()))
        return state.iteration == 3

    result = mhbench.minimize("de", numpy_sphere, bounds=[(-5, 5)] * 4, budget=100000, seed=3, callback=callback)
    assert result.stop == "callback" and result.iterations == 3
    assert [s[0] for s in seen] == [0, 1, 2, 3]
    assert [s[1] for s in seen] == list(result.history_evaluations)
    assert [s[2] for s in seen] == list(result.history)
    assert np.array_equal(seen[-1][3], result.x)


def test_max_time_stops_the_run():
    def slow(X):
        time.sleep(0.01)
        return numpy_sphere(X)

    start = time.perf_counter()
    result = mhbench.minimize("pso", slow, bounds=[(-5, 5)] * 3, budget=10**8, max_time=0.3, seed=1)
    assert result.stop == "time"
    assert 0.3 <= result.seconds < 0.3 + 0.5
    assert time.perf_counter() - start < 2


def test_args_reach_the_objective():
    shift = np.array([1.0, -2.0, 0.5])

    def shifted(X, center, scale):
        return scale * numpy_sphere(X - center)

    result = mhbench.minimize("cmaes", shifted, bounds=[(-5, 5)] * 3, budget=3000, seed=1, args=(shift, 2.0))
    assert np.allclose(result.x, shift, atol=1e-4)
    one = mhbench.minimize("cmaes", lambda x, c, s: s * float(np.dot(x - c, x - c)), bounds=[(-5, 5)] * 3,
                           budget=3000, seed=1, args=(shift, 2.0), batch=False)
    assert np.allclose(one.x, shift, atol=1e-4)
