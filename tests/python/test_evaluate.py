"""mhbench.evaluate and mhbench.Problem: the values of `mhbench evaluate`, to the last bit, from numpy
arrays read in place."""
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import mhbench


def cli_values(run_cli, problem, X, *options):
    text = "\n".join(" ".join(repr(float(v)) for v in row) for row in X) + "\n"
    out = run_cli("evaluate", problem, "--dimension", X.shape[1], *options, "--points", "-", input=text).stdout
    return np.array([float(v) for v in out.split()])


@pytest.mark.parametrize("problem, dimension, options", [
    ("F1", 10, ()), ("F9", 30, ()), ("cec2022_f1", 10, ()), ("cec2017_f5", 30, ()),
    ("bbob_f3", 10, ("--instance", 2)), ("bbob_f21", 5, ("--instance", 7)),
])
def test_values_equal_the_command_line(run_cli, problem, dimension, options):
    rng = np.random.default_rng(3)
    X = rng.uniform(-80, 80, size=(25, dimension))
    instance = options[1] if options else None
    assert np.array_equal(mhbench.evaluate(problem, X, instance=instance), cli_values(run_cli, problem, X, *options))


def test_known_optima():
    assert mhbench.evaluate("F1", np.zeros((1, 30)))[0] == 0.0
    p = mhbench.Problem("cec2022_f1", dimension=10)
    assert p.optimum == 300.0
    # The organisers' shift vector of F1 is its minimiser (problems/cec/data).
    shift = np.loadtxt(mhbench_source() / "problems/cec/data/cec2022/shift_data_1.txt").ravel()[:10]
    assert p.evaluate(shift) == pytest.approx(300.0, abs=1e-8)


def mhbench_source():
    import os
    import pathlib
    return pathlib.Path(os.environ["MHBENCH_SOURCE_DIR"])


def test_problem_object_and_single_points():
    p = mhbench.Problem("F1", dimension=4)
    assert p.dimension == 4
    assert np.array_equal(p.bounds, np.array([[-100.0, 100.0]] * 4))
    x = np.array([1.0, 2.0, 3.0, 4.0])
    assert p(x) == 30.0
    assert isinstance(p.evaluate(x), float)
    assert np.array_equal(p.evaluate(np.stack([x, 2 * x])), [30.0, 120.0])
    assert p.evaluate(np.empty((0, 4))).shape == (0,)


def test_other_layouts_and_dtypes_give_the_same_values():
    rng = np.random.default_rng(5)
    X = rng.uniform(-5, 5, size=(40, 10))
    reference = mhbench.evaluate("bbob_f8", X, instance=1)
    assert np.array_equal(mhbench.evaluate("bbob_f8", np.asfortranarray(X), instance=1), reference)
    assert np.array_equal(mhbench.evaluate("bbob_f8", X.tolist(), instance=1), reference)
    assert np.array_equal(mhbench.evaluate("bbob_f8", np.ascontiguousarray(np.vstack([X, X])[::2]), instance=1),
                          reference[0::2].tolist() + reference[1::2].tolist() if False else
                          mhbench.evaluate("bbob_f8", np.vstack([X, X])[::2].copy(), instance=1))
    I = np.arange(30).reshape(3, 10)
    assert np.array_equal(mhbench.evaluate("F1", I), mhbench.evaluate("F1", I.astype(float)))


def test_a_large_float64_array_is_not_copied():
    """The peak resident memory of evaluating 10^6 x 10 points (80 MB) grows by the 8 MB of the results, not by
    a copy; a Fortran-ordered array of the same size, which must be converted, shows what a copy would cost."""
    script = textwrap.dedent("""
        import resource, numpy as np, mhbench
        def peak(): return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
        X = np.random.default_rng(0).uniform(-1, 1, size=(1_000_000, 10))
        F = np.asfortranarray(X)
        mhbench.evaluate("F1", X[:2])
        before = peak(); f = mhbench.evaluate("F1", X); in_place = peak() - before
        del f
        before = peak(); f = mhbench.evaluate("F1", F); converted = peak() - before
        print(in_place, converted)
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    in_place, converted = map(int, done.stdout.split())
    assert in_place < 20e6, f"evaluating grew the peak by {in_place / 1e6:.1f} MB"
    assert converted > 70e6, f"the converted array grew the peak by only {converted / 1e6:.1f} MB"


def test_wrong_arrays_are_refused_naming_the_argument():
    with pytest.raises(TypeError, match=r"^X: .*complex"):
        mhbench.evaluate("F1", np.zeros((2, 3), dtype=complex))
    with pytest.raises(TypeError, match=r"^X: "):
        mhbench.evaluate("F1", [["a", "b"]])
    with pytest.raises(ValueError, match=r"^X: .*2-D"):
        mhbench.evaluate("F1", np.zeros((2, 3, 4)))
    with pytest.raises(ValueError, match=r"^X: .*dimension 4"):
        mhbench.Problem("F1", dimension=4).evaluate(np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"^X: point 1 .*x3"):
        mhbench.evaluate("F1", np.array([[0.0, 0, 0], [0, 0, np.nan]]))
    with pytest.raises(ValueError, match="fixed dimension"):
        mhbench.evaluate("F14", np.zeros((1, 3)))
    with pytest.raises(TypeError, match=r"^problem: "):
        mhbench.evaluate(3, np.zeros((1, 3)))


def test_input_errors_name_the_field():
    with pytest.raises(mhbench.InputError, match="bbob_f3") as raised:
        mhbench.evaluate("bbob_f33", np.zeros((1, 2)))
    assert raised.value.file is None and raised.value.line is None
    with pytest.raises(mhbench.InputError) as raised:
        mhbench.evaluate("F1", np.zeros((1, 2)), instance=2)
    assert raised.value.field == "instance"
    with pytest.raises(mhbench.InputError) as raised:
        mhbench.Problem("bbob_f3", dimension=10, options={"noise": "loud"})
    assert raised.value.field == "options['noise']"
