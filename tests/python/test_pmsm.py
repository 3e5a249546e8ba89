"""mhbench.pmsm: simulate, fit and diagnose give what `mhbench simulate`, `fit` and `diagnose` give on the
same data, from a file or from numpy columns."""
import csv
import json
import os
import pathlib

import numpy as np
import pytest

import mhbench

PROFILE = pathlib.Path(os.environ["MHBENCH_SOURCE_DIR"]) / "experiments/pmsm/multi_point_profile.toml"


@pytest.fixture(scope="module")
def simulated(tmp_path_factory, run_cli):
    directory = tmp_path_factory.mktemp("pmsm")
    run_cli("simulate", PROFILE, "--out", directory / "cli.csv")
    run_cli("fit", "--data", directory / "cli.csv", "--model", "base", "--json", directory / "fit.json")
    run_cli("diagnose", "--data", directory / "cli.csv", "--model", "base", "--json", directory / "diagnosis.json")
    return directory, mhbench.pmsm.simulate(PROFILE)


def test_simulate_gives_the_command_lines_data(simulated):
    directory, result = simulated
    with open(directory / "cli.csv") as f:
        rows = list(csv.DictReader(f))
    assert set(result.data) == set(rows[0])
    for name, values in result.data.items():
        expected = [r[name] for r in rows] if name == "segment" else [float(r[name]) for r in rows]
        assert np.array_equal(values, expected), name
    assert result.truth == json.loads((directory / "cli.json").read_text()) | {"profile": str(PROFILE)}


def test_fit_of_columns_and_of_the_file_give_the_command_lines_fit(simulated):
    directory, result = simulated
    expected = json.loads((directory / "fit.json").read_text())
    del expected["data"]
    from_columns = mhbench.pmsm.fit(result.data, model="base")
    from_file = mhbench.pmsm.fit(directory / "cli.csv", model="base")
    assert from_columns.report == expected
    assert from_file.report == expected
    for name, entry in expected["parameters"].items():
        assert from_columns.parameters[name] == entry["value"]
        assert list(from_columns.intervals[name]) == entry["ci95"]


def test_fit_holds_the_true_parameters_and_its_residuals(simulated):
    _, result = simulated
    fit = mhbench.pmsm.fit(result.data, model="base")
    truth = result.truth["true_parameters"]
    for name, value in truth.items():
        if name in fit.intervals:
            lower, upper = fit.intervals[name]
            assert lower <= value <= upper, name
    assert len(fit.residuals["u_d"]) == len(result.data["i_d"]) == len(fit.residuals["u_q"])
    assert np.sqrt(np.mean(fit.residuals["u_d"] ** 2)) == pytest.approx(fit.report["rms"]["u_d"], rel=1e-12)


def test_diagnose_gives_the_command_lines_recommendation_and_writes_the_report(simulated, tmp_path):
    directory, result = simulated
    expected = json.loads((directory / "diagnosis.json").read_text())
    diagnosis = mhbench.pmsm.diagnose(result.data, model="base", report=tmp_path / "report")
    assert diagnosis.recommended == expected["recommended_model"]
    assert diagnosis.findings == expected["findings"]
    assert pathlib.Path(diagnosis.report_html).is_file()


def test_diagnose_offers_a_law_with_fewer_terms_unless_whole_laws():
    # An example, one drive: seed 1 of the device study's clear saturation, whose nine operating points
    # do not pin the whole law (tests/pmsm_effect_set_search_test.cpp has the rates).
    import tomllib
    with open(PROFILE.parent / "device_diagnosis_profile.toml", "rb") as f:
        profile = tomllib.load(f)
    profile["plant"]["saturation"]["saturation_current"] = 0.3
    drive = mhbench.pmsm.simulate(profile, seed=1)
    reduced = mhbench.pmsm.diagnose(drive.data)
    assert reduced.recommended.startswith("base+saturation(")
    assert any(f.startswith("Only the terms of its law this log pins: saturation with ") for f in reduced.findings)
    assert mhbench.pmsm.diagnose(drive.data, whole_laws=True).recommended == "base"


