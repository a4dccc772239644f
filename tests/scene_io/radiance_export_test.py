#!/usr/bin/env python3
"""`portico scene export STORE -o FILE.rad` read by Radiance's own tools.

  radiance_export_test.py BIN_DIR SOURCE_DIR

* The three lit reference scenes (cornell_closed, two_rooms,
  daylight_window with its sun and sky): Radiance's `oconv` compiles each,
  and the file holds what the store holds: as many polygons as the export
  reports, every material defined once, each lamp one `light` polygon, the
  triangles the store has (a lamp quad counting two); `getinfo -d` gives
  the store's bounds.
* An IES point luminaire, aimed askew, exported as a Radiance source (a
  light sphere with its candela distribution as brightdata): rtrace -I
  -ab 0 gives E = I(gamma, C) cos / d^2 at sensors of several orientations
  within 2 %.
* Units and orientation: rtrace -I -ab 0 under the Cornell box's lamp
  (0.4 x 0.4 m, radiance 15, 1 m above the sensor) gives the closed form of
  a rectangle over a point; the exported overcast sky gives 10 000 lx on
  an open horizontal plane; a glazed pane facing the sun passes what
  portico's pane passes at normal incidence (tint x (1 - R) / (1 + R)).
Exit 77 (ctest: skipped) where Radiance is not installed."""
import json, math, os, re, subprocess, sys, tempfile

bin_dir, source_dir = sys.argv[1], sys.argv[2]
sys.path.insert(0, os.path.join(source_dir, "tests", "tools"))
import radiance_tools as rt

radiance = rt.radiance_or_skip(source_dir)
check = rt.Checks()
portico = os.path.join(bin_dir, "portico")
scenes = os.path.join(source_dir, "tests", "scenes")


def run(*command):
    return subprocess.run(command, check=True, capture_output=True, text=True).stdout


def primitives(path):
    """(modifier, type, name, real arguments) of each primitive of a Radiance file."""
    words = []
    with open(path) as f:
        for line in f:
            words += line.split("#", 1)[0].split()
    out, i = [], 0
    while i < len(words):
        modifier, kind, name = words[i:i + 3]
        i += 3
        counts = []
        for _ in range(3):   # string, integer and real arguments, each a count and the values
            n = int(words[i])
            counts.append(words[i + 1:i + 1 + n])
            i += 1 + n
        out.append((modifier, kind, name, [float(v) for v in counts[2]]))
    return out


