#!/usr/bin/env python3
"""`portico scene import --cells rooms` against the generator's own cells
(docs/room-finding.md): the demo preset exported to OBJ and imported back
finds one region per generated room, cut into few boxes, a portal across every door, renders
the light of the same mesh imported as one cell, and a mesh that is not a
building fails with one line naming it.

Usage: room_finding_test.py BIN_DIR [--preset NAME] [--floors N]   (default demo; the image check runs on demo only)
Prints the figures; exits 1 when a target is missed."""
import itertools
import json
import math
import shutil
import sqlite3
import struct
import subprocess
import sys
import tempfile
from pathlib import Path


def cells_and_portals(store):
    db = sqlite3.connect(Path(store) / "scene.db")
    cells = {i: (name, (x0, y0, z0), (x1, y1, z1))
             for i, name, x0, y0, z0, x1, y1, z1 in db.execute(
                 "SELECT id, name, min_x, min_y, min_z, max_x, max_y, max_z FROM cells")}
    portals = []
    for a, b, blob in db.execute("SELECT cell_a, cell_b, polygon FROM portals"):
        floats = struct.unpack(f"<{len(blob) // 4}f", blob)
        portals.append((a, b, [floats[k:k + 3] for k in range(0, len(floats), 3)]))
    return cells, portals


def region_of(name):
    """room-R-B -> R, outdoors-B -> 0."""
    return 0 if name.startswith("outdoors") else int(name.split("-")[1])


def indoor(name):
    return name != "sky" and not name.startswith("facade")


class CellIndex:
    """The cells overlapping each 1 m bucket of space: a point's cell is looked up among a few, not all."""
    def __init__(self, cells):
        self.cells = cells
        self.buckets = {}
        for i, (name, lo, hi) in cells.items():
            ranges = [range(math.floor(lo[k]), math.floor(hi[k]) + 1) for k in range(3)]
            for key in itertools.product(*ranges):
                self.buckets.setdefault(key, []).append(i)

    def locate(self, p):
        for i in self.buckets.get(tuple(math.floor(p[k]) for k in range(3)), ()):
            name, lo, hi = self.cells[i]
            if all(lo[k] <= p[k] < hi[k] for k in range(3)):
                return i
        return None


def compare(truth_store, found_store):
    truth, truth_portals = cells_and_portals(truth_store)
    found, found_portals = cells_and_portals(found_store)
    index = CellIndex(found)
    # A generated room is found when 90 % of the points of a 0.25 m lattice inside it (0.3 m in from its walls,
    # below 2.5 m) lie in one region that no other generated room shares.
    dominant = {}
    for i, (name, lo, hi) in truth.items():
        if not indoor(name):
            continue
        votes, total = {}, 0
        x = lo[0] + 0.3
        while x < hi[0] - 0.3:
            z = lo[2] + 0.3
            while z < hi[2] - 0.3:
                for y in (lo[1] + 0.5, lo[1] + 1.5, lo[1] + 2.4):
                    c = index.locate((x, y, z))
                    if c is not None:
                        r = region_of(found[c][0])
                        votes[r] = votes.get(r, 0) + 1
                    total += 1
                z += 0.25
            x += 0.25
        if total:
            r, n = max(votes.items(), key=lambda kv: kv[1])
            dominant[i] = (r, n / total)
    owners = {}
    for i, (r, share) in dominant.items():
        owners.setdefault(r, []).append(i)
    # Rooms (cells named "room"): corridors and junctions meet through openings as wide as the corridor, which
    # the finder joins by design, so they are counted in `regions` but not as rooms.
    generated_rooms = [i for i in dominant if "room" in truth[i][0]]
    rooms_found = sum(1 for i in generated_rooms
                      if dominant[i][0] != 0 and dominant[i][1] >= 0.9 and len(owners[dominant[i][0]]) == 1)
    # A door or window (a generated portal out of an indoor cell, between two regions) is found when a found portal
    # joins the same two regions (outdoors: 0), lies within 0.6 m of the opening's plane (the regions' border runs
    # where their fronts meet, near the opening) and covers the opening's centre seen along its normal.
    def region_side(cell):
        return dominant[cell][0] if cell in dominant else 0
    openings = [(a, b, poly) for a, b, poly in truth_portals if indoor(truth[a][0]) or indoor(truth[b][0])]
    openings = [o for o in openings if region_side(o[0]) != region_side(o[1])]
    # The found portals' boxes by the pair of regions they join.
    joining = {}
    for fa, fb, fpoly in found_portals:
        pair = frozenset((region_of(found[fa][0]), region_of(found[fb][0])))
        joining.setdefault(pair, []).append(([min(p[k] for p in fpoly) for k in range(3)],
                                             [max(p[k] for p in fpoly) for k in range(3)]))
    found_openings = 0
    for a, b, poly in openings:
        centre = [sum(p[k] for p in poly) / len(poly) for k in range(3)]
        extent = [max(p[k] for p in poly) - min(p[k] for p in poly) for k in range(3)]
        normal = extent.index(min(extent))
        margin = [0.6 if k == normal else 0.11 for k in range(3)]
        if any(all(lo[k] - margin[k] <= centre[k] <= hi[k] + margin[k] for k in range(3))
               for lo, hi in joining.get(frozenset((region_side(a), region_side(b))), ())):
            found_openings += 1
    rooms = sum(1 for r in owners if r != 0)
    return {"generated_rooms": len(generated_rooms), "generated_indoor_cells": len(dominant), "regions": rooms, "rooms_found": rooms_found,
            "openings": len(openings), "openings_found": found_openings,
            "cells": len(found), "portals": len(found_portals)}


