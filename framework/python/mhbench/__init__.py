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
import warnings
from dataclasses import dataclass
from typing import Any, Callable, Optional

from . import _mhbench
from ._mhbench import InputError, IterationState, PluginFault, Problem, evaluate, trial_seed

if hasattr(_mhbench, "_pmsm"):  # built with the PMSM problem (the default)
    from . import pmsm

__all__ = [
    "InputError", "IterationState", "MinimizeResult", "PluginFault", "Problem", "RunResult", "evaluate", "minimize",
    "optimizers", "plugins", "problems", "register_optimizer", "register_problem", "run", "trial_seed",
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


@dataclass
class RunResult:
    """What mhbench.run returns: where the results are (output: results.jsonl, table.md, table.csv,
    report.html), one entry per trial in trials (numpy columns: optimizer, problem, trial, seed, ok,
    best_fitness, evaluations, iterations, seconds, error, best_position) and table.csv's rows in table
    (numpy columns by header; float64 where every cell is a number). failed counts the trials that
    failed, failures says why for the first few."""
    output: str
    name: str
    trials: dict
    table: dict
    ran: int
    skipped: int
    failed: int
    failures: list
    notes: list
    seconds: float

    def to_pandas(self, what: str = "table"):
        """table.csv ("table") or the trials ("trials") as a pandas DataFrame; needs pandas, which mhbench
        itself never does."""
        try:
            import pandas
        except ImportError as missing:
            raise ImportError("to_pandas needs pandas (Debian: python3-pandas); the columns are numpy arrays in "
                              "RunResult.table and RunResult.trials") from missing
        if what not in ("table", "trials"):
            raise ValueError(f"what: expects 'table' or 'trials', got {what!r}")
        return pandas.DataFrame(dict(self.table if what == "table" else self.trials))

    def __repr__(self) -> str:
        return (f"RunResult(name={self.name!r}, output={self.output!r}, ran={self.ran}, skipped={self.skipped}, "
                f"failed={self.failed})")


def run(config, *, threads: Optional[int] = None, out=None, resume: bool = False, plots: bool = False) -> RunResult:
    """Runs an experiment as `mhbench run` does: config is the path of its TOML file or a dict of the same
    content (relative paths in a dict are relative to the working directory). threads: worker threads
    (default: all cores; results do not depend on it); out: the output directory (default: the config's
    output); resume: keep the trials already in results.jsonl. Writes results.jsonl, table.md, table.csv
    and report.html, and the plots when plots=True (gnuplot). Failed trials do not raise: they are counted
    in failed, with a warning."""
    record = _mhbench.run(config, threads, out, resume, plots)
    result = RunResult(**record)
    if result.failed:
        warnings.warn(f"{result.failed} trial(s) failed; first: {result.failures[0]}", RuntimeWarning, stacklevel=2)
    return result


def register_problem(name: str, cls, *, summary: Optional[str] = None, parameters: Optional[dict] = None) -> None:
    """Registers a problem written in Python under name, beside the C++ ones: minimize, run and TOML
    experiments then use it by name. cls(**parameter values) makes one instance per trial, with
    bounds (shape (D, 2)) and evaluate(X) -> n values for an (n, D) array; optionally optimum (the known
    minimum, for error columns) and variable_names (D names). parameters: {name: default}; a value's type
    is its default's. summary: shown by problems() (default: the first line of the class's docstring)."""
    _mhbench.register_problem(name, cls, summary, parameters)


def register_optimizer(name: str, cls, *, summary: Optional[str] = None, parameters: Optional[dict] = None) -> None:
    """Registers an optimizer written in Python under name, beside the C++ ones. cls(**parameter values)
    makes one instance per run, with initialize(evaluator, rng) (create and evaluate the first
    population) and iterate(progress, evaluator, rng) (one generation). evaluator.evaluate(X) evaluates an
    (n, D) array and counts it; rng is the run's seeded generator (uniform, normal, below), so a seed fixes
    the run; progress.fraction() is the share of the budget used. parameters and summary as for
    register_problem."""
    _mhbench.register_optimizer(name, cls, summary, parameters)
