#!/usr/bin/env bash
# Smoke test of `portico bench coordinator` (docs/coordinator-benchmark.md):
# the real coordinator and 4 simulated workers through a small job on the
# soda-hall preset (2 700 lights: ~500 leases, a steady window of ~0.5 s). Checks the CSV's figures are there and sane, and that the job's
# accounting balanced (every photon, deposit and camera ray the simulated
# workers reported is what the coordinator applied, no Result refused).
# Then that the check can fail: simulated Results that do not add up are
# refused by the coordinator, and the bench says so and exits non-zero.
# Usage: coordinator_smoke_test.sh BIN_DIR
set -euo pipefail
bin="$1"
work="$(mktemp -d /tmp/portico-bench-coordinator-smoke-XXXXXX)"
trap 'rm -rf "$work"' EXIT

"$bin/portico" bench coordinator --workers 4 --preset soda-hall --store "$work/store" --photons-per-light 1000 \
  --lease-rays 500 \
  --csv "$work/coordinator.csv" --plot "$work/coordinator.png" >"$work/out.txt" 2>&1 || {
  cat "$work/out.txt"; echo "FAIL: portico bench coordinator exited with $?"; exit 1; }
cat "$work/out.txt"
test -s "$work/coordinator.png" || { echo "FAIL: no plot"; exit 1; }

awk -F, '
  NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next }
  {
    rows++
    if ($col["workers"] != 4) { print "FAIL: workers " $col["workers"]; bad = 1 }
    if (!($col["leases"] > 10)) { print "FAIL: leases " $col["leases"]; bad = 1 }
    if (!($col["window_leases"] > 0 && $col["window_s"] > 0 && $col["leases_per_s"] > 0)) {
      print "FAIL: no steady window: " $0; bad = 1 }
    rate = $col["window_leases"] / $col["window_s"]
    if (rate < 0.995 * $col["leases_per_s"] || rate > 1.005 * $col["leases_per_s"]) {
      print "FAIL: leases_per_s " $col["leases_per_s"] " is not window_leases / window_s = " rate; bad = 1 }
    if (!($col["coordinator_cpu_ms_per_lease"] > 0 && $col["coordinator_cpu_ms_per_lease"] < 1000)) {
      print "FAIL: coordinator CPU per lease " $col["coordinator_cpu_ms_per_lease"] " ms"; bad = 1 }
    # One thread: at most 1, give or take the 10 ms clock ticks /proc counts CPU in.
    if (!($col["coordinator_busy"] > 0 && $col["coordinator_busy"] <= 1.2)) {
      print "FAIL: coordinator busy " $col["coordinator_busy"] " (one thread: at most 1)"; bad = 1 }
    if (!($col["window_s"] >= 0.2)) { print "FAIL: a steady window of " $col["window_s"] " s is too short to measure"; bad = 1 }
    if (!($col["latency_median_ms"] > 0 && $col["latency_p99_ms"] >= $col["latency_median_ms"])) {
      print "FAIL: latency median " $col["latency_median_ms"] " p99 " $col["latency_p99_ms"]; bad = 1 }
    if (!($col["bytes_in_per_lease"] > 0 && $col["bytes_out_per_lease"] > 0)) { print "FAIL: no bytes"; bad = 1 }
    if ($col["emitted"] != $col["photons"] || !($col["photons"] > 0)) {
      print "FAIL: emitted " $col["emitted"] " of " $col["photons"]; bad = 1 }
    if (!($col["deposit_records"] > 0) || !($col["photons_handed_on"] > 0) || !($col["camera_rays"] > 0)) {
      print "FAIL: the Results carried no deposits, crossings or camera rays: " $0; bad = 1 }
    if ($col["results_refused"] != 0 || $col["errors"] != 0 || $col["balanced"] != 1) {
      print "FAIL: accounting did not balance: " $0; bad = 1 }
  }
  END { if (rows != 1) { print "FAIL: " rows " rows"; bad = 1 } exit bad }' "$work/coordinator.csv"

# Results that do not add up: refused, the job fails, the bench says so.
if "$bin/portico" bench coordinator --workers 2 --preset soda-hall --store "$work/store" \
  --photons-per-light 100 --miscount --timeout 120 --csv "$work/miscount.csv" >"$work/miscount.txt" 2>&1; then
  cat "$work/miscount.txt"; echo "FAIL: the bench passed Results that do not add up"; exit 1
fi
grep -q "NOT BALANCED" "$work/miscount.txt" || { cat "$work/miscount.txt"; echo "FAIL: no NOT BALANCED line"; exit 1; }
awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next }
  { if ($col["balanced"] != 0 || !($col["results_refused"] > 0)) { print "FAIL: miscount row " $0; exit 1 } }' \
  "$work/miscount.csv"
grep "NOT BALANCED" "$work/miscount.txt" | head -3
echo "PASS"
