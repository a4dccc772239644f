#!/usr/bin/env bash
# `portico scene import model.ifc`: both sample models (tests/scenes/ifc)
# become multi-cell stores, connected across storeys, with a lamp and a
# camera per space, a portal through every door and window and a glass
# pane in every window that has glass; with the outdoors closed, one
# space's camera of each renders non-black and (nearly) without escaped
# photons. Usage: ifc_import_test.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$1"; src="$2"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT

check() {   # model camera spaces min_doors_with_portal min_windows_with_portal glazed_windows
  local model="$1" camera="$2" spaces="$3" doors="$4" windows="$5" glazed="$6"
  local store="$work/$(basename "$model" .ifc)"
  "$bin/portico" scene import --outdoors closed --camera "$camera" "$src/tests/scenes/ifc/$model" "$store" \
      > "$store.import.txt"
  "$bin/portico" render "$store" -o "$store.png" --photons 20000 --spp 2 --gather 4 --width 64 --height 48 \
      --workers 2 > /dev/null 2>&1
  python3 - "$store/conversion.json" "$store.png.json" "$camera" "$spaces" "$doors" "$windows" "$store.import.txt" \
      "$glazed" <<'PY'
import json, sys
conversion, render, camera, spaces, doors, windows, info, glazed = sys.argv[1:]
s = json.load(open(conversion))["summary"]
r = json.load(open(render))
problems = []
def expect(ok, what):
    if not ok: problems.append(what)
expect(s["spaces"] == int(spaces), f"spaces {s['spaces']} != {spaces}")
expect(s["spaces_with_cells"] == s["spaces"], f"spaces with cells {s['spaces_with_cells']} of {s['spaces']}")
expect(s["cells"] > s["spaces"], f"only {s['cells']} cells")
expect(s["connected_components"] == 1, f"cell graph in {s['connected_components']} pieces")
expect(s["cameras"] == s["spaces"], f"{s['cameras']} cameras for {s['spaces']} spaces")
expect(s["lights"] == s["spaces"], f"{s['lights']} lamps for {s['spaces']} spaces")
expect(s["doors_with_portal"] >= int(doors), f"doors with a portal {s['doors_with_portal']} < {doors}")
expect(s["windows_with_portal"] >= int(windows), f"windows with a portal {s['windows_with_portal']} < {windows}")
expect(s["windows_glazed"] == int(glazed) and s["windows_at_opening"] == int(glazed),
       f"glazed windows {s['windows_glazed']} ({s['windows_at_opening']} at an opening) != {glazed}")
expect(s["windows_glazed"] + s["windows_without_glass"] == s["windows"] and s["windows_glass_unplaced"] == 0,
       f"windows {s['windows']}: glazed {s['windows_glazed']}, without glass {s['windows_without_glass']}, "
       f"glass unplaced {s['windows_glass_unplaced']}")
# The IfcSites' RefLatitude and RefLongitude (degrees, minutes, seconds, millionths) and true north.
sites = {"5 Wohnen": (49 + 6 / 60 + 1.566 / 3600, 8 + 26 / 60 + 11.5404 / 3600, 130.0),
         "A102 Living Room": (41 + 52 / 60 + 27.84 / 3600, -(87 + 38 / 60 + 21.839999 / 3600), 180.0)}
site = s.get("site") or {}
expect(all(abs(site.get(k, 1e9) - v) < 1e-4 for k, v in zip(("latitude", "longitude", "north_azimuth"), sites[camera])),
       f"site {site}, expected {sites[camera]}")
text = open(info).read()
expect("valid:" in text, "store not valid: " + text[-300:])
p = r["photons"]
expect(p["emitted"] == 20000, f"emitted {p['emitted']}")
# Every photon is accounted for; a rare photon still slips between cells
# through a slit under the sealing test's sampling (docs/importing-buildings.md).
expect(p["absorbed"] + p["escaped"] == p["emitted"], f"photons unaccounted: {p}")
expect(p["escaped"] <= p["emitted"] // 10000, f"escaped photons {p['escaped']} > 0.01 %")
expect(r["rays"]["escaped"] == 0, f"rays escaped: {r['rays']['escaped']} of {r['rays']['traced']}")
if problems:
    print(f"{camera}: " + "; ".join(problems)); sys.exit(1)
print(f"ok {camera}: {s['cells']} cells, {s['portals']} portals, {s['doors_with_portal']}/{s['doors']} doors and "
      f"{s['windows_with_portal']}/{s['windows']} windows with a portal, escaped photons {p['escaped']}, rays {r['rays']['escaped']} of {r['rays']['traced']}")
PY
  python3 "$(dirname "$0")/png_not_black.py" "$store.png"
}

check AC20-FZK-Haus.ifc "5 Wohnen" 7 5 11 11
# Duplex's two skylights carry no style: no glass, left open.
check Duplex_A_20110907.ifc "A102 Living Room" 21 14 24 22
