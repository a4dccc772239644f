#!/usr/bin/env python3
"""Render time of `scene import --cells rooms` against the generator's own cells and `--grid N`
(docs/room-finding.md): a preset exported to OBJ is imported as found rooms and as N^3 voxel cells for each N, and
each store, with the generator's, renders the generator's first camera inside the building (its second: the first
is an overview from the sky) with the same settings.

Usage: room_finding_bench.py BIN_DIR --preset NAME [--floors N] [--grids 2,4,8] [--width 240 --height 160]
                             [--photons 400000] [--spp 16] [--workers 2]
Prints one line per store: cells, portals, photon pass and render time, portal crossings per camera ray, image mean
and its difference from the generator's store."""
import argparse
import json
import shutil
import subprocess
import tempfile
import time
from pathlib import Path


def run(*command):
    subprocess.run([str(c) for c in command], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("bin_dir")
    parser.add_argument("--preset", required=True)
    parser.add_argument("--floors")
    parser.add_argument("--grids", default="2,4,8")
    parser.add_argument("--width", default="240")
    parser.add_argument("--height", default="160")
    parser.add_argument("--photons", default="400000")
    parser.add_argument("--spp", default="16")
    parser.add_argument("--workers", default="2")
    args = parser.parse_args()
    portico = Path(args.bin_dir) / "portico"
    work = Path(tempfile.mkdtemp(prefix="room-finding-bench-"))
    try:
        generated = work / "generated"
        run(portico, "scene", "generate", "--preset", args.preset, *(["--floors", args.floors] if args.floors else []),
            generated)
        run(portico, "scene", "export", "-o", work / "building.obj", generated)
        stores = {"generator": (generated, None)}
        started = time.monotonic()
        run(portico, "scene", "import", "--cells", "rooms", work / "building.obj", work / "rooms")
        stores["rooms"] = (work / "rooms", time.monotonic() - started)
        for n in args.grids.split(","):
            started = time.monotonic()
            run(portico, "scene", "import", "--grid", n, work / "building.obj", work / f"grid{n}")
            stores[f"grid {n}"] = (work / f"grid{n}", time.monotonic() - started)
        camera = json.loads(subprocess.run([portico, "scene", "info", "--json", "--quick", generated], check=True,
                                           capture_output=True, text=True).stdout)["cameras"][1]
        view = ["--look-from", ",".join(map(str, camera["origin"])), "--look-at", ",".join(map(str, camera["look_at"])),
                "--fov", str(camera["fov"])]
        print(f"{args.preset}: view {camera['name']}", flush=True)
        means = {}
        for name, (store, import_s) in stores.items():
            image = work / f"{name.replace(' ', '')}.exr"
            run(portico, "render", store, *view, "--width", args.width, "--height", args.height, "--photons", args.photons,
                "--spp", args.spp, "--workers", args.workers, "-o", image)
            report = json.loads(Path(f"{image}.json").read_text())
            line = subprocess.run([Path(args.bin_dir) / "portico-compare", image, image], capture_output=True,
                                  text=True).stdout
            means[name] = float(line.split()[2])
            info = json.loads(subprocess.run([portico, "scene", "info", "--json", "--quick", store], check=True,
                                             capture_output=True, text=True).stdout)
            t = report["time_ms"]
            print(f"{args.preset} {name}: {info['cells']} cells, {info['portals']} portals"
                  + (f", import {import_s:.1f} s" if import_s is not None else "")
                  + f"; photons {t['photons'] / 1000:.1f} s, render {t['render'] / 1000:.1f} s, total "
                  f"{t['total'] / 1000:.1f} s; {report['rays']['crossings_per_camera_ray']:.2f} crossings per camera "
                  f"ray; photons escaped {report['photons']['escaped']}; image mean {means[name]:.5f} "
                  f"({100 * (means[name] / means['generator'] - 1):+.1f} % against the generator's)", flush=True)
    finally:
        shutil.rmtree(work)


if __name__ == "__main__":
    main()
