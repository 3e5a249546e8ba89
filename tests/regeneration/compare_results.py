#!/usr/bin/env python3
"""Regenerates committed results with a built mhbench and compares them with the committed files.

A refactoring must leave every result the same: tables, records, plots and diagnosis reports are
compared byte for byte, except fields that measure time or say where and when a run happened
(experiment.json's "runs", table columns of run time, a record's "seconds"). Those are the only
fields that differ between two runs of the same binary, which `--self-check` confirms by running
each job twice.

  tests/regeneration/compare_results.py --mhbench build/mhbench            # the CI subset
  tests/regeneration/compare_results.py --mhbench build/mhbench --all      # every committed result

The subset (about two minutes on 2 cores, 121 s measured 2026-11-26) reruns Table 3, the demo (every optimizer on classic and
BBOB functions), one case of each detection study (of the 5 kW and 100 kW machines' studies and of
the two raw-log studies the clean drives; of the detection-limit studies a pair at twice the limits) and the tutorial's diagnoses; --all reruns every experiment and study (about 15 minutes on
2 cores before the two machines' studies were added, and about 12 more for results/cec2022, 25 more
for results/cec2017, 4 for results/cec2022_lshade_code_choices and 50 for results/cec2017_jso_lshade
as they were measured, docs/test-functions.md and docs/algorithms.md).
Exit 0 when everything matches, 1 with a list of differences, 2 on bad usage.
"""
import argparse
import csv
import io
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

SOURCE = Path(__file__).resolve().parents[2]

# Table columns that hold run time: Markdown headers and CSV fields.
TIME_HEADER = re.compile(r"\btime\b|\(s\)$|seconds", re.IGNORECASE)
TIME_TEXT = re.compile(r"[0-9.]+ s of trial time")
TIME_FIELD = re.compile(r"(^|_)(time|seconds)(_s)?$|_time_s$|^seconds$")


class Job:
    """One command whose output directory is compared with committed files."""

    def __init__(self, name, command, committed, files=None, only_rows=None):
        self.name = name
        self.command = command      # argv after the program, with {out} for the output directory
        self.committed = committed  # directory in the repository
        self.files = files          # {committed name: produced relative path}; None: every committed file
        self.only_rows = only_rows  # {column: value}: compare only the study's rows of this case (and design)


def experiment_jobs():
    jobs = []
    for directory in sorted((SOURCE / "results").iterdir()):
        meta = directory / "experiment.json"
        if not meta.exists():
            continue
        info = json.loads(meta.read_text())
        command = ["run", info["config_file"], "--out", "{out}", "--quiet"]
        # A directory that holds one dimension of its config (run --dimension D) is rerun the same way.
        if info.get("selected_dimension"):
            command += ["--dimension", str(info["selected_dimension"])]
        jobs.append(Job(directory.name, command, directory))
    return jobs


def study_jobs(only=None):
    """Each committed study; with `only`, one case of each (a label, or design/label on a study with designs)."""
    jobs = []
    for name in ("detection_study", "detection_study_generating", "detection_study_averaged", "baldor_study", "baldor_generating_study", "detection_study_5kw", "detection_study_100kw",
                 "detection_study_raw", "detection_study_raw_5kw", "detection_limit_study_servo", "detection_limit_study_5kw",
                 "detection_limit_study_100kw"):
        command = ["study", f"experiments/pmsm/{name}.toml", "--out", "{out}", "--quiet"]
        rows = None
        if only:
            command += ["--only", only[name]]
            design, _, label = only[name].rpartition("/")
            rows = {"case": label, **({"design": design} if design else {})}
        jobs.append(Job(name, command, SOURCE / "results" / name, only_rows=rows))
    return jobs


