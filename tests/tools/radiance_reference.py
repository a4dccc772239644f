#!/usr/bin/env python3
"""Sensors and converged Radiance references for the reference scenes, for the
comparison of `portico analyze` with Radiance (tests/analysis/radiance_test.py).

  radiance_reference.py sensors SCENE PORTICO     # writes tests/scenes/SCENE/sensors.pts
  radiance_reference.py reference SCENE PORTICO   # writes tests/scenes/SCENE/radiance_reference.csv

PORTICO is the `portico` binary (its `scene import` and `scene export -o
FILE.rad` make the Radiance scene). Radiance: tests/tools/radiance_tools.py.

Sensors: a work plane 0.8 m above each floor (objects named *floor*), one
sensor facing up at the centre of every 0.5 m square of it, none within
5 cm of the footprint of a box (objects named *box*) reaching 0.75 m or
higher; and in each room four sensors 1.2 m up at its centre facing +x, -x,
+z, -z. Under daylight with a sun, a sensor whose direct sunlight changes
when it moves 5 cm along x or z is dropped: it sits on a shadow's edge,
where a millimetre decides between sun and shade.

Reference: rtrace -I with the settings of REFERENCE_OPTIONS (no ambient
cache, 8192 divisions, up to 40 bounces ended by Russian roulette: -lr -80,
since rtrace's default -lr 7 cuts every path after 7 reflections, ambient
ones included, which left the room lit only through its door in two_rooms
6 % too dark; sources cut to 1 % pieces), each sensor REPEATS times with
independent samples (-u+): the mean, and the standard error of the mean
from the spread."""
import argparse, json, math, os, subprocess, sys, tempfile, time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import radiance_tools as rt

SCENES = os.path.join(rt.SOURCE_DIR, "tests", "scenes")
REFERENCE_OPTIONS = ["-ab", "40", "-lr", "-80", "-ad", "8192", "-aa", "0", "-lw", "1e-7", "-ds", "0.01", "-dj", "0", "-dc", "1",
                     "-dt", "0", "-u+"]
REPEATS = 4
PLANE_HEIGHT, SPACING, BOX_MARGIN = 0.8, 0.5, 0.05


def obj_bounds(path):
    lo, hi = [math.inf] * 3, [-math.inf] * 3
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                p = [float(w) for w in line.split()[1:4]]
                lo = [min(a, b) for a, b in zip(lo, p)]
                hi = [max(a, b) for a, b in zip(hi, p)]
    return lo, hi


def render_args(scene):
    path = os.path.join(SCENES, scene, "render_args.txt")
    return open(path).read().split() if os.path.exists(path) else []


