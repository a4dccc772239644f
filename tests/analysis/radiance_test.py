#!/usr/bin/env python3
"""`portico analyze` against Radiance on a reference scene of tests/scenes.

  radiance_test.py BIN_DIR SOURCE_DIR SCENE [portico analyze arguments...]

The scene's sensors (sensors.pts) are measured by `portico analyze` (with
the scene's render_args.txt, for daylight, and the arguments given) and
compared with the converged Radiance reference stored beside it
(radiance_reference.csv, made by tests/tools/radiance_reference.py with
the rtrace command in its header): every sensor's illuminance within 5 %,
the mean over sensors within 2 %. Both sides are 179 x Rec. 709 Y of the
RGB irradiance. Then a cheap live check that the stored reference is still
what Radiance gives for this export: three sensors (the brightest, the
median, the first) through rtrace -I at the reference's settings with a
quarter of its divisions, four runs each, within 3 %.
Exit 77 (ctest: skipped) where Radiance is not installed."""
import math, os, subprocess, sys, tempfile, time

bin_dir, source_dir, scene = sys.argv[1:4]
extra = sys.argv[4:]
sys.path.insert(0, os.path.join(source_dir, "tests", "tools"))
import radiance_tools as rt

radiance = rt.radiance_or_skip(source_dir)
check = rt.Checks()

portico = os.path.join(bin_dir, "portico")
rt.analyze_or_skip(portico)
scene_dir = os.path.join(source_dir, "tests", "scenes", scene)
args_file = os.path.join(scene_dir, "render_args.txt")
daylight = open(args_file).read().split() if os.path.exists(args_file) else []
sensors = rt.read_pts(os.path.join(scene_dir, "sensors.pts"))
reference = rt.read_reference(os.path.join(scene_dir, "radiance_reference.csv"))
assert len(reference) == len(sensors), f"{len(reference)} reference rows for {len(sensors)} sensors"


with tempfile.TemporaryDirectory() as work:
    store = os.path.join(work, "store")
    subprocess.run([portico, "scene", "import", os.path.join(scene_dir, "scene.json"), store], check=True,
                   capture_output=True)
    results = os.path.join(work, "results.csv")
    command = [portico, "analyze", store, "-o", results, "--sensors", os.path.join(scene_dir, "sensors.pts"),
               *daylight, *extra]
    started = time.monotonic()
    run = subprocess.run(command, capture_output=True, text=True)
    seconds = time.monotonic() - started
    if run.returncode != 0:
        print(run.stdout, run.stderr)
        sys.exit(f"portico analyze failed: {' '.join(command)}")
    rows = rt.read_results(results)
    check(len(rows) == len(sensors), f"{len(rows)} result rows for {len(sensors)} sensors")

    errors, inconsistent = [], 0
    for ref, row in zip(reference, rows):
        # Radiance's side is 179 x Rec. 709 Y of its RGB: so must portico's lux be of its RGB.
        if abs(rt.lux((row["irradiance_r"], row["irradiance_g"], row["irradiance_b"])) - row["lux"]) > 1e-3 * row["lux"] + 1e-6:
            inconsistent += 1
        errors.append((row["lux"] / ref["lux"] - 1, ref, row))
    check(inconsistent == 0, f"{scene}: every row's lux is 179 x Rec. 709 Y of its irradiance ({inconsistent} not)")
    worst = max(errors, key=lambda e: abs(e[0]))
    mean_ratio = sum(row["lux"] for _, _, row in errors) / sum(ref["lux"] for _, ref, _ in errors) - 1
    rms = math.sqrt(sum(e * e for e, _, _ in errors) / len(errors))
    print(f"{scene}: {len(rows)} sensors in {seconds:.1f} s ({' '.join(command[3:])})")
    for e, ref, row in sorted(errors, key=lambda e: -abs(e[0]))[:5]:
        print(f"  sensor {ref['index']} at ({ref['x']:g}, {ref['y']:g}, {ref['z']:g}) facing "
              f"({ref['dx']:g}, {ref['dy']:g}, {ref['dz']:g}): portico {row['lux']:.2f} lx "
              f"(+-{row['standard_error_lux']:.2f}), Radiance {ref['lux']:.2f} lx: {100 * e:+.2f} %")
    over = [e for e in errors if abs(e[0]) > 0.05]
    check(not over, f"{scene}: every sensor within 5 % of Radiance ({len(over)} over; worst {100 * worst[0]:+.2f} % "
                    f"at sensor {worst[1]['index']}; RMS {100 * rms:.2f} %)")
    check(abs(mean_ratio) <= 0.02, f"{scene}: mean over sensors {100 * mean_ratio:+.2f} % from Radiance's (limit 2 %)")

    # The stored reference is still what Radiance makes of this export.
    rad = os.path.join(work, "scene.rad")
    subprocess.run([portico, "scene", "export", store, "-o", rad, *daylight], check=True, capture_output=True)
    octree = os.path.join(work, "scene.oct")
    rt.oconv(radiance, ([os.path.join(work, "scene.sky.rad")] if daylight else []) + [rad], octree)
    # The reference's settings with a quarter of its divisions, each sensor four times (-u+: independent
    # samples), at the brightest, the median and the first sensor of the file (the dimmest are the noisiest).
    by_lux = sorted(reference, key=lambda p: p["lux"])
    picks = [by_lux[-1], by_lux[len(by_lux) // 2], reference[0]]
    options = ["-ab", "40", "-lr", "-80", "-ad", "2048", "-aa", "0", "-lw", "1e-6", "-ds", "0.01", "-dj", "0", "-dc", "1",
               "-dt", "0", "-u+"]
    live = rt.rtrace_irradiance(radiance, octree, options,
                                [tuple(p[k] for k in ("x", "y", "z", "dx", "dy", "dz")) for p in picks for _ in range(4)])
    for n, p in enumerate(picks):
        samples = [rt.lux(v) for v in live[4 * n:4 * n + 4]]
        value = sum(samples) / 4
        off = value / p["lux"] - 1
        # rtrace -u+ is not seeded: the four samples' own spread bounds what
        # a dim, indirectly lit sensor can be asked (3 % or 4 standard errors).
        spread = (sum((x - value) ** 2 for x in samples) / 3) ** 0.5 / 2 / value
        limit = max(0.03, 4 * spread)
        check(abs(off) <= limit, f"{scene}: live rtrace -I at sensor {p['index']}: {value:.2f} lx, stored "
                                 f"{p['lux']:.2f} lx ({100 * off:+.2f} %, limit {100 * limit:.2f} %)")

check.finish()
