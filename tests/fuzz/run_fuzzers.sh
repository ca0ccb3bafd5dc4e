#!/usr/bin/env bash
# Runs the libFuzzer targets of a PATHD_FUZZ build for a bounded time each
# (`make fuzz`). Usage: run_fuzzers.sh BUILD_DIR SECONDS [TARGET...]
# Targets come from BUILD_DIR/fuzz_targets.txt (tests/fuzz/CMakeLists.txt);
# with no TARGET, all of them, one after the other. Each starts from its
# checked-in seed corpus (only read) plus what earlier runs found
# (BUILD_DIR/fuzz/<target>/corpus, written); a crash, leak, UB report or
# timeout leaves its input in BUILD_DIR/fuzz/<target>/artifacts/ and makes
# the script fail after the remaining targets ran. Run from the project root.
set -uo pipefail
build_dir=${1:?usage: run_fuzzers.sh BUILD_DIR SECONDS [TARGET...]}
seconds=${2:?usage: run_fuzzers.sh BUILD_DIR SECONDS [TARGET...]}
shift 2
list="$build_dir/fuzz_targets.txt"
[ -f "$list" ] || { echo "run_fuzzers: $list missing (configure with -DPATHD_FUZZ=ON)" >&2; exit 2; }

summary=()
failed=0
while read -r name exe corpus; do
  [ -n "$name" ] || continue
  if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
  work="$build_dir/fuzz/$name"
  mkdir -p "$work/corpus" "$work/artifacts"
  log="$work/last_run.log"
  echo "== $name: ${seconds}s, seeds $corpus, log $log"
  # -timeout: one input running 10 s is a hang worth reporting; the
  # readers and a plan on the 24 x 20 map take microseconds.
  # -malloc_limit_mb: no input of a few KB justifies one allocation of 64 MB;
  # one that makes it was sized by a header, not by the data (the readers
  # run with their default limit of 2^28 cells).
  "$exe" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=64 \
    -print_final_stats=1 -artifact_prefix="$work/artifacts/" \
    "$work/corpus" "$corpus" >"$log" 2>&1
  rc=$?
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1)
  if [ $rc -eq 0 ]; then
    summary+=("$name: ok, ${runs:-?} runs, ${rate:-?} exec/s, ${cov:-cov: ?}, corpus $(ls "$work/corpus" | wc -l) files")
  else
    failed=1
    summary+=("$name: FAILED (exit $rc), see $log and $work/artifacts/")
    grep -m1 -E 'ERROR: |runtime error|check failed' "$log" >&2
  fi
done <"$list"

printf '%s\n' "${summary[@]}"
exit $failed
