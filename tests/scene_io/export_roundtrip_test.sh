#!/usr/bin/env bash
# `portico scene export STORE -o FILE.{obj,glb,gltf}` and back: importing the
# file gives a store with the same triangles (count and bounds, as an OBJ
# export of it reports them) and the same lights (count, shapes, total
# power). Two stores: the two_rooms reference scene (a quad lamp) and a
# room lit by a triangle lamp and a quad lamp from a building.json's
# "lights". Usage: export_roundtrip_test.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$1"; src="$2"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT

printf 'v 0 0 0\nv 0 0 2\nv 2 0 2\nv 2 0 0\nv 0 2 0\nv 2 2 0\nf 1 2 3 4\nf 1 4 6 5\n' > "$work/room.obj"
cat > "$work/lamps.json" <<'JSON'
{"objects": [{"obj": "room.obj", "albedo": [0.5, 0.5, 0.5]}],
 "lights": [{"triangle": [[0.2, 1.9, 0.2], [0.2, 1.9, 0.8], [0.8, 1.9, 0.2]], "radiance": [30, 20, 10]},
            {"quad": {"corner": [1, 1.9, 1], "edge1": [0.5, 0, 0], "edge2": [0, 0, 0.5]}, "radiance": [0.5, 0.5, 0.5]}],
 "camera": {"origin": [1, 1, 1.5], "target": [1, 1, 0]}}
JSON
"$bin/portico" scene import "$src/tests/scenes/two_rooms/scene.json" "$work/two_rooms" > /dev/null
"$bin/portico" scene import "$work/lamps.json" "$work/lamps" > /dev/null 2>&1

summary() {   # STORE -> "TRIANGLES triangles, bounds ..." line of an OBJ export, then the lights
  "$bin/portico" scene export "$1" -o "$1.check.obj" | sed 's/^[^:]*: //'
  python3 - "$1/scene.db" <<'PY'
import math, sqlite3, sys
rows = sqlite3.connect(sys.argv[1]).execute(
    "SELECT shape, edge1_x, edge1_y, edge1_z, edge2_x, edge2_y, edge2_z, radiance_r, radiance_g, radiance_b FROM lights")
shapes, power = {}, [0.0, 0.0, 0.0]
for shape, ax, ay, az, bx, by, bz, r, g, b in rows:
    cross = (ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx)
    area = math.sqrt(sum(c * c for c in cross)) * (0.5 if shape == "triangle" else 1.0)
    shapes[shape] = shapes.get(shape, 0) + 1
    power = [p + math.pi * area * L for p, L in zip(power, (r, g, b))]
print(f"lights {sorted(shapes.items())} power {' '.join(f'{p:.4g}' for p in power)}")
PY
}

failed=0
for store in two_rooms lamps; do
  expected="$(summary "$work/$store")"
  for format in obj glb gltf; do
    "$bin/portico" scene export "$work/$store" -o "$work/$store.$format" > /dev/null
    "$bin/portico" scene import "$work/$store.$format" "$work/$store-$format" > /dev/null 2>&1
    got="$(summary "$work/$store-$format")"
    if [ "$got" == "$expected" ]; then
      echo "ok: $store via .$format: $(echo "$got" | tr '\n' ';')"
    else
      echo "FAILED: $store via .$format: $(echo "$got" | tr '\n' ';') instead of $(echo "$expected" | tr '\n' ';')"
      failed=1
    fi
  done
done
# glTF extras: the cells, portals and camera of two_rooms.
python3 - "$work/two_rooms.gltf" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
cells = [n for n in d["nodes"] if "portico_cell" in n.get("extras", {})]
cameras = [n for n in d["nodes"] if "camera" in n]
portals = d["scenes"][0]["extras"]["portico_portals"]
problems = []
if len(cells) != 3: problems.append(f"{len(cells)} cell nodes instead of 3")
if len(portals) != 2: problems.append(f"{len(portals)} portals instead of 2")
if len(cameras) != 1 or d["cameras"][0]["type"] != "perspective": problems.append("no perspective camera node")
if problems: print("; ".join(problems)); sys.exit(1)
print(f"ok: two_rooms.gltf has {len(cells)} cell nodes, {len(portals)} portals, a camera")
PY
exit $failed
