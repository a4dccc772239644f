#!/usr/bin/env python3
"""Writes tiles.png and renders reference.exr for the textured_floor scene.

The room of cornell_closed without its boxes, its floor textured with
tiles.png: 4 x 4 tiles of 8 x 8 pixels, each its own colour (so a flipped
or mirrored lookup shows), repeated 1.5 times each way across the floor
(floor.obj's uvs). Rendered by Mitsuba 3.9.1 (llvm_ad_rgb, `path`,
unbounded depth) with the floor's BSDF a `diffuse` whose reflectance is a
`bitmap` texture: bilinear filtering, repeat wrapping, the PNG's sRGB values
linearised, no MIP-mapping -- what portico does. The OBJ loader flips v, as
OBJ files mean (v = 0 is the image's bottom row).

Usage (from this folder, about 2 minutes on 2 threads):
  DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 \
    nice ~/.local/share/portico/mitsuba-venv/bin/python render_reference.py [--spp 4096] [--threads 2]
"""
import argparse, json, os, sys
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
# The scene as `portico bench quality --mitsuba` renders it (python/portico_mitsuba).
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", "python"))
from portico_mitsuba.scene import scene_dict  # noqa: E402

# sRGB bytes of the 4 x 4 tiles, row 0 at the image's top.
PALETTE = [
    [(200, 60, 40), (235, 235, 225), (60, 90, 170), (235, 235, 225)],
    [(235, 235, 225), (40, 40, 40), (235, 235, 225), (220, 180, 60)],
    [(90, 160, 80), (235, 235, 225), (130, 70, 140), (235, 235, 225)],
    [(235, 235, 225), (170, 120, 80), (235, 235, 225), (20, 120, 130)],
]


def tiles_image():
    image = np.zeros((32, 32, 3), dtype=np.uint8)
    for row in range(4):
        for col in range(4):
            image[8 * row:8 * row + 8, 8 * col:8 * col + 8] = PALETTE[row][col]
    return image


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=4096)
    ap.add_argument("--pass-spp", type=int, default=256)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    import drjit as dr
    dr.set_thread_count(a.threads)
    mi.Bitmap(tiles_image()).write(os.path.join(HERE, "tiles.png"))
    sc = json.load(open(os.path.join(HERE, "scene.json")))
    scene = mi.load_dict(scene_dict(mi, HERE, sc, a.pass_spp))
    passes = max(1, a.spp // a.pass_spp)
    total = None
    for p in range(passes):
        img = np.array(mi.render(scene, spp=a.pass_spp, seed=p), dtype=np.float64)[..., :3]
        total = img if total is None else total + img
    mi.Bitmap((total / passes).astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB).write(
        os.path.join(HERE, "reference.exr"))


if __name__ == "__main__":
    main()
