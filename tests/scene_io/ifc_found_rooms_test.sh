#!/usr/bin/env bash
# IFC models without usable IfcSpace (docs/importing-buildings.md, "Models
# without spaces"): `portico scene import model.ifc STORE` converts their
# geometry only and finds the rooms in it. IfcOpenHouse (no IfcSpace) and
# Revit's CPM house (no IfcSpace) become valid stores with a region per room,
# a camera named "room N" and a ceiling panel in each; room 1's view renders
# lit, every photon accounted for; the rooms' air is in conversion.json. A
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
  python3 - "$store.png" <<'PY'
import sys, zlib, struct
data = open(sys.argv[1], "rb").read()
chunks, i = [], 8
while i < len(data):
    n = struct.unpack(">I", data[i:i + 4])[0]
    if data[i + 4:i + 8] == b"IDAT": chunks.append(data[i + 8:i + 8 + n])
    i += 12 + n
raw = zlib.decompress(b"".join(chunks))
mean = sum(raw) / len(raw)
if mean < 8: print(f"{sys.argv[1]}: black (mean byte {mean:.1f})"); sys.exit(1)
print(f"ok {sys.argv[1]}: mean byte {mean:.1f}")
PY
}

# IfcOpenHouse: one room; the inside of its 2 m deep footing block is no room.
check IfcOpenHouse_IFC4.ifc 1
check Revit2022-CPM.ifc 4

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
