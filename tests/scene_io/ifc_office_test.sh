#!/usr/bin/env bash
# `portico scene import` of a generated 100-room IFC4 office
# (python/portico_ifc/tools/make_office_ifc.py: 2 storeys of 25 rooms each
# side of a corridor, a door per room, an entrance, a window every fifth room,
# a stair opening in the upper floor slab): a cell per room and corridor, a
# portal through every door and window, and the two corridors joined through
# the stair opening only. Counts, not timings (docs/importing-buildings.md,
# "Costs", has those). Usage: ifc_office_test.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$1"; src="$2"
python="${PORTICO_PYTHON:-$src/.venv/bin/python3}"
[ -x "$python" ] || { echo "$python: no python3 with IfcOpenShell (run deploy/install-deps.sh, or set PORTICO_PYTHON)"; exit 1; }
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT

PYTHONPATH="$src/python" "$python" -m portico_ifc.tools.make_office_ifc --storeys 2 --rooms-per-side 25 "$work/office.ifc"
"$bin/portico" scene import "$work/office.ifc" "$work/store" > "$work/import.txt"
"$bin/portico" scene info --json "$work/store" > "$work/info.json"
# The same conversion once more, kept: building.json names the portals' cells.
PYTHONPATH="$src/python" "$python" -m portico_ifc "$work/office.ifc" "$work/converted" > /dev/null

python3 - "$work/store/conversion.json" "$work/info.json" "$work/converted/building.json" "$work/import.txt" <<'PY'
import json, sys
conversion, info, building, text = sys.argv[1:]
s = json.load(open(conversion))["summary"]
i = json.load(open(info))
b = json.load(open(building))
rooms, storeys = 100, 2
problems = []
def expect(ok, what):
    if not ok: problems.append(what)
expect(s["spaces"] == rooms + storeys, f"spaces {s['spaces']} != {rooms + storeys}")
expect(s["space_cells"] == s["spaces"], f"{s['space_cells']} space cells for {s['spaces']} box spaces")
expect(s["spaces_with_cells"] == s["spaces"], f"spaces with cells {s['spaces_with_cells']} of {s['spaces']}")
expect(s["doors"] == rooms + 1 and s["doors_with_portal"] == s["doors"],
       f"doors with a portal {s['doors_with_portal']} of {s['doors']} (expected {rooms + 1})")
expect(s["windows"] == 20 and s["windows_with_portal"] == s["windows"],
       f"windows with a portal {s['windows_with_portal']} of {s['windows']} (expected 20)")
expect(s["connected_components"] == 1, f"cell graph in {s['connected_components']} pieces")
expect(s["cameras"] == s["spaces"] and s["lights"] == s["spaces"], f"{s['cameras']} cameras, {s['lights']} lamps")
expect(i["valid"] and i["cells"] == s["cells"] and i["portals"] == s["portals"] and i["lights"] == s["lights"],
       f"store: valid {i['valid']}, {i['cells']} cells, {i['portals']} portals, {i['lights']} lights; "
       f"conversion: {s['cells']}, {s['portals']}, {s['lights']}")
expect("valid:" in open(text).read(), "import did not report a valid store")
# Partitions, floors and facades seal: a room's only portals are its door and its window.
touching_rooms = [p for p in b["portals"] if any(c.startswith("space-room-") for c in p["between"])]
expect(len(touching_rooms) == rooms + 20, f"{len(touching_rooms)} portals touch rooms (expected {rooms} doors + 20 windows)")
expect(not any(all(c.startswith("space-room-") for c in p["between"]) for p in b["portals"]), "a portal joins two rooms")
# A room touches the corridor only at its door: one portal, about the door's size.
room_portals = [p for p in b["portals"] if sorted(p["between"]) == ["space-l0-corridor", "space-room-0s07"]]
expect(len(room_portals) == 1, f"{len(room_portals)} portals between room 0S07 and the corridor")
def extent(p):
    xs = list(zip(*p["polygon"]))
    return sorted(max(c) - min(c) for c in xs)
if room_portals:
    e = extent(room_portals[0])
    expect(0.9 <= e[1] <= 1.3 and 2.1 <= e[2] <= 2.5, f"door portal {e[1]:.2f} x {e[2]:.2f} m")
# The storeys meet at the stair opening (4 m x 1.8 m) in the slab between the corridors.
stairs = [p for p in b["portals"] if sorted(p["between"]) == ["space-l0-corridor", "space-l1-corridor"]]
expect(len(stairs) == 1, f"{len(stairs)} portals between the corridors")
if stairs:
    e = extent(stairs[0])
    expect(e[0] == 0 and 1.7 <= e[1] <= 2.1 and 3.9 <= e[2] <= 4.3, f"stair portal {e[1]:.2f} x {e[2]:.2f} m")
if problems:
    print("office: " + "; ".join(problems)); sys.exit(1)
print(f"ok office: {s['cells']} cells ({s['space_cells']} spaces), {s['portals']} portals, "
      f"{s['doors_with_portal']}/{s['doors']} doors and {s['windows_with_portal']}/{s['windows']} windows with a portal, "
      f"{i['triangles']} triangles, converted in {s['seconds']} s")
PY
