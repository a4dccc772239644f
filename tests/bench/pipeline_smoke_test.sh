#!/usr/bin/env bash
# Smoke test of `portico bench pipeline` (docs/pipeline-benchmark.md): a small
# photon pass on the l-shape preset, three ways. Checks that the CSV has the
# three modes with positive numbers, that portico with 1 and 2 workers
# deposits the same photons, and that the in-core Embree tracer does the same
# work as portico (deposits within 10 %). Then, on the same store, that the
# default photon count is the paper's: 50 000 per light of the building.
# Usage: pipeline_smoke_test.sh BIN_DIR
set -euo pipefail
bin="$1"
work="$(mktemp -d /tmp/portico-bench-smoke-XXXXXX)"
trap 'rm -rf "$work"' EXIT

"$bin/portico" bench pipeline --preset l-shape --photons 20000 --memory 1GiB --store "$work/store" \
  --csv "$work/pipeline.csv" --plot "$work/pipeline.png" >"$work/out.txt" 2>&1 || {
  cat "$work/out.txt"; echo "FAIL: portico bench pipeline exited with $?"; exit 1; }
cat "$work/out.txt"
test -s "$work/pipeline.png" || { echo "FAIL: no plot"; exit 1; }

awk -F, '
  NR == 1 {
    for (i = 1; i <= NF; ++i) col[$i] = i
    if ($1 != "mode" || $2 != "photons" || $3 != "seconds" || $4 != "photons_per_s") { print "FAIL: header " $0; bad = 1 }
    next
  }
  {
    mode = $col["mode"]; seen[mode] = 1
    if (!($col["photons"] == 20000)) { print "FAIL: " mode " photons " $col["photons"]; bad = 1 }
    if (!($col["seconds"] > 0) || !($col["photons_per_s"] > 0)) { print "FAIL: " mode " has no positive time"; bad = 1 }
    if (!($col["emitted"] == 20000)) { print "FAIL: " mode " emitted " $col["emitted"]; bad = 1 }
    deposits[mode] = $col["deposits"]
  }
  END {
    split("embree-incore-2t portico-1w portico-2w", modes, " ")
    for (k in modes) if (!(modes[k] in seen)) { print "FAIL: mode " modes[k] " missing"; bad = 1 }
    if (deposits["portico-1w"] != deposits["portico-2w"]) {
      print "FAIL: portico-1w deposited " deposits["portico-1w"] ", portico-2w " deposits["portico-2w"]; bad = 1 }
    e = deposits["embree-incore-2t"]; p = deposits["portico-1w"]
    if (!(p > 0) || !(e > 0) || e < 0.9 * p || e > 1.1 * p) {
      print "FAIL: in-core deposits " e " not within 10 % of portico'"'"'s " p; bad = 1 }
    else printf "deposits: in-core %d, portico %d (%+.2f %%)\n", e, p, 100 * (e - p) / p
    exit bad
  }' "$work/pipeline.csv"

"$bin/portico" bench pipeline --preset l-shape --store "$work/store" --modes embree-incore-2t \
  --csv "$work/default.csv" >"$work/default.txt" 2>&1 || {
  cat "$work/default.txt"; echo "FAIL: portico bench pipeline (default photons) exited with $?"; exit 1; }
lights=$(sed -n 's/^scene: .* \([0-9][0-9]*\) lights,.*/\1/p' "$work/default.txt")
photons=$(awk -F, 'NR == 2 { print $2 }' "$work/default.csv")
[[ -n "$lights" && "$photons" == "$((lights * 50000))" ]] || {
  cat "$work/default.txt"; echo "FAIL: default photons $photons, not 50 000 per light of $lights"; exit 1; }
echo "default photons: $photons (50 000 per light of $lights)"
echo "PASS"
