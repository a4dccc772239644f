"""Renders a named camera of a portico scene store with peer renderers.

    python -m portico_peers view STORE OUT_DIR [--camera NAME] [--portico BIN]
    python -m portico_peers mitsuba OUT_DIR --spp 64,256        (Mitsuba 3's virtual environment)
    python -m portico_peers luxcore OUT_DIR --spp 16,64 [--photongi] (the project's .venv, pyluxcore)

`view` writes the store's geometry and camera once (store_view.py); each
renderer then writes OUT_DIR/<renderer>-<spp>.exr and prints one CSV row per
render, `spp,seconds,image`, its wall time on --threads threads, scene
loading excluded.
"""
