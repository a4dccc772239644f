"""IFC model -> building.json + one OBJ per (cell, material) (docs/importing-buildings.md).

    python -m portico_ifc model.ifc OUTDIR [--lights auto|fixtures|panels|none] [--no-glazing] [--outdoors open|closed]
        [--cells spaces|rooms]

Writes OUTDIR/building.json and OUTDIR/meshes/*.obj, and prints a summary
(JSON) of what was found: spaces, cells, portals, doors and windows with a
portal, glazed windows, lamps, cameras. A model whose IfcSpaces give no
cells is written as geometry only, for the room finder (geometry_only.py).
"""

import argparse
import json
import os
import sys
import time

import numpy as np
import ifcopenshell

from . import cell_partition as cp
from .clip import distribute
from .geometry_only import convert_geometry_only
from .closing import CLOSING_ALBEDO, CLOSING_MATERIAL, close_spaces
from .glazing import outdoor_cells, window_panes
from .ifc_model import read_ifc
from .lights_cameras import fixture_lamps, space_cameras, space_panels
from .output_files import rounded as _rounded, site_json as _site_json, slug as _slug, write_obj as _write_obj

MARGIN = 2.0        # metres of outside air around the building
SKY_INSET = 0.05    # metres: the black enclosure lies this far inside the outer cell faces
SKY_ALBEDO = (0.0, 0.0, 0.0)
GROUND_ALBEDO = (0.25, 0.25, 0.25)


def _enclosure(lo, hi):
    """The box from lo to hi as inward-facing triangles: ground (bottom) and sky."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    quads = {
        "ground": [(x0, y0, z0), (x0, y0, z1), (x1, y0, z1), (x1, y0, z0)],
        "sky": [[(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)],
                [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)],
                [(x0, y0, z1), (x0, y1, z1), (x1, y1, z1), (x1, y0, z1)],
                [(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)],
                [(x1, y0, z0), (x1, y0, z1), (x1, y1, z1), (x1, y1, z0)]],
    }

    def triangles(quad):
        q = np.array(quad, dtype=np.float64)
        return [q[[0, 1, 2]], q[[0, 2, 3]]]

    ground = np.array(triangles(quads["ground"]))
    sky = np.array([t for quad in quads["sky"] for t in triangles(quad)])
    return ground, sky


def _cell_names(cells, spaces, outdoor=()):
    names, seen = [], {}
    for i, c in enumerate(cells):
        base = f"space-{_slug(spaces[c.label].name)}" if c.label != cp.AIR else "outside" if i in outdoor else "air"
        seen[base] = seen.get(base, 0) + 1
        names.append(base)
    counts = {}
    result = []
    for n in names:
        counts[n] = counts.get(n, 0) + 1
        result.append(n if seen[n] == 1 else f"{n}-{counts[n]}")
    return result


def _joined_through(start, end, axis, portals_between, lines, cell_of_point):
    """Whether portals join the cells of two points on one line along `axis`:
    every face between two cells on the way is crossed by a portal there."""
    u, v = [a for a in range(3) if a != axis]
    lo, hi = sorted((start[axis], end[axis]))
    stops = np.concatenate([[lo], lines[axis][(lines[axis] > lo) & (lines[axis] < hi)], [hi]])
    path = []
    for x in (stops[:-1] + stops[1:]) / 2:
        p = start.copy()
        p[axis] = x
        path.append(cell_of_point(p))
    if None in path or path[0] == path[-1]:
        return False
    for a, b, plane in zip(path[:-1], path[1:], stops[1:-1]):
        if a != b and not any(abs(p.plane - plane) < 1e-9 and
                              all(p.lo[w] - 1e-3 <= start[w] <= p.hi[w] + 1e-3 for w in (u, v))
                              for p in portals_between.get((min(a, b), max(a, b), axis), ())):
            return False
    return True


def _match_openings(openings, portals, cells, lines, cell_of_point):
    """For each door and window: the cells either side of it and whether
    portals join them through the hole, on the line through its centre
    across its wall or roof. The faces crossed need not lie within the
    hole's depth: a wall that falls wholly between two grid lines lies in a
    thin air cell with a portal on either side of it."""
    portals_between = {}
    for p in portals:
        portals_between.setdefault((min(p.cell_a, p.cell_b), max(p.cell_a, p.cell_b), p.axis), []).append(p)
    found = []
    for o in openings:
        axis = o.across
        centre = (o.lo + o.hi) / 2
        ends = []
        for sign in (-1, 1):
            p = centre.copy()
            p[axis] += sign * ((o.hi[axis] - o.lo[axis]) / 2 + 0.3)
            ends.append(p)
        sides = [cell_of_point(p) for p in ends]
        labels = [cells[s].label if s is not None else None for s in sides]
        joined = _joined_through(ends[0], ends[1], axis, portals_between, lines, cell_of_point)
        found.append({"kind": o.kind, "name": o.name, "sides": labels,
                      "portal": joined, "between_two_regions": labels[0] != labels[1],
                      "lo": _rounded(o.lo), "hi": _rounded(o.hi)})
    return found


def _pane_objects(panes, lines, owner, cells, names, out_dir):
    """Panes as glass objects: one OBJ per (cell, transmittance)."""
    if not panes:
        return []
    corners = np.concatenate([p.corners[[[0, 1, 2], [0, 2, 3]]] for p in panes])
    tint = sorted({p.transmittance for p in panes})
    of_triangle = np.repeat([tint.index(p.transmittance) for p in panes], 2)
    objects = []
    for c, triangles, source in distribute(corners, lines, owner, cells):
        for t in np.unique(of_triangle[source]):
            path = os.path.join("meshes", f"{c:04d}-glass-{t:02d}.obj")
            _write_obj(os.path.join(out_dir, path), triangles[of_triangle[source] == t])
            objects.append({"obj": path, "name": f"{names[c]}-glass-{t}", "cell": names[c],
                            "glass": {"transmittance": list(tint[t]), "ior": 1.5}})
    return objects


def _glazing_summary(glazing, model, panes, paneless, objects, openings):
    """Counts of glazed windows for the summary; sets each window's "glass" in `openings`."""
    glass_of = {p.window: list(p.transmittance) for p in panes if not p.curtain}
    for o in openings:
        if o["kind"] == "window":
            o["glass"] = glass_of.get(o["name"])
    curtain = {g.name for g in model.glazings if g.curtain}
    return {"glazing": glazing,
            "windows_glazed": sum(1 for p in panes if not p.curtain),
            "windows_at_opening": sum(1 for p in panes if p.at_opening and not p.curtain),
            "windows_without_glass": len(model.unglazed_windows),
            "windows_glass_unplaced": sum(1 for name in paneless if name not in curtain),
            "curtain_plates_glazed": sum(1 for p in panes if p.curtain),
            "curtain_plates_unplaced": sum(1 for name in paneless if name in curtain),
            "glass_objects": sum(1 for o in objects if "glass" in o)}


