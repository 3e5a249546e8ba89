"""mhbench.run: an experiment from its TOML file or a dict, the command line's results and table as
numpy columns."""
import csv

import numpy as np
import pytest

import mhbench

TOML = """
name = "python_run"
trials = 3
seed = 5
output = "cli-out"
[budget]
evaluations = 1200
[[optimizer]]
name = "gwo"
[[optimizer]]
name = "de"
population = 12
[[problem]]
name = "F1"
dimension = 5
[[problem]]
name = "bbob_f3"
dimension = 4
instance = 2
"""

AS_DICT = {
    "name": "python_run", "trials": 3, "seed": 5, "output": "dict-out", "budget": {"evaluations": 1200},
    "optimizer": [{"name": "gwo"}, {"name": "de", "population": 12}],
    "problem": [{"name": "F1", "dimension": 5}, {"name": "bbob_f3", "dimension": 4, "instance": 2}],
}

TIMES = ("mean_time_s", "total_time_s")


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory, run_cli, read_records):
    directory = tmp_path_factory.mktemp("cli")
    (directory / "e.toml").write_text(TOML)
    run_cli("run", directory / "e.toml", "--no-plots", "--quiet")
    with open(directory / "cli-out" / "table.csv") as f:
        rows = list(csv.DictReader(f))
    return read_records(directory / "cli-out"), rows


def check_same_as_cli(result, cli_run):
    records, rows = cli_run
    assert result.ran == 12 and result.failed == 0
    t = result.trials
    assert len(t["best_fitness"]) == 12
    for k in range(12):
        record = records[(t["optimizer"][k], t["problem"][k], int(t["trial"][k]))]
        assert t["best_fitness"][k] == record["best_fitness"]
        assert t["seed"][k] == record["seed"]
        assert np.array_equal(t["best_position"][k], record["best_position"])
        assert t["ok"][k]
    assert list(result.table["problem"]) == [r["problem"] for r in rows]
    for column, values in result.table.items():
        if column in TIMES or values.dtype.kind != "f":
            continue
        expected = [float(r[column]) if r[column] else np.nan for r in rows]
        assert np.array_equal(values, expected, equal_nan=True), column


def test_a_dict_runs_as_the_toml_file_does(cli_run, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = mhbench.run(AS_DICT, threads=2)
    assert result.output == str(tmp_path / "dict-out")
    check_same_as_cli(result, cli_run)
    for written in ("results.jsonl", "table.md", "table.csv", "report.html"):
        assert (tmp_path / "dict-out" / written).is_file()


def test_a_file_with_out_and_threads(cli_run, tmp_path):
    (tmp_path / "e.toml").write_text(TOML)
    result = mhbench.run(tmp_path / "e.toml", threads=1, out=tmp_path / "elsewhere")
    assert result.output == str(tmp_path / "elsewhere")
    check_same_as_cli(result, cli_run)
    again = mhbench.run(str(tmp_path / "e.toml"), out=tmp_path / "elsewhere", resume=True)
    assert again.ran == 0 and again.skipped == 12


def test_to_pandas_needs_pandas_only_when_called(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = mhbench.run(AS_DICT | {"trials": 1}, threads=1)
    try:
        import pandas  # noqa: F401
    except ImportError:
        with pytest.raises(ImportError, match="pandas"):
            result.to_pandas()
    else:
        assert list(result.to_pandas()["problem"]) == list(result.table["problem"])
        assert len(result.to_pandas("trials")) == 4


def test_a_bad_config_is_an_input_error_naming_the_field(tmp_path, monkeypatch, run_cli):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(mhbench.InputError, match="gwo") as raised:
        mhbench.run(AS_DICT | {"optimizer": [{"name": "gwoo"}]})
    assert raised.value.file == "<dict>"
    (tmp_path / "bad.toml").write_text(TOML.replace("population = 12", "population = 1"))
    with pytest.raises(mhbench.InputError) as raised:
        mhbench.run(tmp_path / "bad.toml")
    refused = run_cli("run", tmp_path / "bad.toml", check=False)
    assert refused.returncode == 2
    assert f"error: {raised.value}" in refused.stderr  # file, line and field as the program says them
    assert raised.value.file == str(tmp_path / "bad.toml") and raised.value.line > 0
    with pytest.raises(TypeError, match="^config: "):
        mhbench.run(42)
    with pytest.raises(TypeError, match=r"^config: problem\[0\].dimension: "):
        mhbench.run(AS_DICT | {"problem": [{"name": "F1", "dimension": object()}]})
