"""Mitsuba renders of one scene at increasing sample counts, each timed.

Shared by the reference-scene ladder (python -m portico_mitsuba) and the
building views (python -m portico_peers mitsuba): prints `spp,seconds,image`
per render, its wall time on `threads` threads with the scene's loading and
the first JIT compilation excluded (a warm-up render of 1 spp comes first);
each render is seeded with its spp, so rows are independent.
"""
import os
import time

# Debian's libLLVM, for Dr.Jit's LLVM variants (DRJIT_LIBLLVM_PATH wins).
DEBIAN_LIBLLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"


def render_ladder(scene_for_spp, counts, threads, variant, out_dir, out=print):
    """scene_for_spp(mi, spp) gives the scene dictionary; images go to out_dir/mitsuba-SPP.exr."""
    if not os.environ.get("DRJIT_LIBLLVM_PATH") and os.path.exists(DEBIAN_LIBLLVM):
        os.environ["DRJIT_LIBLLVM_PATH"] = DEBIAN_LIBLLVM
    import numpy as np
    import mitsuba as mi
    mi.set_variant(variant)
    import drjit as dr
    dr.set_thread_count(threads)
    os.makedirs(out_dir, exist_ok=True)
    out("spp,seconds,image")
    for spp in counts:
        scene = mi.load_dict(scene_for_spp(mi, spp))
        if spp == counts[0]:  # the first render compiles the kernels: not counted
            dr.eval(mi.render(scene, spp=1, seed=999))
        started = time.perf_counter()
        # Copied out inside the timing: Dr.Jit evaluates lazily, and asynchronously.
        pixels = np.array(mi.render(scene, spp=spp, seed=spp), dtype=np.float32)[..., :3]
        seconds = time.perf_counter() - started
        path = os.path.join(out_dir, f"mitsuba-{spp}.exr")
        mi.Bitmap(pixels, pixel_format=mi.Bitmap.PixelFormat.RGB).write(path)
        out(f"{spp},{seconds:.3f},{path}")
