#!/usr/bin/env bash
# Runs one libFuzzer harness until it has executed RUNS inputs or SECONDS have passed, starting it
# again from its grown corpus after each finding, and prints the total. libFuzzer stops at the first
# crash, and the libhdf5 paths meet faults inside libhdf5 every few thousand inputs (docs/fuzzing.md,
# "Findings"). libFuzzer's fork mode (-fork=1 -ignore_crashes=1) also goes on, but starts a process
# per job that first replays its share of the corpus; here one process runs until it finds something.
# Each finding is written to FINDINGS, named by the run it came from; triage them all (docs/fuzzing.md).
#
# usage: fuzz_until.sh FUZZER CORPUS FINDINGS RUNS SECONDS [libFuzzer options...]
# e.g.   nice -n 19 tests/fuzz/fuzz_until.sh build-fuzz/fuzz/fuzz_hdf5 corpus/hdf5 findings/hdf5 10000000 3600 \
#            -timeout=10 -rss_limit_mb=2048
set -uo pipefail
fuzzer="$(realpath "$1")" corpus="$2" findings="$3" runs="$4" seconds="$5"
shift 5
mkdir -p "$findings"
stuck_after=${FUZZ_UNTIL_STUCK_AFTER:-30}
# A harness built without AddressSanitizer can meet a fault that has already damaged malloc's own
# data; libFuzzer's crash handler then allocates, glibc aborts, and the handler waits forever on a
# lock it holds (seen on fuzz_hdf5: a global-heap copy in H5HG_read, then "malloc(): invalid size"),
# where -timeout no longer fires. Such a process uses no CPU at all: one that has had none for
# $stuck_after seconds is killed, and its run counts as a finding. Beside the harness, so that the
# loop goes on as soon as the harness ends.
watch_for_stuck() {
  local pid="$1" log="$2" ticks=-1 still=0 now
  while sleep 5; do
    now=$(sed 's/^.*) //' "/proc/$pid/stat" 2>/dev/null | cut -d' ' -f12,13 | tr ' ' +)
    [ -n "$now" ] || return
    now=$((now))
    if [ "$now" -eq "$ticks" ]; then still=$((still + 5)); else still=0 ticks=$now; fi
    if [ "$still" -ge "$stuck_after" ]; then
      # On a line of its own: the harness may have stopped in the middle of one.
      printf '\nfuzz_until.sh: stuck without CPU for %s s (a crash handler waiting on itself?), killed\n' "$still" >>"$log"
      kill -KILL "$pid" 2>/dev/null
      return
    fi
  done
}

start=$(date +%s)
total=0
segment=0
while [ "$total" -lt "$runs" ]; do
  left=$((seconds - ($(date +%s) - start)))
  [ "$left" -le 0 ] && break
  segment=$((segment + 1))
  log="$findings/run-$segment.log"
  # Artifacts go to FINDINGS with the run's number, so that no finding overwrites another.
  "$fuzzer" "$corpus" -runs=$((runs - total)) -max_total_time="$left" -print_final_stats=1 \
      -artifact_prefix="$findings/run-$segment-" "$@" >"$log" 2>&1 &
  pid=$!
  watch_for_stuck "$pid" "$log" >/dev/null 2>&1 &
  watcher=$!
  wait "$pid" 2>/dev/null
  kill "$watcher" 2>/dev/null
  wait "$watcher" 2>/dev/null
  stuck=$(sed -n 's/^fuzz_until\.sh: //p' "$log" | tail -1)
  executed=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  # A killed run printed no totals: count the inputs of its last status line ("#N ..."), fewer than it ran.
  [ -z "$executed" ] && executed=$(sed -n 's/^#\([0-9][0-9]*\)[[:space:]].*/\1/p' "$log" | tail -1)
  total=$((total + ${executed:-0}))
  # UBSan reports undefined behaviour as "file:line:col: runtime error: ...", with no ==ERROR line.
  finding=$(grep -m1 -E '^==[0-9]+== ?ERROR|: runtime error: ' "$log" || true)
  [ -n "$stuck" ] && finding="${finding:+$finding; }$stuck"
  echo "run $segment: ${executed:-0} inputs, total $total after $(($(date +%s) - start)) s${finding:+; $finding}"
  # A run that ended without a finding and short of its inputs ran out of time; one that executed
  # nothing cannot start (a broken build or corpus): stop rather than loop.
  [ -z "$finding" ] && break
  [ "${executed:-0}" -eq 0 ] && break
done
echo "total: $total inputs in $(($(date +%s) - start)) s"