def convert(ifc_path, out_dir, lights="auto", glazing=True, outdoors="open", closing=True, cells="spaces"):
    started = time.time()
    model = read_ifc(ifc_path, glazing)
    read_seconds = time.time() - started

    def geometry_only(reason):
        if not model.elements:
            raise SystemExit(f"{ifc_path}: {reason}, and no element with geometry either: nothing to import")
        return convert_geometry_only(model, ifc_path, out_dir, lights, glazing, reason, started, read_seconds)

    if cells == "rooms":
        return geometry_only("rooms asked for (--cells rooms)")
    if not model.spaces:
        return geometry_only("no IfcSpace with geometry")
    every = np.concatenate([e.mesh.vertices for e in model.elements] + [s.mesh.vertices for s in model.spaces])
    building_lo, building_hi = every.min(axis=0), every.max(axis=0)
    outer_lo = building_lo - np.array([MARGIN, SKY_INSET * 2, MARGIN])
    outer_hi = building_hi + MARGIN

    holes = [(o.lo, o.hi) for o in model.openings + model.unfilled_openings]
    # Glass bounds a room too: curtain walls' plates and windows' glass.
    bounding = [e.mesh for e in model.elements if e.sealing] + [g.glass for g in model.glazings]
    closings, closing_areas = close_spaces(model.spaces, bounding, holes) if closing else ([], [])
    lines = cp.grid_lines(model.spaces, outer_lo, outer_hi, [e.mesh for e in model.elements])
    labels = cp.label_boxes(lines, model.spaces)
    cells, owner = cp.merge_boxes(labels, lines)
    if all(c.label == cp.AIR for c in cells):
        return geometry_only(f"none of its {len(model.spaces)} IfcSpaces holds the centre of a grid box "
                             "(all thinner than the grid between them)")
    sealers = [(e.mesh, e.mesh.bounds()) for e in model.elements if e.sealing]
    portals = cp.find_portals(cells, owner, lines, sealers)

    def cell_of_point(p):
        idx = [int(np.searchsorted(lines[a], p[a], side="right")) - 1 for a in range(3)]
        if any(i < 0 or i >= len(lines[a]) - 1 for a, i in enumerate(idx)):
            return None
        return int(owner[tuple(idx)])

    if lights == "none":
        lamps = []
    elif lights == "fixtures" or (lights == "auto" and model.fixtures):
        lamps = fixture_lamps(model.fixtures, cells, cell_of_point)
    else:
        lamps = space_panels(model.spaces, cells)
    cameras = space_cameras(model.spaces, cells)
    seen = {}
    for cam in cameras:
        seen[cam["name"]] = seen.get(cam["name"], 0) + 1
        if seen[cam["name"]] > 1:
            cam["name"] = f"{cam['name']} ({seen[cam['name']]})"
    outdoor = outdoor_cells(cells, portals, outer_lo, outer_hi)
    names = _cell_names(cells, model.spaces, outdoor if outdoors == "open" else ())
    panes, paneless = window_panes(model.glazings, model.openings, cells, outdoor, portals, lines, cell_of_point)

    os.makedirs(os.path.join(out_dir, "meshes"), exist_ok=True)
    objects = []
    groups = [(e.mesh.corners(), e.material_of_triangle) for e in model.elements]
    material_names = [m[0] for m in model.materials] + ["ground", "sky", CLOSING_MATERIAL]
    material_albedo = [m[1] for m in model.materials] + [GROUND_ALBEDO, SKY_ALBEDO, CLOSING_ALBEDO]
    closing_triangles = np.concatenate(closings) if closings else np.zeros((0, 3, 3))
    if len(closing_triangles):
        groups.append((closing_triangles, np.full(len(closing_triangles), len(model.materials) + 2)))
    if outdoors == "closed":
        ground, sky = _enclosure(outer_lo + SKY_INSET, outer_hi - SKY_INSET)
        groups.append((ground, np.full(len(ground), len(model.materials))))
        groups.append((sky, np.full(len(sky), len(model.materials) + 1)))
    corners = np.concatenate([g[0] for g in groups])
    material = np.concatenate([g[1] for g in groups])
    for c, triangles, source in distribute(corners, lines, owner, cells):
        for m in np.unique(material[source]):
            name = f"{names[c]}-{_slug(material_names[m])}-{m}"
            path = os.path.join("meshes", f"{c:04d}-{m:03d}.obj")
            _write_obj(os.path.join(out_dir, path), triangles[material[source] == m])
            objects.append({"obj": path, "name": name, "cell": names[c], "albedo": list(material_albedo[m])})
    objects += _pane_objects(panes, lines, owner, cells, names, out_dir)
    for i, lamp in enumerate(lamps):
        path = os.path.join("meshes", f"lamp-{i:04d}.obj")
        q = np.array(lamp["quad"])
        _write_obj(os.path.join(out_dir, path), [q[[0, 1, 2]], q[[0, 2, 3]]])
        photometric = {key: lamp[key] for key in ("lumens", "colour", "colour_temperature") if key in lamp}
        objects.append({"obj": path, "name": lamp["name"], "cell": names[lamp["cell"]], "albedo": [0, 0, 0],
                        **photometric})

    def rectangle(p):
        u, v = [a for a in range(3) if a != p.axis]
        corners = []
        for cu, cv in ((p.lo[u], p.lo[v]), (p.hi[u], p.lo[v]), (p.hi[u], p.hi[v]), (p.lo[u], p.hi[v])):
            q = [0.0, 0.0, 0.0]
            q[p.axis], q[u], q[v] = float(p.plane), float(cu), float(cv)
            corners.append(q)
        return corners

    building = {
        "name": model.name or os.path.splitext(os.path.basename(ifc_path))[0],
        "units": "metres",
        "_source": os.path.basename(ifc_path),
        "cells": [{"name": names[i], "aabb": {"min": c.lo.tolist(), "max": c.hi.tolist()}} for i, c in enumerate(cells)],
        "portals": [{"between": [names[p.cell_a], names[p.cell_b]], "polygon": rectangle(p)} for p in portals],
        "objects": objects,
        "cameras": cameras,
    }
    if model.site is not None:
        building["site"] = _site_json(model.site)
    with open(os.path.join(out_dir, "building.json"), "w") as f:
        json.dump(building, f, indent=1)

    # The spaces' own solids, for checks that need points inside a space
    # (python -m portico_ifc.watertight); not part of the scene.
    os.makedirs(os.path.join(out_dir, "spaces"), exist_ok=True)
    space_files = []
    for i, space in enumerate(model.spaces):
        path = os.path.join("spaces", f"{i:04d}.obj")
        _write_obj(os.path.join(out_dir, path), space.mesh.corners())
        space_files.append({"name": space.name, "obj": path})
    openings = _match_openings(model.openings, portals, cells, lines, cell_of_point)
    summary = {
        "schema": model.schema,
        "unit_scale": model.unit_scale,
        "spaces": len(model.spaces),
        "space_cells": sum(1 for c in cells if c.label != cp.AIR),
        "air_cells": sum(1 for c in cells if c.label == cp.AIR),
        "cells": len(cells),
        "portals": len(portals),
        "connected_components": cp.connected_components(len(cells), portals),
        "spaces_with_cells": len({c.label for c in cells if c.label != cp.AIR}),
        "doors": sum(1 for o in openings if o["kind"] == "door"),
        "windows": sum(1 for o in openings if o["kind"] == "window"),
        "doors_with_portal": sum(1 for o in openings if o["kind"] == "door" and o["portal"]),
        "windows_with_portal": sum(1 for o in openings if o["kind"] == "window" and o["portal"]),
        "openings_without_filling": len(model.unfilled_openings),
        "closing": closing,
        "spaces_closed": sum(1 for a in closing_areas if a > 0),
        "closing_m2": round(sum(closing_areas), 2),
        **_glazing_summary(glazing, model, panes, paneless, objects, openings),
        "outdoors": outdoors,
        "outdoor_cells": len(outdoor),
        "site": building.get("site"),
        "light_fixtures": len(model.fixtures),
        "lights": len(lamps),
        "light_source": "none" if lights == "none" else "fixtures" if lamps and lamps[0]["name"].startswith("fixture") else "space panels",
        "cameras": len(cameras),
        "materials": len(model.materials),
        "elements": len(model.elements),
        "read_seconds": round(read_seconds, 2),
        "seconds": round(time.time() - started, 2),
    }
    with open(os.path.join(out_dir, "conversion.json"), "w") as f:
        closed = [{"space": sp.name, "m2": round(a, 2)} for sp, a in zip(model.spaces, closing_areas) if a > 0]
        json.dump({"summary": summary, "openings": openings, "spaces": space_files, "closed_spaces": closed,
                   "openings_without_filling": [{"name": o.name, "lo": _rounded(o.lo), "hi": _rounded(o.hi)}
                                                for o in model.unfilled_openings]}, f, indent=1)
    return summary


