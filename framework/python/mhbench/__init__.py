"""mhbench from Python: its optimizers and problems on numpy arrays (docs/python.md).

    import mhbench
    mhbench.optimizers()                       # names, parameters, ranges, descriptions
    mhbench.evaluate("cec2022_f1", X)          # X: (n, D) float64, read in place; n values
    r = mhbench.minimize("gwo", fun, bounds=[(-5, 5)] * 10, budget=20000, seed=1)
    r.x, r.f, r.history, r.evaluations

Errors: TypeError or ValueError naming the argument for a wrong type, shape or value;
mhbench.InputError (a ValueError) for a value mhbench refuses (an unknown name, a parameter out of
its range, a config that does not load); mhbench.PluginFault (a RuntimeError) when an optimizer or
a problem breaks the framework's contract during a run. An exception raised by a Python objective or
callback reaches the caller as it was raised, with its traceback.
"""
from dataclasses import dataclass, field
from typing import Any, Callable, Optional

from . import _mhbench
from ._mhbench import InputError, IterationState, PluginFault, Problem, evaluate, trial_seed

__all__ = [
    "InputError", "IterationState", "MinimizeResult", "PluginFault", "Problem", "evaluate", "minimize",
    "optimizers", "plugins", "problems", "trial_seed",
]


def plugins(kind: str) -> list:
    """Every registered plugin of one kind ("optimizers", "problems", "effects", ...), as `mhbench list` shows
    it: a list of dicts with name, summary and parameters (each: name, type, default, minimum, maximum,
    choices, range, unit, description)."""
    return _mhbench.plugins(kind)


def optimizers() -> list:
    """Every registered optimizer: name, summary and parameters (see plugins)."""
    return _mhbench.plugins("optimizers")


def problems() -> list:
    """Every registered problem: name, summary and parameters (see plugins)."""
    return _mhbench.plugins("problems")


@dataclass
class MinimizeResult:
    """The outcome of minimize. x and f are the best point evaluated and its value (the framework's own
    record, not the optimizer's claim); history[k] is the best value after iteration k (history[0]: after
    initialisation), reached after history_evaluations[k] evaluations; stop says what ended the run:
    "budget", "iterations", "target", "time" or "callback"."""
    x: Any
    f: float
    history: Any
    history_evaluations: Any
    evaluations: int
    iterations: int
    seconds: float
    seed: int
    stop: str
    optimizer: str

    def __repr__(self) -> str:
        return (f"MinimizeResult(f={self.f!r}, evaluations={self.evaluations}, iterations={self.iterations}, "
                f"stop={self.stop!r}, optimizer={self.optimizer!r}, seed={self.seed})")


def minimize(optimizer: str, fun, bounds=None, *, budget: Optional[int] = None, iterations: Optional[int] = None,
             seed: int = 0, options: Optional[dict] = None, batch: bool = True,
             callback: Optional[Callable[[IterationState], Any]] = None, args: tuple = (),
             target: Optional[float] = None, max_time: Optional[float] = None,
             problem_options: Optional[dict] = None) -> MinimizeResult:
    """Minimizes fun over a box with a registered optimizer.

    optimizer: a registered optimizer's name (optimizers()); options: its parameters, e.g. {"population": 30}.
    fun: fun(X, *args) with X an (n, D) float64 array of n points, returning n values; with batch=False,
        fun(x, *args) with one point of shape (D,), returning a number. Or a registered problem's name,
        whose parameters go in problem_options (e.g. {"dimension": 10}) and whose own box is used unless
        bounds is given.
    bounds: one (lower, upper) pair per variable, shape (D, 2).
    budget: evaluations; iterations: optimizer iterations (generations). At least one is needed; the run
        stops at the first reached, exactly at the budget whatever the optimizer does.
    seed: the run's random seed. The command line seeds trial k of an experiment with
        trial_seed(master_seed, optimizer_label, problem_label, k) (the record's "seed" in results.jsonl):
        minimize with that seed and the same settings gives that trial's result to the last bit.
    target: stop once the best value is <= target; max_time: stop after this many seconds; callback:
        callback(state) after initialisation and after each iteration, stopping the run when it returns
        True. These are checked between iterations, so an iteration under way finishes first.
    """
    record = _mhbench.minimize(optimizer, fun, bounds, budget, iterations, seed, options, batch, callback, args,
                               target, max_time, problem_options)
    return MinimizeResult(**record)
