"""Watertightness of a converted building (docs/ifc-corpus.md).

    python -m portico_ifc.watertight OUT_DIR [--rays-per-space 64] [--seed 1]

OUT_DIR is what `python -m portico_ifc model.ifc OUT_DIR` wrote (building.json,
meshes/, conversion.json), converted with the outdoors open; for a model
whose rooms were found in its geometry, what `portico scene import
--keep-conversion OUT_DIR model.ifc STORE` kept (conversion.json then lists
the rooms' air). From random points inside every space (or found room), rays in random directions (a fixed seed:
same model, same figures) must hit a surface of the building, or leave it
through an opening: the box of a door's or window's hole, or of a void that
nothing fills. A ray that meets neither leaves the building through a hole in
its shell (a missing floor, a ceiling that stops short): a leak. Prints one
line of JSON: rays, hits, through openings, leaks and the leak share, the
leakiest spaces (or rooms) and the worst one's own share; for rooms found,
also the rays from the outdoor air the building shelters (over a floor and
under a ceiling, as wide as a room: where a room that lost a whole wall
went, and verandas and loggias), which leak there.
"""

import argparse
import json
import os
import sys

import numpy as np

from .ifc_model import Mesh
from .solid_queries import inside_mesh, nearest_hits



def read_obj_triangles(path):
    """(m, 3, 3) triangles of an OBJ file written by the converter (v and f lines)."""
    vertices, faces = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vertices.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                faces.append([int(x.split("/")[0]) - 1 for x in line.split()[1:4]])
    if not faces:
        return np.zeros((0, 3, 3))
    return np.asarray(vertices)[np.asarray(faces)]


