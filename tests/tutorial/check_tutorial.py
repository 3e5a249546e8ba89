#!/usr/bin/env python3
"""The tutorial (docs/tutorial-missing-physics.md) reproduces character for character.

Runs every `$ ...` command of its indented blocks, in order, in a scratch directory that sees the
repository's build/, experiments/ and docs/ as the tutorial's reader does from the repository root,
and compares what each `./build/mhbench` command prints with the text under it. Exit 1 and the
differences when any differs. With --update, writes the printed output into the tutorial instead
(then read the diff: a changed number is a changed result, and the prose around it may need it too).
"""
import argparse
import difflib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

SOURCE = Path(__file__).resolve().parents[2]
TUTORIAL = SOURCE / "docs" / "tutorial-missing-physics.md"


def blocks(lines):
    """(index of the command line, command, printed lines, trailing blank lines) of each `$` block."""
    i = 0
    while i < len(lines):
        if not lines[i].startswith("    $ "):
            i += 1
            continue
        j = i + 1
        printed = []
        while j < len(lines) and (lines[j].startswith("    ") or lines[j] == "") and not lines[j].startswith("    $ "):
            printed.append(lines[j])
            j += 1
        blank = 0
        while printed and printed[-1] == "":
            printed.pop()
            blank += 1
        yield i, lines[i][6:], printed, blank
        i = j


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mhbench", required=True, help="the program the tutorial's ./build/mhbench stands for")
    parser.add_argument("--update", action="store_true", help="write what the program prints into the tutorial")
    args = parser.parse_args()
    program = Path(args.mhbench).resolve()
    scratch = Path(tempfile.mkdtemp(prefix="mhbench-tutorial-"))
    try:
        (scratch / "build").mkdir()
        (scratch / "build" / "mhbench").symlink_to(program)
        for name in ("experiments", "docs"):
            (scratch / name).symlink_to(SOURCE / name)
        lines = TUTORIAL.read_text().split("\n")
        out, last, differing = [], 0, 0
        for at, command, printed, blank in blocks(lines):
            out.extend(lines[last:at + 1])
            run = subprocess.run(command, shell=True, cwd=scratch, capture_output=True, text=True)
            got = [("    " + line) if line else "" for line in (run.stdout + run.stderr).rstrip("\n").split("\n")]
            if not command.startswith("./build/mhbench"):
                got = printed  # shell steps (cp, printf) print nothing; only their effect matters
            if got != printed:
                differing += 1
                print(f"DIFFERENT: {command}")
                for d in difflib.unified_diff(printed, got, "tutorial", "printed", lineterm="", n=1):
                    print(f"    {d}")
            out.extend(got + [""] * blank)
            last = at + 1 + len(printed) + blank
        out.extend(lines[last:])
        if args.update and differing:
            TUTORIAL.write_text("\n".join(out))
            print(f"updated {differing} blocks of {TUTORIAL}")
        print(f"{differing} of the tutorial's printed outputs differ")
        return 1 if differing and not args.update else 0
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