def main():
    bin_dir = sys.argv[1]
    preset = sys.argv[sys.argv.index("--preset") + 1] if "--preset" in sys.argv else "demo"
    work = Path(tempfile.mkdtemp(prefix="room-finding-"))
    portico = f"{bin_dir}/portico"
    failures = []
    generated = str(work / "generated")
    floors = sys.argv[sys.argv.index("--floors") + 1] if "--floors" in sys.argv else None
    subprocess.run([portico, "scene", "generate", "--preset", preset] + (["--floors", floors] if floors else [])
                   + [generated], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    subprocess.run([portico, "scene", "export", "-o", str(work / "building.obj"), generated], check=True,
                   stdout=subprocess.DEVNULL)
    rooms = str(work / "rooms")
    subprocess.run([portico, "scene", "import", "--cells", "rooms", str(work / "building.obj"), rooms], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    figures = compare(generated, rooms)
    print(f"{preset}: {json.dumps(figures)}")
    if preset == "demo" and figures["regions"] != figures["generated_indoor_cells"]:
        failures.append(f"{figures['regions']} regions for {figures['generated_indoor_cells']} generated cells")
    # Few large boxes, not many thin ones: on the demo (rooms with clear walls) at most three per region and the
    # outdoors; more and rendering pays for it in portal crossings (docs/room-finding.md, "Render time").
    if preset == "demo" and figures["cells"] > 3 * (figures["regions"] + 1):
        failures.append(f"{figures['cells']} cells for {figures['regions']} regions and the outdoors")
    if figures["rooms_found"] < 0.95 * figures["generated_rooms"]:
        failures.append(f"only {figures['rooms_found']} of {figures['generated_rooms']} rooms found as one region")
    if figures["openings_found"] < 0.95 * figures["openings"]:
        failures.append(f"only {figures['openings_found']} of {figures['openings']} doors and windows found as portals")

    if preset == "demo":
        # The same mesh in one cell: the light must not change with the cells.
        one = str(work / "one")
        subprocess.run([portico, "scene", "import", str(work / "building.obj"), one], check=True,
                       stdout=subprocess.DEVNULL)
        camera = json.loads(subprocess.run([portico, "scene", "info", "--json", "--quick", generated], check=True,
                                           capture_output=True, text=True).stdout)["cameras"][1]
        views = work / "views.json"
        views.write_text(json.dumps([{"name": "v", "look_from": camera["origin"], "look_at": camera["look_at"],
                                      "fov": camera["fov"], "width": 120, "height": 80}]))
        means = {}
        for name, store in (("rooms", rooms), ("one", one)):
            out = work / f"{name}"
            subprocess.run([portico, "render", store, "--views", str(views), "--photons", "200000", "--spp", "4",
                            "--workers", "2", "-o", str(out)], check=True, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
            line = subprocess.run([f"{bin_dir}/portico-compare", str(out / "v.exr"), str(out / "v.exr")],
                                  capture_output=True, text=True).stdout
            means[name] = float(line.split()[2])
        off = abs(means["rooms"] / means["one"] - 1)
        print(f"image mean: rooms {means['rooms']:.5f}, one cell {means['one']:.5f}: {100 * off:.2f} % apart")
        # Bound: the finder's cells change where photons are gathered, not the light; 5 % covers the density
        # estimates' bias at box faces measured on the demo (3.6 %).
        if off > 0.05:
            failures.append(f"the rooms' image mean is {100 * off:.2f} % off the one-cell import's")
    # Not a building: one closed 1 m cube.
    cube = work / "cube.obj"
    cube.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                    "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\n"
                    "f 4 1 5\nf 4 5 8\n")
    result = subprocess.run([portico, "scene", "import", "--cells", "rooms", str(cube), str(work / "cube")],
                            capture_output=True, text=True, timeout=60)
    lines = result.stderr.strip().splitlines()
    print(f"cube: exit {result.returncode}: {lines}")
    if result.returncode != 1 or len(lines) != 1 or "no rooms found in" not in lines[0] or "--grid" not in lines[0] \
            or (work / "cube").exists():
        failures.append(f"the cube did not fail with one line: exit {result.returncode}, {lines}")
    for failure in failures:
        print(f"FAIL: {failure}")
    shutil.rmtree(work)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
