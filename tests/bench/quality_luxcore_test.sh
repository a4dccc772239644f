#!/usr/bin/env bash
# `portico bench quality --luxcore` on cornell_closed: LuxCoreRender's rows
# beside portico's, scored against the same reference, their error falling
# with the samples; the view the peers render lines up with portico's camera
# (the light's edges fall in the same pixels: its worst block stays small).
# Skipped (exit 77) where pyluxcore is not installed (deploy/install-deps.sh installs it).
# The view writer refuses a store it would render otherwise than portico
# (glass), naming the material.
set -euo pipefail
bin="$1"
src="$2"
python="${PORTICO_PYTHON:-$src/.venv/bin/python3}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$bin/portico" scene import "$src/tests/scenes/daylight_window/scene.json" "$work/glass" > /dev/null
if PYTHONPATH="$src/python" "$python" -m portico_peers view "$work/glass" "$work/glass-view" --portico "$bin/portico" \
    2> "$work/err.txt"; then
  echo "the view writer accepted a store with glass"; exit 1
fi
grep -q "is glass" "$work/err.txt" || { cat "$work/err.txt"; exit 1; }

if ! "$python" -c "import pyluxcore" > /dev/null 2>&1; then
  echo "skipped: no pyluxcore in $python (deploy/install-deps.sh installs it)"; exit 77
fi
"$bin/portico" bench quality "$src/tests/scenes/cornell_closed" --settings "--spp 2 --gather 2 --photons 50000" \
  --luxcore --luxcore-photongi 0 --luxcore-spp 2,32 --csv "$work/q.csv" --plot "$work/q.png" | tee "$work/out.txt"
python3 - "$work/q.csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert [r["settings"] for r in rows] == ["--spp 2 --gather 2 --photons 50000", "luxcore path --spp 2",
                                         "luxcore path --spp 32"], rows
for r in rows:
    assert float(r["seconds"]) > 0, r
    for k in ("mean_err", "worst_block", "rel_rmse_blocks"):
        assert 0 <= float(r[k]) < 1, r
# 16 times the samples: LuxCore's block RMSE falls (by about 4 times), and
# at 32 samples no block (the light's edges included) is 15 % off.
assert float(rows[2]["rel_rmse_blocks"]) < 0.5 * float(rows[1]["rel_rmse_blocks"]), rows
assert float(rows[2]["worst_block"]) < 0.15, rows
assert float(rows[2]["mean_err"]) < 0.01, rows
PY
[ -s "$work/q.png" ] || { echo "no plot"; exit 1; }
echo "bench quality --luxcore: ok"
