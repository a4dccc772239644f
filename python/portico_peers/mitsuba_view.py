"""A store view (store_view.py) rendered by Mitsuba 3's path tracer.

Generated buildings' walls face away from the rooms in places and portico
shades both sides of every surface, so each diffuse material is Mitsuba's
`twosided` diffuse; lights emit on their front only, as portico's do.
Pinhole camera, box pixel filter, unbounded path depth.
"""
import os

from portico_mitsuba.scene import base_dict

# Debian's libLLVM, for Dr.Jit's LLVM variants (DRJIT_LIBLLVM_PATH wins).
DEBIAN_LIBLLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"


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
    import time

    if not os.environ.get("DRJIT_LIBLLVM_PATH") and os.path.exists(DEBIAN_LIBLLVM):
        os.environ["DRJIT_LIBLLVM_PATH"] = DEBIAN_LIBLLVM
    import numpy as np
    import mitsuba as mi
    mi.set_variant(variant)
    import drjit as dr
    dr.set_thread_count(threads)
    out("spp,seconds,image")
    scene = None
    for spp in counts:
        scene = mi.load_dict(scene_dict(mi, view_dir, view, spp, max_depth))
        if spp == counts[0]:  # the first render compiles the kernels: not counted
            dr.eval(mi.render(scene, spp=1, seed=999))
        started = time.perf_counter()
        pixels = np.array(mi.render(scene, spp=spp, seed=spp), dtype=np.float32)[..., :3]
        seconds = time.perf_counter() - started
        path = os.path.join(view_dir, f"mitsuba-{spp}.exr")
        mi.Bitmap(pixels, pixel_format=mi.Bitmap.PixelFormat.RGB).write(path)
        out(f"{spp},{seconds:.3f},{path}")