with tempfile.TemporaryDirectory() as work:
    print(rt.version(radiance))
    for scene in ("cornell_closed", "two_rooms", "daylight_window"):
        store = os.path.join(work, scene)
        run(portico, "scene", "import", os.path.join(scenes, scene, "scene.json"), store)
        info = json.loads(run(portico, "scene", "info", store, "--json", "--quick"))
        args_file = os.path.join(scenes, scene, "render_args.txt")
        args = open(args_file).read().split() if os.path.exists(args_file) else []
        rad = os.path.join(work, scene + ".rad")
        summary = run(portico, "scene", "export", store, "-o", rad, *args)
        reported = int(re.search(r"as (\d+) polygons", summary).group(1))
        prims = primitives(rad)
        kinds = {}
        for modifier, kind, name, _ in prims:
            kinds[kind] = kinds.get(kind, 0) + 1
        materials = {name: kind for modifier, kind, name, _ in prims if kind != "polygon"}
        polygons = [p for p in prims if p[1] == "polygon"]
        lamps = [p for p in polygons if materials.get(p[0]) == "light"]
        triangles = sum(len(p[3]) // 3 - 2 for p in polygons)
        check(len(polygons) == reported and len(materials) == info["materials"] and
              len(lamps) == info["lights"] and triangles == info["triangles"],
              f"{scene}: {len(polygons)} polygons (export says {reported}), {len(materials)} materials "
              f"(store: {info['materials']}), {len(lamps)} lamps (store: {info['lights']} lights), "
              f"{triangles} triangles (store: {info['triangles']})")
        octree = os.path.join(work, scene + ".oct")
        files = ([os.path.join(work, scene + ".sky.rad")] if args else []) + [rad]
        rt.oconv(radiance, files, octree)
        bounds = [float(v) for v in subprocess.run(["getinfo", "-d", octree], env=rt.environment(radiance),
                                                   capture_output=True, text=True, check=True).stdout.split()[1:]]
        corners = re.search(r"bounds \(([^)]*)\) - \(([^)]*)\)", summary).groups()
        numbers = [float(v) for corner in corners for v in corner.split(",")]
        lo, hi = numbers[:3], numbers[3:]
        inside = all(bounds[k] <= lo[k] and bounds[k] + bounds[3] >= hi[k] for k in range(3))
        check(inside, f"{scene}: oconv compiles it; its octree cube {bounds} holds the store's bounds {lo} - {hi}")
        if scene == "cornell_closed":
            # The lamp: 0.4 x 0.4 m at y = 1.999 facing down, radiance 15; a point 1 m below its centre.
            d, a = 1.0, 0.2
            corner = a / math.hypot(a, d) * math.atan(a / math.hypot(a, d))
            expected = 4 * 15 / 2 * 2 * corner   # four rectangles with a corner over the point, each (L/2)(...+...)
            got = rt.rtrace_irradiance(radiance, octree, ["-ab", "0", "-ds", "0.01", "-dj", "0"],
                                       [(0, 0.999, 0, 0, 1, 0)])[0]
            check(abs(got[0] / expected - 1) < 0.005, f"cornell_closed lamp: rtrace -I -ab 0 gives {got[0]:.5g} W/m^2 "
                  f"1 m under it, the closed form {expected:.5g}")

    # A pane alone, and the sun and sky it is exported with.
    store = os.path.join(work, "pane")
    pane = os.path.join(work, "pane.obj")
    with open(pane, "w") as f:   # 1 x 1 m, horizontal at y = 1, facing up
        f.write("v -0.5 1 0.5\nv 0.5 1 0.5\nv 0.5 1 -0.5\nv -0.5 1 -0.5\nf 1 2 3\nf 1 3 4\n")
    building = os.path.join(work, "pane.json")
    with open(building, "w") as f:
        json.dump({"objects": [{"obj": "pane.obj", "glass": {"transmittance": [0.6, 0.8, 1.0], "ior": 1.5}}],
                   "camera": {"origin": [0, 2, 3], "target": [0, 1, 0]}}, f)
    subprocess.run([portico, "scene", "import", building, store], check=True, capture_output=True)
    rad, sky, octree = (os.path.join(work, "pane" + e) for e in (".rad", ".sky.rad", ".oct"))

    # The overcast sky and a sun of 10 W/m^2 at 30 degrees on an open horizontal plane.
    run(portico, "scene", "export", store, "-o", rad, "--sky", "overcast", "--sun", "0,30", "--sun-irradiance", "10,10,10")
    rt.oconv(radiance, [sky], octree)
    got = rt.rtrace_irradiance(radiance, octree, ["-ab", "1", "-ad", "16384", "-aa", "0", "-dj", "0"], [(0, 0, 0, 0, 1, 0)])[0]
    expected = 10000 + 179 * 10 * math.sin(math.radians(30))
    check(abs(rt.lux(got) / expected - 1) < 0.01,
          f"overcast sky and sun: {rt.lux(got):.0f} lx on an open horizontal plane, {expected:.0f} expected")

    # Normal incidence: the sun overhead through the pane.
    run(portico, "scene", "export", store, "-o", rad, "--sky", "uniform:0,0,0", "--sun", "0,90", "--sun-irradiance", "10,10,10")
    rt.oconv(radiance, [sky, rad], octree)
    got = rt.rtrace_irradiance(radiance, octree, ["-ab", "0", "-dj", "0"], [(0, 0.5, 0, 0, 1, 0)])[0]
    r = (0.5 / 2.5) ** 2
    expected = [10 * t * (1 - r) / (1 + r) for t in (0.6, 0.8, 1.0)]
    check(all(abs(g / e - 1) < 0.002 for g, e in zip(got, expected)),
          f"the sun through a pane of tint 0.6 0.8 1 at normal incidence: {' '.join(f'{g:.4f}' for g in got)} W/m^2; "
          f"portico's pane passes {' '.join(f'{e:.4f}' for e in expected)}")

    # An IES point luminaire, aimed askew and brighter towards C0, as a Radiance source: rtrace -I -ab 0 at
    # sensors of several orientations gives E = I(gamma, C) cos(theta) / d^2 (inverse-square and cosine laws).
    def candela(gamma, c):
        return 0.0 if gamma > 90 else (500 + 1000 * math.cos(math.radians(gamma))) * (
            1 + 0.3 * math.sin(math.radians(gamma)) * math.cos(math.radians(c)))
    with open(os.path.join(work, "askew.ies"), "w") as f:
        f.write("IESNA:LM-63-2002\n[TEST] radiance_export_test\nTILT=NONE\n1 -1 1 37 73 1 2 0 0 0\n1 1 10\n")
        f.write(" ".join(f"{2.5 * v:g}" for v in range(37)) + "\n" + " ".join(f"{5 * h:g}" for h in range(73)) + "\n")
        for h in range(73):
            f.write(" ".join(f"{candela(2.5 * v, 5 * h):.6f}" for v in range(37)) + "\n")
    with open(os.path.join(work, "far.obj"), "w") as f:   # something to import, far away
        f.write("v 50 0 50\nv 51 0 50\nv 51 0 51\nf 1 2 3\n")
    position, aim, c0 = (0.0, 2.0, 0.0), (0.3, -1.0, 0.2), (1.0, 0.0, 0.0)
    with open(os.path.join(work, "askew.json"), "w") as f:
        json.dump({"objects": [{"obj": "far.obj", "albedo": [0, 0, 0]}],
                   "lights": [{"name": "askew", "ies": "askew.ies", "position": list(position), "aim": list(aim),
                               "c0": list(c0), "colour": [1, 1, 1]}],
                   "camera": {"origin": [0, 1, 3], "target": [0, 0, 0]}}, f)
    store = os.path.join(work, "askew")
    run(portico, "scene", "import", os.path.join(work, "askew.json"), store)
    rad = os.path.join(work, "askew.rad")
    summary = run(portico, "scene", "export", store, "-o", rad)
    check("1 IES luminaires" in summary and os.path.exists(os.path.join(work, "askew.luminaire0.dat")),
          f"the luminaire exported with its data file: {summary.strip()}")
    octree = os.path.join(work, "askew.oct")
    rt.oconv(radiance, [rad], octree)

    def unit(v):
        n = math.sqrt(sum(x * x for x in v))
        return tuple(x / n for x in v)
    def dot(a, b):
        return sum(x * y for x, y in zip(a, b))
    def cross(a, b):
        return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    nadir = unit(aim)
    c0_axis = unit(tuple(c - dot(c0, nadir) * n for c, n in zip(c0, nadir)))
    c90_axis = cross(c0_axis, nadir)
    sensors = [(x, 0.0, z, 0, 1, 0) for x in (-1.5, 0.0, 1.5) for z in (-1.5, 0.0, 1.5)]
    sensors += [(1.0, 1.0, 0.5, -1, 0, 0), (-0.5, 0.8, -1.0, 0.6, 0.8, 0), (0.5, 0.3, 1.2, 0, 0.6, -0.8)]
    expected = []
    for s in sensors:
        to_sensor = tuple(a - b for a, b in zip(s[:3], position))
        d2 = dot(to_sensor, to_sensor)
        e = unit(to_sensor)
        gamma = math.degrees(math.acos(max(-1.0, min(1.0, dot(e, nadir)))))
        c = math.degrees(math.atan2(dot(e, c90_axis), dot(e, c0_axis)))
        cos_theta = max(0.0, -dot(e, s[3:]))
        expected.append(candela(gamma, c) * cos_theta / d2)
    cwd = os.getcwd()
    os.chdir(work)   # the data file is found beside the scene (RAYPATH holds .)
    try:
        got = [rt.lux(rgb) for rgb in rt.rtrace_irradiance(radiance, octree, ["-ab", "0", "-ds", "0.01", "-dj", "0"],
                                                              sensors)]
    finally:
        os.chdir(cwd)
    worst = max(abs(g / e - 1) for g, e in zip(got, expected) if e > 0)
    check(worst < 0.02 and all(e > 0 for e in expected),
          f"the IES luminaire through rtrace -I: {len(sensors)} sensors within {100 * worst:.2f} % of I cos / d^2 "
          f"({' '.join(f'{g:.1f}/{e:.1f}' for g, e in zip(got, expected))} lx)")
    # The check can tell: 5 % more light is off by more than 2 % somewhere.
    check(max(abs(g / (1.05 * e) - 1) for g, e in zip(got, expected)) > 0.02, "a 5 % error would be seen")

    # Refused: Preetham's sky, and a sky for a format that has none.
    refused = subprocess.run([portico, "scene", "export", store, "-o", rad, "--sun", "30,40"], capture_output=True,
                             text=True)
    check(refused.returncode != 0 and "preetham" in refused.stderr.lower(),
          f"--sun alone (Preetham's sky) refused: {refused.stderr.strip()}")
    refused = subprocess.run([portico, "scene", "export", store, "-o", os.path.join(work, "x.obj"), "--sky",
                              "overcast"], capture_output=True, text=True)
    check(refused.returncode != 0 and ".rad" in refused.stderr, f"--sky with an OBJ export refused: {refused.stderr.strip()}")

check.finish()
