#!/usr/bin/env bash
# `portico bench quality` on cornell_closed with a short ladder (a smoke test,
# not a timing): one CSV row per setting, errors that make sense, a plot.
set -euo pipefail
bin="$1"
scenes="$2"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$bin/portico" bench quality "$scenes/cornell_closed" --settings "--spp 1 --gather 1 --photons 20000;--spp 4 --gather 2 --photons 50000" \
  --csv "$work/quality.csv" --plot "$work/quality.png" | tee "$work/out.txt"
[ "$(wc -l < "$work/quality.csv")" -eq 3 ] || { echo "expected a header and 2 rows"; exit 1; }
head -1 "$work/quality.csv" | grep -qx "settings,seconds,mean_err,worst_block,rel_rmse_blocks,rel_mse,flip"
# Every row: seconds > 0, errors in [0, 1); the longer render's block RMSE and relative MSE are lower;
# FLIP in (0, 1) where flip-evaluator is installed (the sources' .venv), else empty.
python3 - "$work/quality.csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
for r in rows:
    assert float(r["seconds"]) > 0, r
    for k in ("mean_err", "worst_block", "rel_rmse_blocks"):
        assert 0 <= float(r[k]) < 1, r
    assert 0 < float(r["rel_mse"]) < 1, r
    assert r["flip"] == "" or 0 < float(r["flip"]) < 1, r
assert float(rows[1]["rel_rmse_blocks"]) < float(rows[0]["rel_rmse_blocks"]), rows
assert float(rows[1]["rel_mse"]) < float(rows[0]["rel_mse"]), rows
if rows[0]["flip"]:
    assert float(rows[1]["flip"]) < float(rows[0]["flip"]), rows
PY
[ -s "$work/quality.png" ] || { echo "no plot"; exit 1; }
# A folder without reference.exr is refused, naming it.
mkdir "$work/noref" && cp "$scenes/cornell_closed/scene.json" "$work/noref/"
if "$bin/portico" bench quality "$work/noref" 2> "$work/err.txt"; then echo "accepted a scene without reference"; exit 1; fi
grep -q "no reference.exr" "$work/err.txt"
# --mitsuba without Mitsuba is refused, naming the interpreter looked for, before a row is printed.
if "$bin/portico" bench quality "$scenes/cornell_closed" --settings "--spp 1 --photons 1000" --mitsuba \
    --mitsuba-python "$work/no-such-venv/bin/python" > "$work/out2.txt" 2> "$work/err2.txt"; then
  echo "--mitsuba ran without Mitsuba"; exit 1
fi
grep -q "no Mitsuba 3 in $work/no-such-venv/bin/python" "$work/err2.txt" || { cat "$work/err2.txt"; exit 1; }
echo "bench quality smoke: ok"
