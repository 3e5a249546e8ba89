"""Shared fixtures of the Python module's tests. CTest runs each file with PYTHONPATH naming the build
tree's package and MHBENCH_CLI naming the program, so results can be checked against the command line."""
import json
import os
import pathlib
import subprocess

import pytest


@pytest.fixture(scope="session")
def cli() -> pathlib.Path:
    return pathlib.Path(os.environ["MHBENCH_CLI"])


@pytest.fixture(scope="session")
def run_cli(cli):
    """Runs `mhbench ARGS...`; returns the completed process (stdout, stderr as text)."""
    def run(*arguments, input=None, check=True):
        done = subprocess.run([str(cli), *map(str, arguments)], input=input, capture_output=True, text=True)
        if check and done.returncode != 0:
            raise AssertionError(f"mhbench {' '.join(map(str, arguments))} exited {done.returncode}:\n{done.stderr}")
        return done
    return run


@pytest.fixture(scope="session")
def read_records():
    """The trial records of a results directory, keyed by (optimizer, problem, trial)."""
    def read(directory):
        records = {}
        with open(pathlib.Path(directory) / "results.jsonl") as f:
            for line in f:
                r = json.loads(line)
                records[(r["optimizer"], r["problem"], r["trial"])] = r
        return records
    return read
