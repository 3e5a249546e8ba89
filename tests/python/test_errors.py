"""Errors from Python calls: TypeError/ValueError naming the argument, mhbench.InputError for values
mhbench refuses, mhbench.PluginFault for a broken contract, and a Python objective's own exception
passed through with its traceback."""
import traceback

import numpy as np
import pytest

import mhbench

BOX = [(-1, 1)] * 3


def sphere(X):
    return (X * X).sum(axis=1)


class ObjectiveBroke(Exception):
    pass


def test_an_objectives_exception_reaches_the_caller_with_its_traceback():
    calls = []

    def failing_objective(X):
        calls.append(len(X))
        if len(calls) == 3:
            raise ObjectiveBroke("third call")
        return sphere(X)

    with pytest.raises(ObjectiveBroke, match="third call") as raised:
        mhbench.minimize("pso", failing_objective, bounds=BOX, budget=10000, seed=1)
    frames = [frame.name for frame in traceback.extract_tb(raised.value.__traceback__)]
    assert "failing_objective" in frames
    assert len(calls) == 3  # nothing was evaluated after it


def test_a_callbacks_exception_reaches_the_caller():
    def callback(state):
        raise KeyError("from the callback")

    with pytest.raises(KeyError, match="from the callback"):
        mhbench.minimize("pso", sphere, bounds=BOX, budget=1000, seed=1, callback=callback)


@pytest.mark.parametrize("fun, batch, error, text", [
    (lambda X: sphere(X)[:-1], True, ValueError, r"^fun: returned \d+ value\(s\) for \d+ points"),
    (lambda X: "many", True, TypeError, r"^fun: must return"),
    (lambda x: [1.0, 2.0], False, TypeError, r"^fun: with batch=False must return one real number"),
])
def test_a_wrong_return_is_refused_naming_fun(fun, batch, error, text):
    with pytest.raises(error, match=text):
        mhbench.minimize("gwo", fun, bounds=BOX, budget=200, seed=1, batch=batch)


def test_a_nan_value_is_a_plugin_fault():
    with pytest.raises(mhbench.PluginFault, match="NaN"):
        mhbench.minimize("gwo", lambda X: np.full(len(X), np.nan), bounds=BOX, budget=200, seed=1)
    assert issubclass(mhbench.PluginFault, RuntimeError)


@pytest.mark.parametrize("arguments, error, text", [
    ({"optimizer": 3}, TypeError, r"^optimizer: "),
    ({"fun": 3}, TypeError, r"^fun: "),
    ({"bounds": [(0, 1, 2)]}, ValueError, r"^bounds: .*\(D, 2\)"),
    ({"bounds": [(1, 0)]}, ValueError, r"^bounds: row 0 has lower 1 > upper 0"),
    ({"bounds": [(0, np.inf)]}, ValueError, r"^bounds: .*finite"),
    ({"bounds": None}, TypeError, r"^bounds: "),
    ({"budget": None}, ValueError, r"^budget: "),
    ({"budget": -5}, ValueError, r"^budget: "),
    ({"budget": 2.5}, TypeError, r"^budget: "),
    ({"seed": -1}, ValueError, r"^seed: "),
    ({"seed": "one"}, TypeError, r"^seed: "),
    ({"options": [1]}, TypeError, r"^options: "),
    ({"options": {"population": [1, 2]}}, TypeError, r"^options\['population'\]: "),
    ({"callback": 5}, TypeError, r"^callback: "),
    ({"args": 5}, TypeError, r"^args: "),
    ({"max_time": 0}, ValueError, r"^max_time: "),
    ({"target": "low"}, TypeError, r"^target: "),
])
def test_bad_arguments_are_refused_naming_them(arguments, error, text):
    call = {"optimizer": "gwo", "fun": sphere, "bounds": BOX, "budget": 100, "seed": 1} | arguments
    with pytest.raises(error, match=text):
        mhbench.minimize(call.pop("optimizer"), call.pop("fun"), **call)


def test_values_mhbench_refuses_are_input_errors_naming_the_field():
    with pytest.raises(mhbench.InputError, match="gwo") as raised:
        mhbench.minimize("gwoo", sphere, bounds=BOX, budget=100)
    assert isinstance(raised.value, ValueError)
    with pytest.raises(mhbench.InputError) as raised:
        mhbench.minimize("gwo", sphere, bounds=BOX, budget=100, options={"population": 1})
    assert raised.value.field == "options['population']"
    assert raised.value.reason and raised.value.file is None
    with pytest.raises(mhbench.InputError) as raised:
        mhbench.minimize("gwo", sphere, bounds=BOX, budget=100, options={"wolves": 10})
    assert raised.value.field == "options['wolves']"
    with pytest.raises(mhbench.InputError) as raised:
        mhbench.minimize("gwo", "F1", budget=100, problem_options={"dimension": 0})
    assert raised.value.field == "problem_options['dimension']"
