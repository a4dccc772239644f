#!/usr/bin/env bash
# `portico bench quality --mitsuba` on cornell_closed: Mitsuba 3's rows beside
# portico's, scored the same way, their error falling with the samples.
# Skipped (exit 77) where Mitsuba is not installed (deploy/install-deps.sh --peers).
# The ladder's module refuses a scene it would render otherwise than portico,
# naming it, with or without Mitsuba.
set -euo pipefail
bin="$1"
src="$2"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
if PYTHONPATH="$src/python" python3 -m portico_mitsuba "$src/tests/scenes/daylight_window" "$work/x" 2> "$work/err.txt"; then
  echo "the ladder accepted a scene lit by a sky"; exit 1
fi
grep -q "daylight_window/scene.json: lit by render_args.txt" "$work/err.txt" || { cat "$work/err.txt"; exit 1; }

python="${MITSUBA_VENV:-$HOME/.local/share/portico/mitsuba-venv}/bin/python"
if ! "$python" -c "import mitsuba, drjit" 2> /dev/null; then
  echo "skipped: no Mitsuba 3 in $python (deploy/install-deps.sh --peers)"; exit 77
fi
"$bin/portico" bench quality "$src/tests/scenes/cornell_closed" --settings "--spp 2 --gather 2 --photons 50000" \
  --mitsuba --mitsuba-spp 4,64 --csv "$work/q.csv" --plot "$work/q.png" | tee "$work/out.txt"
python3 - "$work/q.csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert [r["settings"] for r in rows] == ["--spp 2 --gather 2 --photons 50000", "mitsuba path --spp 4",
                                         "mitsuba path --spp 64"], rows
for r in rows:
    assert float(r["seconds"]) > 0, r
    for k in ("mean_err", "worst_block", "rel_rmse_blocks"):
        assert 0 <= float(r[k]) < 1, r
# 16 times the samples: Mitsuba's block RMSE falls (by about 4 times).
assert float(rows[2]["rel_rmse_blocks"]) < 0.5 * float(rows[1]["rel_rmse_blocks"]), rows
PY
[ -s "$work/q.png" ] || { echo "no plot"; exit 1; }
echo "bench quality --mitsuba: ok"
