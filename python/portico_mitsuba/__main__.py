"""Renders a reference scene with Mitsuba 3's path tracer at increasing sample counts.

Usage: python -m portico_mitsuba SCENE_DIR OUT_DIR [--spp 16,64,256] [--threads 2]
                                 [--variant llvm_ad_rgb] [--max-depth -1]

Renders SCENE_DIR/scene.json (tests/scenes' format) once per sample count
into OUT_DIR/mitsuba-SPP.exr and prints one CSV row per render,
`spp,seconds,image`: the render's wall time on THREADS threads, the scene's
loading and the first JIT compilation excluded (a warm-up render of 1 spp
comes first). Each render is seeded with its spp, so rows are independent.
`portico bench quality SCENE_DIR --mitsuba` runs this and scores the images
against SCENE_DIR/reference.exr as it scores its own.

Needs Mitsuba 3 and Dr.Jit (deploy/install-deps.sh --peers: a virtual
environment at ~/.local/share/portico/mitsuba-venv) and, for the LLVM
variants, DRJIT_LIBLLVM_PATH naming Debian's libLLVM 19.
"""
import argparse
import json
import os
import sys

from portico_mitsuba.ladder import render_ladder
from portico_mitsuba.scene import UnsupportedScene, check_supported, scene_dict


def main():
    ap = argparse.ArgumentParser(prog="python -m portico_mitsuba")
    ap.add_argument("scene_dir")
    ap.add_argument("out_dir")
    ap.add_argument("--spp", default="16,64,256", help="sample counts, comma-separated")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--max-depth", type=int, default=-1, help="-1: unbounded, as the references")
    a = ap.parse_args()
    try:
        counts = [int(s) for s in a.spp.split(",")]
    except ValueError:
        sys.exit(f"--spp {a.spp}: not a comma-separated list of sample counts")
    if not counts or min(counts) < 1:
        sys.exit(f"--spp {a.spp}: sample counts must be at least 1")
    scene_json = os.path.join(a.scene_dir, "scene.json")
    try:
        with open(scene_json) as f:
            sc = json.load(f)
        check_supported(a.scene_dir, sc)
    except (OSError, json.JSONDecodeError, UnsupportedScene) as e:
        sys.exit(f"{scene_json}: {e}" if not isinstance(e, UnsupportedScene) else str(e))

    # Mitsuba is imported (by render_ladder) once the scene is known to be one
    # this ladder renders: the refusal needs neither Mitsuba nor numpy.
    render_ladder(lambda mi, spp: scene_dict(mi, a.scene_dir, sc, spp, a.max_depth), counts, a.threads, a.variant,
                  a.out_dir, out=lambda row: print(row, flush=True))

if __name__ == "__main__":
    main()
