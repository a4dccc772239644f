#!/usr/bin/env bash
# Runs every portico fuzz target from a fresh seed corpus and prints one line
# per target: executions, seconds, crashes (docs/fuzzing.md).
#
#   tests/fuzz/run_fuzzers.sh BUILD_FUZZ STORE [RUNS] [OUT]
#
# BUILD_FUZZ: a build tree configured with -DPORTICO_FUZZ=ON (target portico_fuzzers built).
# STORE: a demo scene store (`portico scene generate --preset demo STORE`), for the seeds.
# RUNS: executions per target (default 1000000). OUT: work directory (default BUILD_FUZZ/fuzz-runs).
set -euo pipefail

build=${1:?usage: run_fuzzers.sh BUILD_FUZZ STORE [RUNS] [OUT]}
store=${2:?usage: run_fuzzers.sh BUILD_FUZZ STORE [RUNS] [OUT]}
runs=${3:-1000000}
out=${4:-$build/fuzz-runs}

rm -rf "$out"
mkdir -p "$out"
"$build/bin/portico-fuzz-seeds" "$out/seeds" "$store" > /dev/null

# max_len: room to grow past the largest seed of each target. malloc_limit:
# an input of a few KiB that makes a decoder allocate more than this is a bug.
declare -A max_len=([envelope]=8192 [ray_batch]=4096 [photon_records]=4096 [cell_file]=8192 [scene_db]=16384)
status=0
printf '%-16s %10s %8s %8s\n' target executions seconds crashes
for target in ${TARGETS:-envelope ray_batch photon_records cell_file scene_db}; do   # TARGETS="..." runs some
  corpus="$out/corpus/$target"
  mkdir -p "$corpus" "$out/artifacts"
  cp "$out/seeds/$target"/* "$corpus/"
  log="$out/$target.log"
  started=$(date +%s)
  set +e
  "$build/bin/fuzz_$target" -runs="$runs" -max_len="${max_len[$target]}" -malloc_limit_mb=128 -timeout=10 \
    -print_final_stats=1 -artifact_prefix="$out/artifacts/$target-" "$corpus" > "$log" 2>&1
  code=$?
  set -e
  seconds=$(( $(date +%s) - started ))
  executions=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  crashes=$(find "$out/artifacts" -name "$target-*" | wc -l)
  printf '%-16s %10s %8s %8s\n' "$target" "${executions:-?}" "$seconds" "$crashes"
  if [ "$code" -ne 0 ] || [ "$crashes" -ne 0 ]; then
    status=1
    echo "  fuzz_$target exited $code; see $log and $out/artifacts/" >&2
  fi
done
exit $status
