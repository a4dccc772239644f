#!/usr/bin/env bash
# IFC models without usable IfcSpace (docs/importing-buildings.md, "Models
# without spaces"): `portico scene import model.ifc STORE` converts their
# geometry only and finds the rooms in it. IfcOpenHouse (no IfcSpace) and
# Revit's CPM house (no IfcSpace) become valid stores with a region per room,
# a camera named "room N" and a ceiling panel in each; room 1's view renders
# lit, every photon accounted for; the rooms' air is in conversion.json.
# With a light fixture, the room gets the fixture's lamp instead. A
# model that is not a building (four walls and a floor, no roof) stops with
# the room finder's one line and leaves no store behind.
# (The outdoors is open: light leaves through windows and CPM's unfilled voids.)
# Usage: ifc_found_rooms_test.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$1"; src="$2"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT

check() {   # model rooms
  local model="$1" rooms="$2"
  local store="$work/$(basename "$model" .ifc)"
  "$bin/portico" scene import "$src/tests/scenes/ifc/corpus/$model" "$store" > "$store.info.txt" 2> "$store.err.txt"
  "$bin/portico" render "$store" -o "$store.png" --photons 20000 --spp 2 --gather 4 --width 64 --height 48 \
      --workers 2 > /dev/null 2>&1
  python3 - "$store/conversion.json" "$store.png.json" "$store.info.txt" "$store.err.txt" "$rooms" "$model" <<'PY'
import json, sys
conversion, render, info, err, rooms, model = sys.argv[1:]
c = json.load(open(conversion)); s = c["summary"]; r = json.load(open(render))
text, errors = open(info).read(), open(err).read()
problems = []
def expect(ok, what):
    if not ok: problems.append(what)
found = c.get("found_rooms", [])
expect(c.get("find_rooms", {}).get("reason") == "no IfcSpace with geometry", f"find_rooms {c.get('find_rooms')}")
expect(len(found) == int(rooms) and s["rooms_found"] == len(found), f"{len(found)} rooms found, expected {rooms}")
expect(f"found {len(found)} rooms:" in errors, "the import did not say what it found: " + errors[-300:])
expect("valid:" in text, "store not valid: " + text[-300:])
names = [f"room {k}" for k in range(1, len(found) + 1)]
expect([room["name"] for room in found] == names, f"rooms named {[room['name'] for room in found]}")
expect(f"cameras ({len(found) + 1}, --camera NAME; the first is the default): room 1" in text, "cameras: " + text)
expect(s["lights"] == len(found) and s["light_source"] == "room panels", f"lamps {s['lights']} ({s['light_source']})")
for room in found:
    lo, hi = room["air_lo"], room["air_hi"]
    expect(room["floor_m2"] > 1 and len(room["samples"]) > 100, f"{room['name']}: {room['floor_m2']} m2, "
           f"{len(room['samples'])} samples")
    expect(all(lo[a] <= p[a] < hi[a] for p in room["samples"] for a in range(3)), f"{room['name']}: a sample outside its air")
p = r["photons"]
expect(p["emitted"] == 20000 and p["absorbed"] + p["escaped"] == p["emitted"], f"photons unaccounted: {p}")
expect(p["escaped"] < p["emitted"] // 20, f"{p['escaped']} photons escaped")
if problems:
    print(f"{model}: " + "; ".join(problems)); sys.exit(1)
print(f"ok {model}: {len(found)} rooms, {s['cells']} cells, {s['portals']} portals, {s['lights']} lamps; "
      f"photons escaped {p['escaped']} of {p['emitted']}")
PY
  python3 "$(dirname "$0")/png_not_black.py" "$store.png"
}

# IfcOpenHouse: one room; the inside of its 2 m deep footing block is no room.
check IfcOpenHouse_IFC4.ifc 1
check Revit2022-CPM.ifc 4

# IfcOpenHouse with a light fixture under its roof (added with IfcOpenShell's API): its lamp, no room panels.
"$src/.venv/bin/python3" - "$src/tests/scenes/ifc/corpus/IfcOpenHouse_IFC4.ifc" "$work/house-lamp.ifc" <<'PY'
import sys, numpy as np, ifcopenshell, ifcopenshell.api as api
model = ifcopenshell.open(sys.argv[1])
context = [c for c in model.by_type("IfcGeometricRepresentationContext") if c.ContextType == "Model"][0]
fixture = api.run("root.create_entity", model, ifc_class="IfcLightFixture", name="ceiling lamp")
corners = [[(x * 0.3, y * 0.3, z * 0.1) for x in (-1, 1) for y in (-1, 1) for z in (0, 1)]]   # metres (the API's)
faces = [[(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]]
api.run("geometry.assign_representation", model, product=fixture, representation=api.run(
    "geometry.add_mesh_representation", model, context=context, vertices=corners, faces=faces))
placement = np.eye(4)
placement[:3, 3] = (0.0, 2.5, 2.3)   # IFC axes: over the middle of the house, under its roof
api.run("geometry.edit_object_placement", model, product=fixture, matrix=placement)
api.run("spatial.assign_container", model, products=[fixture], relating_structure=model.by_type("IfcBuildingStorey")[0])
model.write(sys.argv[2])
PY
"$bin/portico" scene import --keep-conversion "$work/house-lamp-conv" "$work/house-lamp.ifc" "$work/house-lamp" \
    > /dev/null 2>&1
python3 - "$work/house-lamp-conv" <<'PY'
import json, sys
conversion = json.load(open(sys.argv[1] + "/conversion.json"))
s, room = conversion["summary"], conversion["found_rooms"][0]
if (s["light_fixtures"], s["lights"], s["light_source"], s["rooms_found"]) != (1, 1, "fixtures", 1):
    print(f"house with a fixture: {s}"); sys.exit(1)
lamp = [[float(x) for x in line.split()[1:]] for line in open(sys.argv[1] + "/meshes/lamp-0000.obj") if line.startswith("v ")]
centre = [sum(p[a] for p in lamp) / len(lamp) for a in range(3)]
if not all(room["air_lo"][a] < centre[a] < room["air_hi"][a] for a in range(3)):
    print(f"house with a fixture: its lamp at {centre} is not in the room's air {room['air_lo']} {room['air_hi']}"); sys.exit(1)
print("ok house with a fixture: 1 room, its fixture's lamp, no room panel")
PY

# Four walls and a floor, no roof: no rooms, one line, nothing written, in bounded time.
store="$work/walls"
if timeout 120 "$bin/portico" scene import "$src/tests/scenes/ifc/corpus/Revit2014-4walls1floorSite.ifc" "$store" \
    > /dev/null 2> "$work/walls.err"; then
  echo "four walls imported as a building"; exit 1
fi
grep -q "^portico: no rooms found in .*Revit2014-4walls1floorSite.ifc: .*use --grid N" "$work/walls.err" \
  || { echo "no one-line 'no rooms found' message:"; cat "$work/walls.err"; exit 1; }
[ ! -e "$store" ] && [ ! -e "$store.ifc-conversion" ] || { echo "a failed import left $store behind"; exit 1; }
echo "ok four walls: $(grep '^portico: no rooms' "$work/walls.err")"
