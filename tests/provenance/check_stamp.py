"""framework/provenance_stamp.cmake, run as the build runs it, on a throwaway git repository: the
stamp is the commit, marked "+modified" once a tracked file differs from it, "unknown" outside a
checkout, and the header is not rewritten (so nothing recompiles) while the stamp stays the same."""
import argparse
import os
import pathlib
import re
import subprocess
import sys
import tempfile


def stamp(cmake, git, source, output):
    subprocess.run([cmake, f"-DGIT={git}", f"-DSOURCE_DIR={source}", f"-DOUTPUT={output}", "-P", SCRIPT], check=True)
    return re.search(r'#define MHBENCH_GIT_COMMIT "([^"]*)"', output.read_text()).group(1)


def git_in(repo, *args):
    return subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@t", *args], cwd=repo, check=True,
                          capture_output=True, text=True).stdout.strip()


parser = argparse.ArgumentParser()
parser.add_argument("--cmake", required=True)
parser.add_argument("--git", required=True)
parser.add_argument("--source", required=True)
args = parser.parse_args()
SCRIPT = str(pathlib.Path(args.source) / "framework" / "provenance_stamp.cmake")

failures = []
with tempfile.TemporaryDirectory() as scratch:
    repo = pathlib.Path(scratch) / "repo"
    repo.mkdir()
    output = pathlib.Path(scratch) / "stamp.hpp"
    (repo / "a.txt").write_text("one\n")
    git_in(repo, "init", "-q")
    git_in(repo, "add", "a.txt")
    git_in(repo, "commit", "-q", "-m", "first")
    commit = git_in(repo, "rev-parse", "HEAD")

    if (s := stamp(args.cmake, args.git, repo, output)) != commit:
        failures.append(f"clean tree: stamp {s!r}, expected {commit!r}")
    before = output.stat().st_mtime_ns
    os.utime(output, ns=(before - 10**9, before - 10**9))
    stamp(args.cmake, args.git, repo, output)
    if output.stat().st_mtime_ns != before - 10**9:
        failures.append("the header was rewritten although the stamp did not change")

    (repo / "untracked.txt").write_text("new\n")
    if (s := stamp(args.cmake, args.git, repo, output)) != commit:
        failures.append(f"an untracked file: stamp {s!r}, expected {commit!r}")
    (repo / "a.txt").write_text("two\n")
    if (s := stamp(args.cmake, args.git, repo, output)) != commit + "+modified":
        failures.append(f"an edited tracked file: stamp {s!r}, expected {commit + '+modified'!r}")

    outside = pathlib.Path(scratch) / "plain"
    outside.mkdir()
    if (s := stamp(args.cmake, args.git, outside, output)) != "unknown":
        failures.append(f"outside a checkout: stamp {s!r}, expected 'unknown'")

for f in failures:
    print("FAILED:", f)
sys.exit(1 if failures else 0)
