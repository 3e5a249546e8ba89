"""The module installed by `cmake --install` into a prefix of its own works from there alone."""
import os
import pathlib
import subprocess
import sys
import textwrap


def test_installed_module_imports_and_runs_from_the_prefix(tmp_path):
    prefix = tmp_path / "prefix"
    subprocess.run([os.environ["MHBENCH_CMAKE"], "--install", os.environ["MHBENCH_BUILD_DIR"], "--prefix", str(prefix)],
                   check=True, capture_output=True)
    site = prefix / os.environ["MHBENCH_PYTHON_INSTALL_DIR"]
    assert (site / "mhbench" / "__init__.py").is_file()
    script = textwrap.dedent("""
        import numpy as np, mhbench
        r = mhbench.minimize("cmaes", lambda X: (X * X).sum(axis=1), bounds=[(-1, 1)] * 4, budget=2000, seed=1)
        maps = open("/proc/self/maps").read()
        core = sorted({line.split()[-1] for line in maps.splitlines() if "libmhbench.so" in line})
        print(mhbench.__file__); print(r.f < 1e-8); print(" ".join(core))
    """)
    environment = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"} | {"PYTHONPATH": str(site)}
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, env=environment, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    module_file, converged, core = done.stdout.splitlines()
    assert pathlib.Path(module_file).is_relative_to(site)
    assert converged == "True"
    # The core library beside the installed program, not the build tree's.
    assert core and all(pathlib.Path(path).is_relative_to(prefix) for path in core.split()), core