def _box_entries(origins, directions, lo, hi):
    """(n, boxes) distance at which each ray enters each box (0 inside), inf if it misses."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / directions
        t0 = (lo[None] - origins[:, None]) * inv[:, None]
        t1 = (hi[None] - origins[:, None]) * inv[:, None]
    near = np.nan_to_num(np.minimum(t0, t1), nan=-np.inf).max(axis=2)
    far = np.nan_to_num(np.maximum(t0, t1), nan=np.inf).min(axis=2)
    return np.where((far >= np.maximum(near, 0.0)), np.maximum(near, 0.0), np.inf)


def space_rays(space_meshes, rays_per_space, seed):
    """Origins and directions: `rays_per_space` for every space, from points
    drawn uniformly inside its solid (rejection sampling in its box: a cell
    box under a sloping roof reaches above it), directions uniform on the
    sphere. Spaces in their order; a space too thin to hit gets none."""
    rng = np.random.Generator(np.random.PCG64(seed))
    origins, names = [], []
    for name, mesh in space_meshes:
        lo, hi = mesh.bounds()
        found = np.zeros((0, 3))
        for _ in range(20):
            candidates = lo + rng.random((rays_per_space * 4, 3)) * (hi - lo)
            found = np.concatenate([found, candidates[inside_mesh(candidates, mesh)]])
            if len(found) >= rays_per_space:
                break
        found = found[:rays_per_space]
        origins.append(found)
        names += [name] * len(found)
    if not names:
        return np.zeros((0, 3)), np.zeros((0, 3)), []
    directions = rng.normal(size=(len(names), 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    return np.concatenate(origins), directions, names


def room_rays(found_rooms, rays_per_space, seed):
    """As space_rays, for rooms found in the geometry (a model without
    usable IfcSpace): points drawn uniformly in voxels drawn from each room's
    air samples (voxels its core reached: free of any surface, not inside a
    wall), directions uniform on the sphere."""
    rng = np.random.Generator(np.random.PCG64(seed))
    origins, names = [], []
    for room in found_rooms:
        corners = np.asarray(room["samples"], dtype=np.float64).reshape(-1, 3)
        if not len(corners):
            continue
        picked = corners[rng.integers(0, len(corners), rays_per_space)]
        origins.append(picked + rng.random((rays_per_space, 3)) * room["voxel"])
        names += [room["name"]] * rays_per_space
    if not names:
        return np.zeros((0, 3)), np.zeros((0, 3)), []
    directions = rng.normal(size=(len(names), 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    return np.concatenate(origins), directions, names


def _mesh_of(path):
    corners = read_obj_triangles(path)
    return Mesh(corners.reshape(-1, 3), np.arange(len(corners) * 3).reshape(-1, 3))


def _escapes(origins, directions, corners, holes):
    """(escaped, through an opening) per ray."""
    hit = nearest_hits(origins, directions, corners) if len(corners) else np.full(len(origins), np.inf)
    if holes:
        lo = np.array([h["lo"] for h in holes]) - 0.01
        hi = np.array([h["hi"] for h in holes]) + 0.01
        through = (_box_entries(origins, directions, lo, hi) < hit[:, None]).any(axis=1)
    else:
        through = np.zeros(len(origins), dtype=bool)
    return ~np.isfinite(hit), through


def _sheltered(conversion, corners, holes, rays_per_space, seed):
    """Rays from the outdoor air the building shelters (rooms found only):
    reported beside the rooms' figures, not in them. A room that lost a wall
    wider than an opening is there, but so are a veranda and a loggia, which
    geometry alone cannot tell from it."""
    pockets = conversion.get("sheltered_outdoors")
    if pockets is None:
        return {}
    origins, directions, names = room_rays(pockets, rays_per_space, seed)
    escaped, through = _escapes(origins, directions, corners, holes)
    return {"sheltered_outdoors": len(pockets), "sheltered_m3": round(sum(p["air_m3"] for p in pockets), 1),
            "sheltered_rays": len(names), "sheltered_leaks": int((escaped & ~through).sum())}


def check(out_dir, rays_per_space=64, seed=1):
    building = json.load(open(os.path.join(out_dir, "building.json")))
    conversion = json.load(open(os.path.join(out_dir, "conversion.json")))
    corners = [read_obj_triangles(os.path.join(out_dir, o["obj"])) for o in building["objects"]]
    corners = np.concatenate(corners) if corners else np.zeros((0, 3, 3))
    holes = conversion.get("openings", []) + conversion.get("openings_without_filling", [])
    if "found_rooms" in conversion:
        origins, directions, spaces = room_rays(conversion["found_rooms"], rays_per_space, seed)
    else:
        space_meshes = [(s["name"], _mesh_of(os.path.join(out_dir, s["obj"]))) for s in conversion.get("spaces", [])]
        origins, directions, spaces = space_rays(space_meshes, rays_per_space, seed)
    escaped, through = _escapes(origins, directions, corners, holes)
    leak = escaped & ~through
    leaky_spaces = sorted({s for s, l in zip(spaces, leak) if l})
    rays = len(origins)
    # Per space (or room): one room with a wall missing among many barely moves the whole share.
    drawn, leaked = {}, {}
    for s, l in zip(spaces, leak):
        drawn[s] = drawn.get(s, 0) + 1
        leaked[s] = leaked.get(s, 0) + int(l)
    leakiest = sorted(leaky_spaces, key=lambda s: (-leaked[s] / drawn[s], s))
    return {"rays": rays, "from": "rooms found" if "found_rooms" in conversion else "spaces",
            "hit": int((~escaped).sum()), "through_openings": int((escaped & through).sum()),
            "leaks": int(leak.sum()), "leak_share": round(float(leak.sum()) / rays, 5) if rays else None,
            "spaces": len(set(spaces)), "leaky_spaces": len(leaky_spaces), "leakiest": leakiest[:5],
            **_sheltered(conversion, corners, holes, rays_per_space, seed),
            "worst_space_share": round(leaked[leakiest[0]] / drawn[leakiest[0]], 5) if leakiest else 0.0,
            "triangles": len(corners), "seed": seed, "rays_per_space": rays_per_space}


def main(argv=None):
    parser = argparse.ArgumentParser(prog="portico_ifc.watertight", description=__doc__.split("\n\n")[0])
    parser.add_argument("out_dir")
    parser.add_argument("--rays-per-space", type=int, default=64)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    for name in ("building.json", "conversion.json"):
        if not os.path.isfile(os.path.join(args.out_dir, name)):
            print(f"{args.out_dir}: no {name} (convert the model first: python -m portico_ifc model.ifc OUT_DIR, "
                  "or portico scene import --keep-conversion OUT_DIR model.ifc STORE)",
                  file=sys.stderr)
            return 2
    print(json.dumps(check(args.out_dir, args.rays_per_space, args.seed)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
