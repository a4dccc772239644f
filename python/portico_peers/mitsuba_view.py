"""A store view (store_view.py) rendered by Mitsuba 3's path tracer.

Generated buildings' walls face away from the rooms in places and portico
shades both sides of every surface, so each diffuse material is Mitsuba's
`twosided` diffuse; lights emit on their front only, as portico's do.
Pinhole camera, box pixel filter, unbounded path depth.
"""
import os

from portico_mitsuba.ladder import render_ladder
from portico_mitsuba.scene import base_dict


def scene_dict(mi, view_dir, view, spp, max_depth=-1):
    cam = view["camera"]
    d = base_dict(mi, cam["origin"], cam["look_at"], cam["up"], cam["fov_y_deg"], cam["width"], cam["height"], spp,
                  max_depth)
    for i, m in enumerate(view["materials"]):
        shape = {"type": "ply", "filename": os.path.join(view_dir, m["ply"]), "face_normals": True,
                 "bsdf": {"type": "twosided",
                          "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": m["albedo"]}}}}
        if m["emission"]:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": m["emission"]}}
        d[f"shape_{i:02d}"] = shape
    return d


def render(view_dir, view, counts, threads, variant="llvm_ad_rgb", max_depth=-1, out=print):
    render_ladder(lambda mi, spp: scene_dict(mi, view_dir, view, spp, max_depth), counts, threads, variant, view_dir,
                  out)