def test_fit_corrects_for_a_stated_control_period():
    # The device servo without noise, its carrier at 40 kHz (whose own bias is then below 0.01 %):
    # the sample and hold of its 100 us control period makes Ld and Lq read 0.4 and 0.7 % high.
    import tomllib
    with open(PROFILE.parent / "device_diagnosis_profile.toml", "rb") as f:
        profile = tomllib.load(f)
    profile["noise"] = {"current": 0.0, "speed": 0.0, "temperature": 0.0}
    profile["plant"]["inverter"]["pwm_frequency"] = 40e3
    profile["drive"]["integration_step"] = 2.5e-6
    drive = mhbench.pmsm.simulate(profile, seed=1)
    truth = drive.truth["true_parameters"]
    result = mhbench.pmsm.fit(drive.data, control_period=100e-6)
    held = result.report["sample_and_hold"]
    assert held["control_period"] == 100e-6
    for name in ("Ld", "Lq"):
        before = abs(result.parameters[name] / truth[name] - 1)
        after = abs(held["corrected"][name]["value"] / truth[name] - 1)
        assert before > 3e-3 and after < 2e-4, (name, before, after)
    assert "sample and hold of the stated control period (100 µs)" in result.text
    assert "sample_and_hold" not in mhbench.pmsm.fit(drive.data).report
    diagnosis = mhbench.pmsm.diagnose(drive.data, control_period=100e-6)
    assert diagnosis.report["sample_and_hold"]["control_period"] == 100e-6


def test_simulate_with_effects_and_seed(simulated, tmp_path):
    _, clean = simulated
    result = mhbench.pmsm.simulate(PROFILE, effects={"deadtime": {}}, seed=7, out=tmp_path / "d.csv")
    assert result.seed == 7
    assert [e["name"] for e in result.truth["effects"]] == ["deadtime"]
    assert not np.array_equal(result.data["u_d"], clean.data["u_d"])
    assert (tmp_path / "d.csv").is_file() and (tmp_path / "d.json").is_file()


def test_bad_data_is_refused_naming_the_column(simulated):
    _, result = simulated
    data = dict(result.data)
    with pytest.raises(ValueError, match=r"^data: the column 'u_q' is missing"):
        mhbench.pmsm.fit({k: v for k, v in data.items() if k != "u_q"})
    with pytest.raises(ValueError, match=r"^data: unknown column 'speed'"):
        mhbench.pmsm.fit(data | {"speed": data["omega_e"]})
    with pytest.raises(ValueError, match=r"^data\['u_d'\]: 10 rows where the columns before have 2500"):
        mhbench.pmsm.fit(data | {"u_d": data["u_d"][:10]})
    with pytest.raises(ValueError, match=r"^data\['i_q'\]: point 3 "):
        broken = data["i_q"].copy()
        broken[3] = np.inf
        mhbench.pmsm.fit(data | {"i_q": broken})
    with pytest.raises(mhbench.InputError):
        mhbench.pmsm.fit(data, model="base+no_such_effect")
    with pytest.raises(TypeError, match="^data: "):
        mhbench.pmsm.fit(42)


def test_a_raw_log_gets_its_operating_points_found_as_the_command_line_finds_them(tmp_path, run_cli):
    # A bench log without a segment column (the tutorial's, section 7): fit and diagnose find its steady
    # windows as `mhbench fit` and `diagnose` do, say so in their report, and the diagnosis report
    # plots the log with the windows shaded.
    profile = pathlib.Path(os.environ["MHBENCH_SOURCE_DIR"]) / "experiments/pmsm/raw_bench_log.toml"
    run_cli("simulate", profile, "--out", tmp_path / "bench.csv")
    run_cli("fit", "--data", tmp_path / "bench.csv", "--model", "base", "--json", tmp_path / "fit.json")
    expected = json.loads((tmp_path / "fit.json").read_text())
    assert expected["operating_points"]["found_automatically"]
    fitted = mhbench.pmsm.fit(tmp_path / "bench.csv", model="base")
    assert fitted.report["operating_points"] == expected["operating_points"]
    assert fitted.parameters == {name: entry["value"] for name, entry in expected["parameters"].items()}
    diagnosis = mhbench.pmsm.diagnose(tmp_path / "bench.csv", model="base", report=tmp_path / "report")
    assert diagnosis.report["operating_points"] == expected["operating_points"]
    assert (tmp_path / "report" / "operating_points.png").is_file()
