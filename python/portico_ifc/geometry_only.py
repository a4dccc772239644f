"""A model whose IfcSpaces give no cells, converted as geometry only.

Cells follow spaces (cell_partition.py); a model without IfcSpace (or whose
spaces are all too thin to hold a cell) has none to follow. It is written
as a building.json without "cells": the elements' surfaces with their
materials, windows' and curtain walls' glass as one glass pane each (on its
glass's middle plane, closing its hole as the window does), lamps under its
light fixtures where it has some, and an overview camera. conversion.json
says "find_rooms": `portico scene import` then finds the rooms in this
geometry (common/scene/import/room_cells.h) and gives each a camera and,
where "lamps" is true, a ceiling panel. Door leaves are left out as in
spaces' conversion: a doorway is an open hole, narrower than a room, so
the room finder separates the rooms either side of it and its portals pass
light through it. The doors', windows' and voids' hole boxes are kept in
conversion.json for the watertightness check.
"""

import json
import os
import time

import numpy as np

from .glazing import panes_on_glass
from .lights_cameras import fixture_lamps
from .output_files import rounded, site_json, slug, write_obj

OVERVIEW_DISTANCE = 1.0   # metres in front of the building's -z face: inside the room finder's padding


def _overview_camera(lo, hi):
    centre = (lo + hi) / 2
    origin = np.array([centre[0], centre[1], lo[2] - OVERVIEW_DISTANCE])
    return {"name": "overview", "origin": [float(x) for x in origin], "target": [float(x) for x in centre],
            "up": [0, 1, 0], "fov_y_deg": 70, "width": 512, "height": 384}


def convert_geometry_only(model, ifc_path, out_dir, lights, glazing, reason, started, read_seconds):
    """Writes OUT_DIR/building.json, meshes/ and conversion.json; returns the summary."""
    os.makedirs(os.path.join(out_dir, "meshes"), exist_ok=True)
    objects = []
    corners = np.concatenate([e.mesh.corners() for e in model.elements]) if model.elements else np.zeros((0, 3, 3))
    material = (np.concatenate([e.material_of_triangle for e in model.elements]) if model.elements
                else np.zeros(0, dtype=np.int64))
    for m in np.unique(material):
        path = os.path.join("meshes", f"{m:03d}-{slug(model.materials[m][0])}.obj")
        write_obj(os.path.join(out_dir, path), corners[material == m])
        objects.append({"obj": path, "name": f"{slug(model.materials[m][0])}-{m}", "albedo": list(model.materials[m][1])})
    panes, paneless = panes_on_glass(model.glazings, model.openings)
    tint = sorted({p.transmittance for p in panes})
    for t, transmittance in enumerate(tint):
        path = os.path.join("meshes", f"glass-{t:02d}.obj")
        write_obj(os.path.join(out_dir, path),
                  [p.corners[k] for p in panes if p.transmittance == transmittance for k in ([0, 1, 2], [0, 2, 3])])
        objects.append({"obj": path, "name": f"glass-{t}", "glass": {"transmittance": list(transmittance), "ior": 1.5}})
    fixtures = lights in ("auto", "fixtures") and model.fixtures
    lamps = fixture_lamps(model.fixtures) if fixtures else []
    for i, lamp in enumerate(lamps):
        path = os.path.join("meshes", f"lamp-{i:04d}.obj")
        q = np.array(lamp["quad"])
        write_obj(os.path.join(out_dir, path), [q[[0, 1, 2]], q[[0, 2, 3]]])
        objects.append({"obj": path, "name": lamp["name"], "albedo": [0, 0, 0], "lumens": lamp["lumens"],
                        "colour_temperature": lamp["colour_temperature"]})
    room_lamps = lights == "panels" or (lights == "auto" and not model.fixtures)
    if len(corners):
        lo, hi = corners.reshape(-1, 3).min(axis=0), corners.reshape(-1, 3).max(axis=0)
    else:
        lo, hi = np.zeros(3), np.ones(3)
    building = {"name": model.name or os.path.splitext(os.path.basename(ifc_path))[0], "units": "metres",
                "_source": os.path.basename(ifc_path), "objects": objects, "cameras": [_overview_camera(lo, hi)]}
    if model.site is not None:
        building["site"] = site_json(model.site)
    with open(os.path.join(out_dir, "building.json"), "w") as f:
        json.dump(building, f, indent=1)

    openings = [{"kind": o.kind, "name": o.name, "sides": None, "portal": None, "between_two_regions": None,
                 "lo": rounded(o.lo), "hi": rounded(o.hi), "glass": None} for o in model.openings]
    curtain = {g.name for g in model.glazings if g.curtain}
    summary = {
        "schema": model.schema,
        "unit_scale": model.unit_scale,
        "spaces": len(model.spaces),
        "cells_from": "rooms found",
        "doors": sum(1 for o in openings if o["kind"] == "door"),
        "windows": sum(1 for o in openings if o["kind"] == "window"),
        "openings_without_filling": len(model.unfilled_openings),
        "glazing": glazing,
        "windows_glazed": sum(1 for p in panes if not p.curtain),
        "windows_without_glass": len(model.unglazed_windows),
        "windows_glass_unplaced": sum(1 for name in paneless if name not in curtain),
        "curtain_plates_glazed": sum(1 for p in panes if p.curtain),
        "curtain_plates_unplaced": sum(1 for name in paneless if name in curtain),
        "glass_objects": len(tint),
        "outdoors": "open",
        "site": building.get("site"),
        "light_fixtures": len(model.fixtures),
        "lights": len(lamps),
        "light_source": "fixtures" if lamps else "room panels" if room_lamps else "none",
        "cameras": 1,
        "materials": len(model.materials),
        "elements": len(model.elements),
        "read_seconds": round(read_seconds, 2),
        "seconds": round(time.time() - started, 2),
    }
    with open(os.path.join(out_dir, "conversion.json"), "w") as f:
        json.dump({"summary": summary, "find_rooms": {"reason": reason, "lamps": room_lamps},
                   "openings": openings, "spaces": [], "closed_spaces": [],
                   "openings_without_filling": [{"name": o.name, "lo": rounded(o.lo), "hi": rounded(o.hi)}
                                                for o in model.unfilled_openings]}, f, indent=1)
    return summary
