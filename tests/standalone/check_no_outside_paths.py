#!/usr/bin/env python3
"""A clone of the repository must build and pass every test alone: nothing the build, the tests, the
fuzz corpus, the experiments or CI read may point outside the checkout, in particular into the
workplace's shared inputs beside it (whose data the repository carries as copies, with their
provenance).

Scans the source and configuration files that are read when building, testing or running (not the
documentation, where the shared inputs are named as provenance) for a path that leaves the checkout
into a "shared" directory, and exits 1 naming each file and line, 0 when there is none.
"""
import pathlib
import re
import sys

SOURCE = pathlib.Path(__file__).resolve().parents[2]
SCANNED = ["CMakeLists.txt", ".ci", "framework", "optimizers", "problems", "experiments", "tests"]
SUFFIXES = {".cpp", ".hpp", ".h", ".txt", ".cmake", ".toml", ".py", ".sh", ".json", ""}
OUTSIDE = re.compile(r"\.\./(\.\./)*shared/|/work/shared\b")

found = []
for top in SCANNED:
    root = SOURCE / top
    files = [root] if root.is_file() else sorted(p for p in root.rglob("*") if p.is_file())
    for path in files:
        if path.suffix not in SUFFIXES or path.name == "README.md" or path == pathlib.Path(__file__).resolve():
            continue
        try:
            text = path.read_text(encoding="utf-8")
        except (UnicodeDecodeError, OSError):
            continue
        for number, line in enumerate(text.splitlines(), 1):
            if OUTSIDE.search(line):
                found.append(f"{path.relative_to(SOURCE)}:{number}: {line.strip()}")
if found:
    print("paths outside the checkout (a clone alone would not have them; copy the data in, with a README):")
    print("\n".join(found))
    sys.exit(1)
print(f"no path outside the checkout in {', '.join(SCANNED)}")