def tutorial_jobs(program, scratch):
    """The tutorial's mystery drive: simulated, then diagnosed with the base and the final model; its
    raw bench log: simulated, then diagnosed, for the plot of its operating points."""
    data = scratch / "mystery.csv"
    run(program, ["simulate", "experiments/pmsm/mystery_drive.toml", "--out", str(data)])
    bench = scratch / "bench.csv"
    run(program, ["simulate", "experiments/pmsm/raw_bench_log.toml", "--out", str(bench)])
    figures = SOURCE / "docs" / "tutorial-missing-physics"
    return [
        Job("tutorial, base model", ["diagnose", "--data", str(data), "--model", "base", "--report", "{out}"], figures,
            files={"candidates_base.png": "candidates.png", "path_base.png": "path.png"}),
        Job("tutorial, final model", ["diagnose", "--data", str(data), "--model", "base+rs_thermal+deadtime+encoder_offset",
                                      "--report", "{out}"], figures, files={"segment_rms_final.png": "segment_rms.png"}),
        Job("tutorial, raw bench log", ["diagnose", "--data", str(bench), "--model", "base", "--report", "{out}"], figures,
            files={"operating_points_bench.png": "operating_points.png"}),
    ]


def run(program, argv):
    result = subprocess.run([str(program)] + argv, cwd=SOURCE, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"compare_results: `mhbench {' '.join(argv)}` failed ({result.returncode}):\n{result.stderr}")
    return result.stdout


def markdown_without_time(text):
    """Markdown tables with their run-time columns blanked; other lines as they are."""
    out, drop = [], []
    for line in text.splitlines():
        if line.startswith("|"):
            cells = line.strip().strip("|").split("|")
            if not set(line.strip()) <= set("|-: "):
                if not drop or any(TIME_HEADER.search(c.strip()) for c in cells):
                    drop = [i for i, c in enumerate(cells) if TIME_HEADER.search(c.strip())]
            cells = ["" if i in drop else c for i, c in enumerate(cells)]
            out.append("|".join(cells))
        else:
            drop = []
            out.append(TIME_TEXT.sub("<time>", line))
    return "\n".join(out)


def csv_rows(text, only_rows=None):
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        return rows
    header = rows[0]
    keep = [i for i, h in enumerate(header) if not TIME_FIELD.search(h)]
    body = rows[1:]
    if only_rows:
        columns = {header.index(field): value for field, value in only_rows.items()}
        body = [r for r in body if all(r[c] == v for c, v in columns.items())]
    return [[r[i] for i in keep if i < len(r)] for r in [header] + body]


def jsonl_records(text, only_rows=None):
    records = []
    for line in text.splitlines():
        record = json.loads(line)
        if only_rows and any(record.get(field) != value for field, value in only_rows.items()):
            continue
        for key in ("seconds", "time", "started"):
            record.pop(key, None)
        records.append(record)
    return records


def normalised(path, only_rows):
    """What of a file must not change: bytes, or the parsed content without its timing fields."""
    if path.suffix == ".csv":
        return csv_rows(path.read_text(), only_rows)
    if path.suffix == ".jsonl":
        return jsonl_records(path.read_text(), only_rows)
    if path.name == "experiment.json":
        meta = json.loads(path.read_text())
        meta.pop("runs", None)
        return meta
    if path.suffix == ".md":
        if only_rows:
            return None  # a subset's summary differs from the whole study's; its rows are in table.csv
        return markdown_without_time(path.read_text())
    return path.read_bytes()


def first_difference(a, b):
    if isinstance(a, str) and isinstance(b, str):
        for k, (x, y) in enumerate(zip(a.splitlines(), b.splitlines())):
            if x != y:
                return f"line {k + 1}:\n      committed: {x[:200]}\n      now:       {y[:200]}"
        return f"{len(a.splitlines())} lines committed, {len(b.splitlines())} now"
    if isinstance(a, list) and isinstance(b, list):
        for k, (x, y) in enumerate(zip(a, b)):
            if x != y:
                return f"row {k + 1}:\n      committed: {str(x)[:300]}\n      now:       {str(y)[:300]}"
        return f"{len(a)} rows committed, {len(b)} now"
    if isinstance(a, bytes):
        return f"bytes differ ({len(a)} committed, {len(b)} now)"
    return "content differs"


