#!/usr/bin/env bash
# IFC windows' glass and the site (docs/importing-buildings.md, "Windows
# and glass"): a one-room IFC with a glazed window (glass style
# Transparency 0.9; python/portico_ifc/tools/make_glazed_room_ifc.py)
# converts to a building.json whose window is one thin glass pane of
# transmittance 0.9, 1 mm inside the opening in the room's cell, and whose
# "site" holds the IfcSite's latitude and longitude and the true north's
# azimuth. Imported with --lights none and rendered under a uniform sky
# (the window is the room's only light), the room is darker glazed than
# with --no-glazing by about what a pane passes of diffuse light, and every
# photon is accounted for. Usage: ifc_glazing_test.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$1"; src="$2"
python="${PORTICO_PYTHON:-$src/.venv/bin/python3}"
[ -x "$python" ] || { echo "$python: no python3 with IfcOpenShell (run deploy/install-deps.sh, or set PORTICO_PYTHON)"; exit 1; }
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT

# True north 30 degrees west of the plan's +y: (x, y) = (-sin 30, cos 30).
PYTHONPATH="$src/python" "$python" -m portico_ifc.tools.make_glazed_room_ifc --transparency 0.9 \
    --true-north=-0.5,0.8660254 "$work/room.ifc" > /dev/null
PYTHONPATH="$src/python" "$python" -m portico_ifc --lights none "$work/room.ifc" "$work/converted" > /dev/null

python3 - "$work/converted/building.json" "$work/converted/conversion.json" <<'PY'
import json, math, sys
b = json.load(open(sys.argv[1]))
s = json.load(open(sys.argv[2]))["summary"]
problems = []
def expect(ok, what):
    if not ok: problems.append(what)
expect(s["windows_glazed"] == 1 and s["windows_at_opening"] == 1 and s["glass_objects"] == 1,
       f"glazed windows {s['windows_glazed']}, at an opening {s['windows_at_opening']}, glass objects {s['glass_objects']}")
glass = [o for o in b["objects"] if "glass" in o]
expect(len(glass) == 1, f"{len(glass)} glass objects")
if glass:
    g = glass[0]
    expect(g["glass"]["transmittance"] == [0.9, 0.9, 0.9] and g["glass"]["ior"] == 1.5 and "albedo" not in g,
           f"glass {g}")
    expect(g["cell"] == "space-room", f"the pane lies in cell {g['cell']}")
    points = [[float(x) for x in line.split()[1:]] for line in open(sys.argv[1].rsplit("/", 1)[0] + "/" + g["obj"])
              if line.startswith("v ")]
    # The window (1.2 m x 1.2 m, sill 0.9 m) is in the south wall (IFC -y: portico +z).
    openings = [p for p in b["portals"] if "space-room" in p["between"] and
                any(c.startswith("outside") for c in p["between"])]
    expect(len(openings) == 1, f"{len(openings)} openings from the room to the outdoors")
    if openings:
        plane = openings[0]["polygon"][0][2]
        zs = {round(p[2], 6) for p in points}
        expect(zs == {round(plane - 0.001, 6)}, f"pane at z {zs}, the opening at {plane}")
        xs, ys = [p[0] for p in points], [p[1] for p in points]
        expect(abs(max(xs) - min(xs) - 1.2) < 1e-6 and abs(max(ys) - min(ys) - 1.2) < 1e-6 and
               abs(min(ys) - 0.9) < 1e-6, f"pane {min(xs)}..{max(xs)} x {min(ys)}..{max(ys)}")
expected = {"latitude": 49 + 6 / 60 + 1.566 / 3600, "longitude": 8 + 26 / 60 + 11.5404 / 3600,
            "north_azimuth": 180 + 30}   # north is the plan's (-0.5, 0.866): portico (-0.5, 0, -0.866)
site = b.get("site")
expect(site is not None and set(site) == set(expected) and
       all(abs(site[k] - v) < 1e-5 for k, v in expected.items()), f"site {site}, expected {expected}")
if problems:
    print("conversion: " + "; ".join(problems)); sys.exit(1)
print(f"ok conversion: pane {glass[0]['glass']}, site {site}")
PY

"$bin/portico" scene import --lights none "$work/room.ifc" "$work/glazed" > /dev/null 2>&1
"$bin/portico" scene import --lights none --no-glazing "$work/room.ifc" "$work/open" > /dev/null 2>&1
for kind in glazed open; do
  "$bin/portico" render "$work/$kind" -o "$work/$kind.exr" --sky uniform:1,1,1 --photons 40000 --spp 8 \
      --width 64 --height 48 --workers 2 > /dev/null 2>&1
done
"$bin/portico-compare" "$work/glazed.exr" "$work/open.exr" --json > "$work/compare.json" || true
python3 - "$work/glazed/conversion.json" "$work/open/conversion.json" "$work/glazed.exr.json" "$work/compare.json" <<'PY'
import json, sys
glazed, opened, render, compare = (json.load(open(p)) for p in sys.argv[1:])
problems = []
def expect(ok, what):
    if not ok: problems.append(what)
expect(glazed["summary"]["windows_glazed"] == 1, f"scene import: {glazed['summary']['windows_glazed']} glazed windows")
expect(opened["summary"]["windows_glazed"] == 0 and not opened["summary"]["glazing"],
       f"scene import --no-glazing: {opened['summary']['windows_glazed']} glazed windows")
p = render["photons"]
expect(p["emitted"] > 0 and p["absorbed"] + p["escaped"] == p["emitted"], f"photons unaccounted: {p}")
ratio = compare["image_mean"] / compare["reference_mean"]
# A pane of transmittance 0.9 passes 0.9 (1 - R') of the light: R' = 2R / (1 + R), 0.077 at normal
# incidence, about 0.17 for diffuse light (ior 1.5); the room's interreflections and the window's
# own reflection of the room keep the ratio above 0.9 x 0.83.
expect(0.68 <= ratio <= 0.88, f"glazed / open image mean {ratio:.3f}, expected about 0.75-0.85")
if problems:
    print("render: " + "; ".join(problems)); sys.exit(1)
print(f"ok render: glazed / open image mean {ratio:.3f} ({compare['image_mean']:.4f} / {compare['reference_mean']:.4f}), "
      f"photons {p}")
PY
