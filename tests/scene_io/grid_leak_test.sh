#!/usr/bin/env bash
# Voxel cells leak nothing: a closed scene (the Cornell box, tests/scenes)
# cut into 4^3 and 8^3 voxels lets out no photon and no ray, as in one cell.
# Usage: grid_leak_test.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$1"; src="$2"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
for grid in 4 8; do
  "$bin/portico" scene import --grid "$grid" "$src/tests/scenes/cornell_closed/scene.json" "$work/g$grid" > /dev/null
  "$bin/portico" render "$work/g$grid" -o "$work/g$grid.png" --photons 200000 --spp 2 --gather 4 \
      --width 64 --height 64 --workers 2 > /dev/null 2>&1
  python3 - "$work/g$grid.png.json" "$grid" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
p, rays = r["photons"], r["rays"]
print(f"--grid {sys.argv[2]}: photons escaped {p['escaped']} of {p['emitted']}, rays escaped {rays['escaped']} of {rays['traced']}")
sys.exit(0 if p["escaped"] == 0 and rays["escaped"] == 0 and p["absorbed"] == p["emitted"] else 1)
PY
done