def committed_files(directory):
    """The files of `directory` that the repository holds. A run in the checkout (the quick start's
    main job) leaves others beside them that .gitignore keeps out (results.jsonl, report.html), with
    its own order of finished trials; those are not the committed results. Outside a git checkout,
    every file."""
    try:
        listed = subprocess.run(["git", "-C", str(SOURCE), "ls-files", "-z", "--", str(directory.relative_to(SOURCE))],
                                capture_output=True, check=True).stdout.decode()
    except (OSError, subprocess.CalledProcessError):
        return sorted(p.name for p in directory.iterdir() if p.is_file())
    inside = directory.relative_to(SOURCE)
    return sorted(Path(p).name for p in listed.split("\0") if p and Path(p).parent == inside)


def compare(job, produced):
    differences = []
    pairs = job.files.items() if job.files else [(name, name) for name in committed_files(job.committed)]
    for committed_name, produced_name in pairs:
        committed = job.committed / committed_name
        now = produced / produced_name
        if not now.exists():
            differences.append(f"{committed.relative_to(SOURCE)}: not produced")
            continue
        expected = normalised(committed, job.only_rows)
        if expected is None:
            continue
        got = normalised(now, job.only_rows)
        if job.only_rows and isinstance(expected, list) and len(expected) <= 1:
            differences.append(f"{committed.relative_to(SOURCE)}: holds no row of {job.only_rows}")
        elif expected != got:
            differences.append(f"{committed.relative_to(SOURCE)}: {first_difference(expected, got)}")
    return differences


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mhbench", required=True, help="the program to run (build/mhbench)")
    parser.add_argument("--all", action="store_true", help="every committed result, not the CI subset")
    parser.add_argument("--self-check", action="store_true", help="run each job twice and compare the runs with each other")
    parser.add_argument("--threads", default="2")
    parser.add_argument("--keep", help="leave the regenerated files in this directory")
    args = parser.parse_args()
    program = Path(args.mhbench).resolve()
    if not program.exists():
        parser.error(f"--mhbench: no such file: {program}")

    scratch = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="mhbench-regeneration-"))
    scratch.mkdir(parents=True, exist_ok=True)
    if args.all:
        jobs = experiment_jobs() + study_jobs()
    else:
        # Table 3 (GWO, SOA, ISOA on the PMSM) and the demo (every optimizer on classic and BBOB functions).
        jobs = [j for j in experiment_jobs() if j.name in ("pmsm_table3", "demo")]
        jobs += study_jobs({"detection_study": "deadtime+psi_thermal+rs_thermal", "detection_study_generating": "generating/encoder_offset",
                            "detection_study_averaged": "current_offset+delay+rs_thermal",
                            "baldor_study": "high_small_quiet/clean", "baldor_generating_study": "mid_large_quiet/clean", "detection_study_5kw": "clean",
                            "detection_study_100kw": "clean", "detection_study_raw": "raw/clean", "detection_study_raw_5kw": "raw/clean",
                            "detection_limit_study_servo": "encoder_offset+voltage_offset", "detection_limit_study_5kw": "deadtime+voltage_offset",
                            "detection_limit_study_100kw": "encoder_offset+flux_harmonic"})
    jobs += tutorial_jobs(program, scratch)

    failed = 0
    for k, job in enumerate(jobs):
        produced = scratch / f"job-{k}"
        shutil.rmtree(produced, ignore_errors=True)
        argv = [a.replace("{out}", str(produced)) for a in job.command]
        if "run" == argv[0] or "study" == argv[0]:
            argv += ["--threads", args.threads]
        run(program, argv)
        if args.self_check:
            again = scratch / f"job-{k}-again"
            shutil.rmtree(again, ignore_errors=True)
            run(program, [a.replace("{out}", str(again)) for a in argv])
            job = Job(job.name, job.command, produced, None if job.files is None else {v: v for v in job.files.values()},
                      job.only_rows)
            differences = compare(job, again)
        else:
            differences = compare(job, produced)
        print(f"{'same' if not differences else 'DIFFERENT'}: {job.name}")
        for d in differences:
            print(f"    {d}")
        failed += bool(differences)
    if not args.keep:
        shutil.rmtree(scratch, ignore_errors=True)
    print(f"{len(jobs) - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