def main(argv=None):
    parser = argparse.ArgumentParser(prog="portico_ifc", description=__doc__.split("\n\n")[0])
    parser.add_argument("ifc")
    parser.add_argument("out_dir")
    parser.add_argument("--lights", choices=("auto", "fixtures", "panels", "none"), default="auto",
                        help="auto: light fixtures where the model has some, else one ceiling panel per space; "
                             "none: no lamps (daylight only)")
    parser.add_argument("--no-glazing", dest="glazing", action="store_false",
                        help="leave windows out, their holes open (default: their glass becomes thin panes)")
    parser.add_argument("--outdoors", choices=("open", "closed"), default="open",
                        help="open: the air around the building is outdoors (cells outside-N), for daylight; "
                             "closed: black sky and grey ground boxes close the scene")
    parser.add_argument("--no-closing", dest="closing", action="store_false",
                        help="leave the faces of spaces that no wall, slab, roof or covering bounds open "
                             "(default: close them with the space's own faces)")
    parser.add_argument("--cells", choices=("spaces", "rooms"), default="spaces",
                        help="spaces: cells follow the IfcSpaces (a model without usable ones is written as "
                             "geometry only, for the room finder); rooms: geometry only whatever the model has")
    args = parser.parse_args(argv)
    if not os.path.isfile(args.ifc):
        print(f"{args.ifc}: does not exist", file=sys.stderr)
        return 2
    try:
        summary = convert(args.ifc, args.out_dir, args.lights, args.glazing, args.outdoors, args.closing, args.cells)
    except (RuntimeError, ifcopenshell.Error) as error:       # IfcOpenShell's parse errors
        print(f"{args.ifc}: not a readable IFC model: {error}", file=sys.stderr)
        return 1
    print(json.dumps(summary))
    return 0