def radiance_scene(scene, portico, work, args):
    """Imports the scene and exports it for Radiance with daylight `args`; returns the octree."""
    store = os.path.join(work, "store")
    if not os.path.isdir(store):
        subprocess.run([portico, "scene", "import", os.path.join(SCENES, scene, "scene.json"), store], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    tag = "sun" if "--sky" in args and "uniform:0,0,0" in args else "scene"
    rad = os.path.join(work, tag + ".rad")
    subprocess.run([portico, "scene", "export", store, "-o", rad, *args], check=True, stdout=subprocess.DEVNULL)
    files = [os.path.join(work, tag + ".sky.rad")] if args else []
    octree = os.path.join(work, tag + ".oct")
    rt.oconv(RADIANCE, files + [rad], octree)
    return octree


def make_sensors(scene, portico):
    description = json.load(open(os.path.join(SCENES, scene, "scene.json")))
    floors, boxes = [], []
    for o in description["objects"]:
        lo, hi = obj_bounds(os.path.join(SCENES, scene, o["obj"]))
        if "floor" in o["obj"]:
            floors.append((lo, hi))
        elif "box" in o["obj"] and hi[1] >= PLANE_HEIGHT - BOX_MARGIN:
            boxes.append((lo, hi))

    def free(x, z):
        return all(not (lo[0] - BOX_MARGIN <= x <= hi[0] + BOX_MARGIN and lo[2] - BOX_MARGIN <= z <= hi[2] + BOX_MARGIN)
                   for lo, hi in boxes)

    sensors = []
    for lo, hi in floors:
        nx, nz = round((hi[0] - lo[0]) / SPACING), round((hi[2] - lo[2]) / SPACING)
        for i in range(nx):
            for k in range(nz):
                x, z = lo[0] + (i + 0.5) * SPACING, lo[2] + (k + 0.5) * SPACING
                if free(x, z):
                    sensors.append((x, lo[1] + PLANE_HEIGHT, z, 0, 1, 0))
        cx, cz = (lo[0] + hi[0]) / 2, (lo[2] + hi[2]) / 2
        if free(cx, cz):
            sensors += [(cx, lo[1] + 1.2, cz, *d) for d in ((1, 0, 0), (-1, 0, 0), (0, 0, 1), (0, 0, -1))]

    args = render_args(scene)
    if "--sun" in args:
        sky = args.index("--sky") if "--sky" in args else None
        sun_only = [a for i, a in enumerate(args) if sky is None or i not in (sky, sky + 1)]
        with tempfile.TemporaryDirectory() as work:
            octree = radiance_scene(scene, portico, work, sun_only + ["--sky", "uniform:0,0,0"])
            probes = []
            for s in sensors:
                probes.append(s)
                for dx, dz in ((0.05, 0), (-0.05, 0), (0, 0.05), (0, -0.05)):
                    probes.append((s[0] + dx, s[1], s[2] + dz, *s[3:]))
            values = [rt.lux(v) for v in rt.rtrace_irradiance(RADIANCE, octree, ["-ab", "0", "-dj", "0"], probes)]
            kept = []
            for n, s in enumerate(sensors):
                group = values[5 * n:5 * n + 5]
                if max(group) - min(group) <= 0.01 * max(group[0], 1e-9) or max(group) == 0:
                    kept.append(s)
            print(f"{scene}: {len(sensors) - len(kept)} sensors on the edge of a sun patch dropped")
            sensors = kept
    path = os.path.join(SCENES, scene, "sensors.pts")
    with open(path, "w") as f:
        for s in sensors:
            f.write(" ".join(f"{v:g}" for v in s) + "\n")
    print(f"{path}: {len(sensors)} sensors")


def make_reference(scene, portico):
    sensors = rt.read_pts(os.path.join(SCENES, scene, "sensors.pts"))
    args = render_args(scene)
    started = time.monotonic()
    with tempfile.TemporaryDirectory() as work:
        octree = radiance_scene(scene, portico, work, args)
        values = rt.rtrace_irradiance(RADIANCE, octree, REFERENCE_OPTIONS, [s for s in sensors for _ in range(REPEATS)])
    seconds = time.monotonic() - started
    path = os.path.join(SCENES, scene, "radiance_reference.csv")
    sky = " scene.sky.rad" if args else ""
    with open(path, "w") as f:
        f.write(f"# Radiance reference of tests/scenes/{scene}/sensors.pts, by tests/tools/radiance_reference.py:\n"
                f"#   portico scene import tests/scenes/{scene}/scene.json STORE\n"
                f"#   portico scene export STORE -o scene.rad{(' ' + ' '.join(args)) if args else ''}\n"
                f"#   oconv{sky} scene.rad > scene.oct\n"
                f"#   rtrace -h -I {' '.join(REFERENCE_OPTIONS)} scene.oct < sensors.pts\n"
                f"# each sensor {REPEATS} times (-u+: independent samples): R,G,B the mean irradiance (W/m^2),\n"
                f"# lux = 179 x Rec. 709 Y of it, lux_stderr the standard error of the mean.\n"
                f"# {rt.version(RADIANCE)}; {seconds:.0f} s wall, one rtrace process on a shared 2-core machine.\n")
        f.write("index,x,y,z,dx,dy,dz,R,G,B,lux,lux_stderr\n")
        for n, s in enumerate(sensors):
            runs = values[REPEATS * n:REPEATS * (n + 1)]
            mean = [sum(r[c] for r in runs) / REPEATS for c in range(3)]
            luxes = [rt.lux(r) for r in runs]
            m = sum(luxes) / REPEATS
            stderr = math.sqrt(sum((v - m) ** 2 for v in luxes) / (REPEATS - 1) / REPEATS)
            f.write(",".join([str(n)] + [f"{v:g}" for v in s] + [f"{v:.6g}" for v in mean] +
                             [f"{rt.lux(mean):.6g}", f"{stderr:.3g}"]) + "\n")
    print(f"{path}: {len(sensors)} sensors, {seconds:.0f} s")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("what", choices=["sensors", "reference"])
    parser.add_argument("scene")
    parser.add_argument("portico")
    a = parser.parse_args()
    RADIANCE = rt.find_radiance()
    if RADIANCE is None:
        sys.exit("no Radiance: deploy/install-deps.sh installs pyradiance into .venv")
    (make_sensors if a.what == "sensors" else make_reference)(a.scene, os.path.abspath(a.portico))
