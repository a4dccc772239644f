#!/usr/bin/env bash
# `portico bench analyze` with short ladders (a smoke test, not a timing):
# Radiance and portico side by side on cornell_closed (one CSV row per rung,
# errors that make sense and fall along each ladder, a plot), then the scale
# run on the small demo building (one row: its rooms, sensors, seconds).
# Exit 77 (ctest: skipped) where Radiance is not installed.
set -euo pipefail
bin="$1"; src="$2"
python3 -c "import sys; sys.path.insert(0, '$src/tests/tools'); import radiance_tools as rt; sys.exit(0 if rt.find_radiance('$src') else 77)" || {
  echo "SKIPPED: Radiance is not installed (deploy/install-deps.sh puts pyradiance into .venv)"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$bin/portico" bench analyze "$src/tests/scenes/cornell_closed" \
  --radiance-settings "-ab 1 -ad 32 -aa 0;-ab 4 -ad 512 -aa 0" \
  --portico-settings "--photons 20000 --spp 1 --gather 1;--photons 100000 --spp 16 --gather 4" \
  --portico-reference "--photons 200000 --spp 64 --gather 4" \
  --csv "$work/analyze.csv" --plot "$work/analyze.png" | tee "$work/out.txt"
[ "$(wc -l < "$work/analyze.csv")" -eq 5 ] || { echo "expected a header and 4 rows"; exit 1; }
python3 - "$work/analyze.csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
for r in rows:
    assert float(r["seconds"]) > 0, r
    assert 0 <= float(r["rms_rel_err"]) < 1 and 0 <= float(r["rms_rel_err_vs_other_reference"]) < 1, r
for program in ("radiance", "portico"):
    ladder = [float(r["rms_rel_err"]) for r in rows if r["program"] == program]
    assert len(ladder) == 2 and ladder[1] < ladder[0], (program, ladder)
PY
[ -s "$work/analyze.png" ] || { echo "no plot"; exit 1; }
grep -q "| 5.00 % |" "$work/out.txt"
"$bin/portico" bench analyze --buildings demo --stores "$work/stores" --analyze-args "--photons 50000 --spp 1" \
  --csv "$work/scale.csv" | tee "$work/scale.txt"
python3 - "$work/scale.csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert len(rows) == 1 and rows[0]["building"] == "demo", rows
assert int(rows[0]["rooms"]) > 0 and int(rows[0]["sensors"]) >= int(rows[0]["rooms"]) and float(rows[0]["seconds"]) > 0, rows
PY
# Neither a scene nor buildings: refused.
if "$bin/portico" bench analyze 2> "$work/err.txt"; then echo "accepted no scene"; exit 1; fi
grep -q "SCENE_DIR" "$work/err.txt"
echo "bench analyze smoke: ok"
