#!/usr/bin/env python3
"""Runs `mhbench fit` on every file of a damaged-file corpus and counts the outcomes per class.

The corpus is written by the hidden test "[.write_damaged_corpus]" (tests/pmsm_damaged_measurement_test.cpp):

    MHBENCH_DAMAGED_CORPUS=/tmp/corpus build/mhbench_tests "[.write_damaged_corpus]"
    tests/damaged_files/count_outcomes.py --mhbench build/mhbench --corpus /tmp/corpus

Each file's outcome is one of: exit 0 with the parameters of the valid file it was made from
("same answer"), exit 0 with other parameters ("wrong answer"), exit 2 with an error line that
names the file (or one that does not), a hang (killed at --timeout), or a crash (any other exit).
Time and peak memory are /usr/bin/time's. The table is printed as Markdown (docs/data-format.md).
"""
import argparse
import collections
import json
import os
import subprocess
import tempfile


def run_fit(mhbench, path, columns, timeout):
    with tempfile.TemporaryDirectory() as scratch:
        json_path = os.path.join(scratch, "fit.json")
        times_path = os.path.join(scratch, "time")
        command = ["/usr/bin/time", "-o", times_path, "-f", "%e %M", mhbench, "fit", "--data", path, "--json", json_path]
        if columns:
            command += ["--columns", columns]
        try:
            done = subprocess.run(command, capture_output=True, text=True, errors="replace", timeout=timeout)
        except subprocess.TimeoutExpired:
            return {"kind": "hang", "seconds": timeout, "kb": 0, "stderr": ""}
        seconds, kb = 0.0, 0
        if os.path.exists(times_path):
            fields = open(times_path).read().split()
            if len(fields) >= 2 and fields[-2].replace(".", "").isdigit():
                seconds, kb = float(fields[-2]), int(fields[-1])
        parameters = None
        if done.returncode == 0 and os.path.exists(json_path):
            parameters = {name: p["value"] for name, p in json.load(open(json_path))["parameters"].items()}
        return {"kind": done.returncode, "seconds": seconds, "kb": kb, "stderr": done.stderr, "parameters": parameters}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mhbench", required=True)
    parser.add_argument("--corpus", required=True)
    parser.add_argument("--timeout", type=float, default=60.0)
    args = parser.parse_args()

    rows = [line.rstrip("\n").split("\t") for line in open(os.path.join(args.corpus, "manifest.tsv")) if line.strip()]
    reference = {}
    for name, kind, source, columns in rows:
        if kind == "valid":
            reference[name] = run_fit(args.mhbench, os.path.join(args.corpus, name), "", args.timeout)["parameters"]

    counts = collections.OrderedDict()
    for name, kind, source, columns in rows:
        if kind == "valid":
            continue
        path = os.path.join(args.corpus, name)
        result = run_fit(args.mhbench, path, columns, args.timeout)
        c = counts.setdefault(kind, collections.Counter())
        c["files"] += 1
        c["seconds"] = max(c["seconds"], result["seconds"])
        c["kb"] = max(c["kb"], result["kb"])
        if result["kind"] == "hang":
            c["hang"] += 1
        elif result["kind"] == 0:
            c["same" if result["parameters"] == reference.get(source) else "wrong"] += 1
        elif result["kind"] == 2:
            errors = [line for line in result["stderr"].splitlines() if line.startswith("error: ")]
            c["refused, file named" if len(errors) == 1 and errors[0].startswith("error: " + path + ": ") else "refused, file not named"] += 1
        else:
            c["crash"] += 1
        print(f"{kind}\t{name}\t{result['kind']}\t{result['seconds']:.2f} s\t{result['kb'] // 1024} MB\t"
              f"{(result['stderr'].strip().splitlines() or [''])[-1][:160]}", flush=True)

    columns = ["files", "same", "wrong", "refused, file named", "refused, file not named", "hang", "crash"]
    print()
    print("| class | files | exit 0, same answer | exit 0, wrong answer | exit 2, file named | exit 2, file not named | hang | crash | slowest | most memory |")
    print("|---|" + "---|" * 9)
    for kind, c in counts.items():
        cells = [str(c[k]) for k in columns]
        print(f"| {kind} | " + " | ".join(cells) + f" | {c['seconds']:.2f} s | {c['kb'] // 1024} MB |")
    total = collections.Counter()
    for c in counts.values():
        total.update({k: c[k] for k in columns})
    print("| all | " + " | ".join(str(total[k]) for k in columns) + " | | |")


if __name__ == "__main__":
    main()
