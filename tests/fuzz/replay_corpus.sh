#!/usr/bin/env bash
# Replays every input of a corpus once through a harness, going on past the inputs it fails on, and
# copies each of those, with its report, to FINDINGS. For the corpora grown by the harnesses built
# without AddressSanitizer (tests/fuzz/clang++-without-asan): replayed by the ASan+UBSan build, every
# input they kept is checked with the sanitizers they ran without (docs/fuzzing.md).
# libFuzzer given files runs each once and stops at the first failure; this starts it again after
# the input that failed. Prints what it replayed and what failed; exits 1 if anything failed.
#
# usage: replay_corpus.sh FUZZER FINDINGS DIR... [-- libFuzzer options...]
# e.g.   ASAN_OPTIONS=allocator_may_return_null=1:detect_leaks=0 nice -n 19 \
#            tests/fuzz/replay_corpus.sh build-fuzz/fuzz/fuzz_hdf5 replayed/hdf5 corpus/hdf5 -- -timeout=10 -rss_limit_mb=2048
set -uo pipefail
fuzzer="$(realpath "$1")" findings="$2"
shift 2
dirs=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do dirs+=("$1"); shift; done
[ $# -gt 0 ] && shift
mkdir -p "$findings"
mapfile -t files < <(find "${dirs[@]}" -maxdepth 1 -type f | sort)
declare -A index
for i in "${!files[@]}"; do index["${files[$i]}"]=$i; done
next=0 replayed=0 failed=0 attempt=0
while [ "$next" -lt "${#files[@]}" ]; do
  attempt=$((attempt + 1))
  log="$findings/replay-$attempt.log"
  "$fuzzer" -runs=1 "$@" "${files[@]:$next}" >"$log" 2>&1
  status=$?
  replayed=$((replayed + $(grep -c '^Executed ' "$log")))
  [ "$status" -eq 0 ] && break
  last=$(sed -n 's/^Running: //p' "$log" | tail -1)
  if [ -z "$last" ] || [ -z "${index[$last]+x}" ]; then
    echo "replay_corpus.sh: the harness failed before any input (see $log)" >&2
    exit 2
  fi
  failed=$((failed + 1))
  cp "$last" "$findings/"
  mv "$log" "$findings/$(basename "$last").log"
  echo "failed: $last ($(grep -m1 -E '^==[0-9]+== ?ERROR|: runtime error: ' "$findings/$(basename "$last").log" | cut -c1-160))"
  next=$((index[$last] + 1))
done
echo "replayed ${#files[@]} inputs ($replayed completed), $failed failed"
[ "$failed" -eq 0 ]
