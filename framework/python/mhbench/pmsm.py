"""mhbench.pmsm: identify a PMSM's electrical model from measurements, as `mhbench fit`, `diagnose` and
`simulate` do (docs/python.md, docs/effects.md, docs/data-format.md).

    data = mhbench.pmsm.simulate("experiments/pmsm/multi_point_profile.toml").data   # dict of numpy columns
    fit = mhbench.pmsm.fit(data, model="base+deadtime")
    fit.parameters["Rs"], fit.intervals["Rs"], fit.residuals["u_d"]
    d = mhbench.pmsm.diagnose("data.csv", model="base", report="report")   # report/report.html
    d.recommended, d.findings

data is a measurement file (CSV, MAT v5/v7/v7.3, HDF5; columns= and pole_pairs= map its names and
units as --columns and --pole-pairs do) or a dict of numpy arrays named as docs/data-format.md names the
columns: i_d, i_q, u_d, u_q, omega_e required; t, segment, theta_e, temp_winding, temp_magnet optional.
"""
import os
import tomllib
from dataclasses import dataclass
from typing import Optional

from . import _mhbench

_bindings = _mhbench._pmsm

__all__ = ["DiagnosisResult", "FitResult", "SimulationResult", "diagnose", "fit", "simulate"]


@dataclass
class FitResult:
    """A model fitted to measurements. parameters: {name: value} for every parameter of the model (Rs, Ld,
    Lq, psi_f, then effect.parameter); intervals: {name: (lower, upper)}, the 95 % interval (NaN where the
    data do not determine it; the value itself where the model fixes it); standard_errors, units likewise;
    residuals: {"u_d": ..., "u_q": ...}, logged minus predicted voltage per sample (numpy); report: what
    `mhbench fit --json` writes; text: what `mhbench fit` prints."""
    model: str
    parameters: dict
    intervals: dict
    standard_errors: dict
    units: dict
    residuals: dict
    report: dict
    text: str

    def __repr__(self) -> str:
        values = ", ".join(f"{k}={v:.6g}" for k, v in self.parameters.items())
        return f"FitResult(model={self.model!r}, {values})"


@dataclass
class DiagnosisResult:
    """Where a model fails and which library effect is missing. recommended: the model to fit next (a
    model spec); findings: the statements in words; report: what `mhbench diagnose --json` writes (every
    candidate, its evidence and verdict); text: what `mhbench diagnose` prints; report_html: the page written
    when report= was given."""
    model: str
    recommended: str
    findings: list
    report: dict
    text: str
    report_html: Optional[str] = None

    def __repr__(self) -> str:
        return f"DiagnosisResult(model={self.model!r}, recommended={self.recommended!r})"


@dataclass
class SimulationResult:
    """A simulated drive: data, the measurement as numpy columns (fit and diagnose take it as it is);
    truth, what the CSV's JSON sidecar records (true parameters, effects, noise, seed, segments)."""
    data: dict
    truth: dict
    seed: int

    def __repr__(self) -> str:
        return f"SimulationResult(rows={len(self.data['i_d'])}, seed={self.seed})"


def _fit_result(record: dict) -> FitResult:
    names = record["names"]
    return FitResult(
        model=record["model"],
        parameters=dict(zip(names, map(float, record["values"]))),
        intervals={n: (float(lo), float(hi)) for n, lo, hi in zip(names, record["lower"], record["upper"])},
        standard_errors=dict(zip(names, map(float, record["standard_error"]))),
        units=dict(zip(names, record["units"])),
        residuals={"u_d": record["residual_d"], "u_q": record["residual_q"]},
        report=record["report"],
        text=record["text"],
    )


def fit(data, model: str = "base", *, optimizer: str = "cmaes", evaluations: int = 0, seed: int = 1,
        settle: float = 0.0, search_rows: Optional[int] = None, columns: Optional[dict] = None, pole_pairs: int = 0,
        threads: Optional[int] = None, control_period: float = 0.0, carrier_frequency: float = 0.0,
        dc_voltage: float = 0.0) -> FitResult:
    """Fits a model (base + effects, e.g. "base+deadtime+delay(tau=150e-6)") to data, as `mhbench fit` does
    with the same options: the same data and settings give the same parameters to the last bit.
    optimizer, evaluations (0: 150 + 50 per searched parameter) and seed drive the search of the effects'
    nonlinear parameters; settle drops that many seconds after each segment start; search_rows bounds the
    rows the search uses; threads caps the worker threads (results do not depend on it); control_period (s),
    as `--control-period`, adds report["sample_and_hold"]: the base parameters corrected for the drive's sample
    and hold, with carrier_frequency (Hz) and dc_voltage (V) its carrier's ripple too (docs/diagnosis.md);
    report["shared_noise"], where the data have an angle and steady windows, states what the noise the logged current
    and voltage share does to the base parameters, as `mhbench fit` does."""
    return _fit_result(_bindings.fit(data, model, optimizer, evaluations, seed, settle, search_rows, columns,
                                     pole_pairs, threads, control_period, carrier_frequency, dc_voltage))


def diagnose(data, model: str = "base", *, optimizer: str = "cmaes", evaluations: int = 0, seed: int = 1,
             settle: float = 0.0, search_rows: Optional[int] = None, columns: Optional[dict] = None,
             pole_pairs: int = 0, threads: Optional[int] = None, report=None,
             whole_laws: bool = False, control_period: float = 0.0, carrier_frequency: float = 0.0,
             dc_voltage: float = 0.0) -> DiagnosisResult:
    """Diagnoses a model against data, as `mhbench diagnose` does: where it fails, which library effect is
    most likely missing and how sure, and the model to fit next. report: a directory to write report.md,
    the plots and report.html into. whole_laws: add a law of several terms (saturation) only whole, as
    `--whole-laws` does (docs/diagnosis.md, section 1). Options as for fit."""
    record = _bindings.diagnose(data, model, optimizer, evaluations, seed, settle, search_rows, columns, pole_pairs,
                                threads, report, whole_laws, control_period, carrier_frequency, dc_voltage)
    return DiagnosisResult(model=record["model"], recommended=record["recommended"],
                           findings=list(record["report"].get("findings", [])), report=record["report"],
                           text=record["text"], report_html=record.get("report_html"))


def simulate(profile, *, effects: Optional[dict] = None, seed: Optional[int] = None, out=None) -> SimulationResult:
    """Simulates a drive, as `mhbench simulate` does: profile is a simulation profile's TOML file or a dict of
    the same content (docs/pmsm.md). effects: {effect name: {parameter: value}} added to (or replacing
    entries of) the profile's [effects]; seed: the noise seed, replacing the profile's; out: a CSV file to
    write the measurement to, with its JSON sidecar beside it."""
    base_directory = None
    if effects is not None:
        if not isinstance(effects, dict):
            raise TypeError(f"effects: expects a dict {{effect: {{parameter: value}}}}, got {type(effects).__name__}")
        if not isinstance(profile, dict):
            path = os.fspath(profile)
            with open(path, "rb") as f:
                profile = tomllib.load(f)
            base_directory = os.path.dirname(os.path.abspath(path))
        profile = dict(profile)
        profile["effects"] = {**profile.get("effects", {}), **effects}
    record = _bindings.simulate(profile, base_directory, seed, out)
    return SimulationResult(data=record["data"], truth=record["truth"], seed=record["seed"])
