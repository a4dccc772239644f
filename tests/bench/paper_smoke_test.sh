#!/usr/bin/env bash
# Smoke test of `portico bench paper` (docs/paper-benchmark.md): its hidden
# --smoke scale (the l-shape building only, a point or two per sweep, ~100
# photons per light) runs every experiment of the paper's section 6 through
# the real pipeline. Checks that every experiment wrote its CSV (with rows)
# and its PNG, that summary.json has every experiment, that no measurement
# failed, and that `--accel auto` is either measured or marked unavailable.
# Usage: paper_smoke_test.sh BIN_DIR
set -euo pipefail
bin="$1"
work="$(mktemp -d /tmp/portico-bench-paper-smoke-XXXXXX)"
trap 'rm -rf "$work"' EXIT

"$bin/portico" bench paper --smoke --out "$work/out" >"$work/out.txt" 2>&1 || {
  status=$?; cat "$work/out.txt"; echo "FAIL: portico bench paper --smoke exited with $status"; exit 1; }
cat "$work/out.txt"

bad=0
for name in fig4_5_grid_resolution fig6_hgrid_init table3_kd_depth fig7_8_kd_heuristics \
            fig9_best_topological table4_uniform_cells fig11_topological_vs_uniform auto_vs_fixed; do
  csv="$work/out/$name.csv" png="$work/out/$name.png"
  if [ ! -s "$csv" ] || [ "$(wc -l <"$csv")" -lt 2 ]; then echo "FAIL: $name.csv missing or without rows"; bad=1; fi
  if [ ! -s "$png" ] || [ "$(head -c 4 "$png" | tail -c 3)" != "PNG" ]; then echo "FAIL: $name.png missing or not a PNG"; bad=1; fi
  grep -q "\"$name\"" "$work/out/summary.json" || { echo "FAIL: summary.json lacks $name"; bad=1; }
  if grep -q ",failed," "$csv"; then echo "FAIL: a measurement of $name failed:"; grep ",failed," "$csv"; bad=1; fi
done
grep -Eq '^l-shape,[0-9]+,auto,auto,[^,]*,(ok|unavailable),' "$work/out/auto_vs_fixed.csv" || {
  echo "FAIL: auto_vs_fixed.csv has no auto row marked ok or unavailable"; bad=1; }
[ "$bad" = 0 ] || exit 1
echo "PASS"
