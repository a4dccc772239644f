#!/usr/bin/env bash
# Triangle lights: a closed room (an OBJ + MTL whose two colours the
# building.json leaves to the file) lit from its "lights" array.
#  1. The ceiling lamp as one quad and as the same quad cut into two
#     triangle lights render the same image within the reference tolerances
#     (portico-compare: 3 % mean, 10 % per block).
#  2. A lone triangle lamp: every photon accounted for (absorbed; none
#     escapes the closed room), the image is not black, and 1 and 2 workers
#     give the same bits.
# Usage: triangle_light_test.sh BIN_DIR
set -euo pipefail
bin="$1"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT

# The room x, z in [0, 4], y in [0, 3], every face looking inwards.
cat > "$work/room.mtl" <<'MTL'
newmtl wall
Kd 0.6 0.6 0.6
newmtl floor
Kd 0.5 0.3 0.2
MTL
cat > "$work/room.obj" <<'OBJ'
mtllib room.mtl
v 0 0 0
v 4 0 0
v 4 0 4
v 0 0 4
v 0 3 0
v 4 3 0
v 4 3 4
v 0 3 4
usemtl floor
f 1 4 3 2
usemtl wall
f 5 6 7 8
f 1 2 6 5
f 4 8 7 3
f 1 5 8 4
f 2 3 7 6
OBJ

write_building() {   # NAME LIGHTS_JSON
  cat > "$work/$1.json" <<JSON
{"units": "metres",
 "objects": [{"obj": "room.obj", "name": "room"}],
 "lights": $2,
 "camera": {"origin": [2, 1.5, 3.8], "target": [2, 1.2, 0], "fov_y_deg": 70, "width": 64, "height": 64}}
JSON
  "$bin/portico" scene import "$work/$1.json" "$work/$1" > /dev/null
}
render() {   # NAME OUTPUT WORKERS
  "$bin/portico" render "$work/$1" -o "$work/$2" --photons 400000 --spp 16 --gather 4 --seed 3 \
      --workers "$3" > /dev/null 2>&1
}

# The lamp: corner (1.5, 2.99, 1.5), 1 m x 1 m, facing down.
write_building quad '[{"quad": {"corner": [1.5, 2.99, 1.5], "edge1": [1, 0, 0], "edge2": [0, 0, 1]}, "radiance": [8, 8, 8]}]'
write_building halves '[{"triangle": [[1.5, 2.99, 1.5], [2.5, 2.99, 1.5], [2.5, 2.99, 2.5]], "radiance": [8, 8, 8]},
                        {"triangle": [[1.5, 2.99, 1.5], [2.5, 2.99, 2.5], [1.5, 2.99, 2.5]], "radiance": [8, 8, 8]}]'
write_building lone '[{"triangle": [[1.5, 2.99, 1.5], [2.5, 2.99, 1.5], [1.5, 2.99, 2.5]], "radiance": [12, 12, 12]}]'
render quad quad.exr 2
render halves halves.exr 2
echo "two triangle lights against one quad light: $("$bin/portico-compare" "$work/halves.exr" "$work/quad.exr")"
"$bin/portico-compare" "$work/halves.exr" "$work/quad.exr" > /dev/null

render lone one.exr 1
render lone two.exr 2
python3 - "$work" <<'PY'
import json, subprocess, sys
work = sys.argv[1]
# The SHA-1 of the pixels (the EXR header carries the time it was written).
digest = lambda name: subprocess.run(["iinfo", "--hash", f"{work}/{name}"], capture_output=True, text=True,
                                     check=True).stdout.split("SHA-1:")[1].split()[0]
problems = []
for name in ("one", "two"):
    r = json.load(open(f"{work}/{name}.exr.json"))
    p = r["photons"]
    if not (p["emitted"] > 0 and p["absorbed"] == p["emitted"] and p["escaped"] == 0 and p["queued"] == 0):
        problems.append(f"{name}: photons not conserved: {p}")
    if r["rays"]["escaped"] != 0: problems.append(f"{name}: {r['rays']['escaped']} rays escaped")
if digest("one.exr") != digest("two.exr"): problems.append("1 and 2 workers give different images")
if problems: print("; ".join(problems)); sys.exit(1)
print(f"lone triangle lamp: photons conserved, 1 and 2 workers give the same bits ({digest('one.exr')[:12]})")
PY
"$bin/portico-compare" "$work/one.exr" "$work/one.exr" --json | python3 -c '
import json, sys
mean = json.load(sys.stdin)["image_mean"]
print(f"lone triangle lamp: image mean {mean:.4f}")
sys.exit(0 if mean > 0.01 else 1)'
