#!/usr/bin/env python3
"""The daylight reference scene (tests/scenes/daylight_window) and its Mitsuba 3 reference.

  render_daylight_reference.py write-scene   # writes the OBJs and scene.json
  render_daylight_reference.py render [--spp N] [--passes P]   # writes reference.exr

A closed room (4 x 2.5 x 3 m, one-sided walls facing in) whose east wall (x = 4)
has two 1 x 1 m openings into the cell `outside`: one open, one glazed (thin
glass 1 mm inside the opening, tint GLASS_TINT, index 1.5). Light: a uniform
sky of radiance SKY over the whole sphere (Mitsuba `constant`) and the sun as
a directional light of irradiance SUN_IRRADIANCE from azimuth SUN_AZ (degrees
from +Z towards +X), elevation SUN_EL (Mitsuba `directional`). portico renders
it with the arguments in render_args.txt. Mitsuba's `volpath` integrator
(unbounded depth) is used because its shadow rays pass through `thindielectric`
panes with their transmittance (their transmission is a null interaction),
so the sun reaches the floor through the glazed window; `path` would
leave that sunlight out.

Run with Mitsuba 3.9.1 (variant llvm_ad_rgb):
  DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 VENV/bin/python tests/tools/render_daylight_reference.py render
"""
import argparse, json, math, os, sys

SCENE_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "daylight_window")
SKY = [0.8, 0.9, 1.1]
SUN_IRRADIANCE = [10.0, 9.5, 8.5]
SUN_AZ, SUN_EL = 110.0, 35.0
GLASS_TINT = [0.75, 0.85, 0.95]
GLASS_IOR = 1.5
RENDER_ARGS = ["--sun", f"{SUN_AZ:g},{SUN_EL:g}", "--sun-irradiance", ",".join(f"{v:g}" for v in SUN_IRRADIANCE),
               "--sky", "uniform:" + ",".join(f"{v:g}" for v in SKY)]

X0, X1, Y0, Y1, Z0, Z1 = 0.0, 4.0, 0.0, 2.5, -1.5, 1.5
OPEN = (-1.2, -0.2)      # z range of the open window
GLAZED = (0.2, 1.2)      # z range of the glazed window
SILL, TOP = 0.9, 1.9     # y range of both windows
PANE_X = 3.999


def quad(a, b, c, d):
    """Two triangles a b c, a c d (counter-clockwise seen from the front)."""
    return [(a, b, c), (a, c, d)]


def box(lo, hi):
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    p = lambda x, y, z: (x, y, z)
    tris = []
    tris += quad(p(x0, y1, z0), p(x0, y1, z1), p(x1, y1, z1), p(x1, y1, z0))   # top +y
    tris += quad(p(x1, y0, z0), p(x1, y1, z0), p(x1, y1, z1), p(x1, y0, z1))   # +x
    tris += quad(p(x0, y0, z1), p(x0, y1, z1), p(x0, y1, z0), p(x0, y0, z0))   # -x
    tris += quad(p(x0, y0, z1), p(x1, y0, z1), p(x1, y1, z1), p(x0, y1, z1))   # +z
    tris += quad(p(x1, y0, z0), p(x0, y0, z0), p(x0, y1, z0), p(x1, y1, z0))   # -z
    return tris


def east_wall():
    """x = 4 facing -x (into the room), with the two window holes."""
    x = X1
    p = lambda y, z: (x, y, z)
    def rect(za, zb, ya, yb):   # counter-clockwise seen from -x
        return quad(p(ya, za), p(ya, zb), p(yb, zb), p(yb, za))
    t = []
    t += rect(Z0, Z1, Y0, SILL)          # below the windows
    t += rect(Z0, Z1, TOP, Y1)           # above
    t += rect(Z0, OPEN[0], SILL, TOP)    # piers between
    t += rect(OPEN[1], GLAZED[0], SILL, TOP)
    t += rect(GLAZED[1], Z1, SILL, TOP)
    return t


def write_obj(path, tris):
    with open(path, "w") as f:
        verts = []
        for tri in tris:
            verts.extend(tri)
        for v in verts:
            f.write("v {:g} {:g} {:g}\n".format(*v))
        for i in range(len(tris)):
            f.write("f {} {} {}\n".format(3 * i + 1, 3 * i + 2, 3 * i + 3))


def check_front(tris, inward):
    for a, b, c in tris:
        e1 = [b[i] - a[i] for i in range(3)]
        e2 = [c[i] - a[i] for i in range(3)]
        n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
        assert sum(n[i] * inward[i] for i in range(3)) > 0, (a, b, c, inward)


def scene_objects():
    P = lambda x, y, z: (x, y, z)
    floor = quad(P(X0, Y0, Z0), P(X0, Y0, Z1), P(X1, Y0, Z1), P(X1, Y0, Z0))
    ceiling = quad(P(X0, Y1, Z0), P(X1, Y1, Z0), P(X1, Y1, Z1), P(X0, Y1, Z1))
    west = quad(P(X0, Y0, Z0), P(X0, Y1, Z0), P(X0, Y1, Z1), P(X0, Y0, Z1))
    north = quad(P(X0, Y0, Z0), P(X1, Y0, Z0), P(X1, Y1, Z0), P(X0, Y1, Z0))
    south = quad(P(X0, Y0, Z1), P(X0, Y1, Z1), P(X1, Y1, Z1), P(X1, Y0, Z1))
    pane = quad(P(PANE_X, SILL, GLAZED[0]), P(PANE_X, SILL, GLAZED[1]), P(PANE_X, TOP, GLAZED[1]),
                P(PANE_X, TOP, GLAZED[0]))
    for tris, inward in [(floor, (0, 1, 0)), (ceiling, (0, -1, 0)), (west, (1, 0, 0)), (north, (0, 0, 1)),
                         (south, (0, 0, -1)), (east_wall(), (-1, 0, 0)), (pane, (-1, 0, 0))]:
        check_front(tris, inward)
    return [
        ("floor", floor, {"albedo": [0.55, 0.5, 0.45]}),
        ("ceiling", ceiling, {"albedo": [0.8, 0.8, 0.8]}),
        ("wall_west", west, {"albedo": [0.7, 0.7, 0.7]}),
        ("wall_north", north, {"albedo": [0.7, 0.7, 0.7]}),
        ("wall_south", south, {"albedo": [0.6, 0.65, 0.75]}),
        ("wall_east", east_wall(), {"albedo": [0.7, 0.7, 0.7]}),
        ("box_low", box((2.2, 0.0, -0.9), (2.8, 0.6, -0.3)), {"albedo": [0.65, 0.45, 0.3]}),
        ("box_tall", box((1.2, 0.0, 0.5), (1.7, 1.0, 1.1)), {"albedo": [0.6, 0.6, 0.6]}),
        ("pane", pane, {"glass": {"transmittance": GLASS_TINT, "ior": GLASS_IOR}}),
    ]


CAMERA = {"origin": [0.3, 1.5, 0.0], "target": [4.0, 0.7, 0.2], "up": [0, 1, 0], "fov_y_deg": 75.0,
          "width": 192, "height": 144}


def write_scene():
    objects = []
    for name, tris, material in scene_objects():
        write_obj(os.path.join(SCENE_DIR, name + ".obj"), tris)
        objects.append(dict({"name": name, "obj": name + ".obj", "cell": "room"}, **material))
    window = lambda z: [[X1, SILL, z[0]], [X1, SILL, z[1]], [X1, TOP, z[1]], [X1, TOP, z[0]]]
    scene = {
        "name": "daylight_window",
        "description": "A closed 4 m (x) x 2.5 m (y) x 3 m (z) room whose east wall (x = 4) has two 1 x 1 m "
                       "openings to the cell 'outside': an open one (z in [-1.2,-0.2]) and a glazed one (z in "
                       "[0.2,1.2], a thin glass pane 1 mm inside it). Lit only by daylight: render with the "
                       "arguments in render_args.txt (uniform sky over the whole sphere, sun as a directional "
                       "light). Written by tests/tools/render_daylight_reference.py.",
        "units": "metres",
        "coordinate_system": "right-handed, +Y up",
        "material_model": "ideal Lambertian reflector, one-sided in the reference render; the pane is thin "
                          "glass (Mitsuba thindielectric: Fresnel reflection 2R/(1+R), transmission (1-2R/(1+R)) "
                          "times the tint, no refraction offset).",
        "pixel_values": "linear radiance in W m^-2 sr^-1 per channel, as the sky's",
        "cells": [
            {"name": "room", "aabb": {"min": [X0, Y0, Z0], "max": [X1, Y1, Z1]}},
            {"name": "outside", "aabb": {"min": [X1, -1.0, -3.0], "max": [X1 + 4.0, 4.0, 3.0]},
             "note": "outdoors (its name): openings into it let the sky and sun in"},
        ],
        "portals": [
            {"between": ["room", "outside"], "polygon": window(OPEN)},
            {"between": ["room", "outside"], "polygon": window(GLAZED)},
        ],
        "objects": objects,
        "camera": CAMERA,
    }
    with open(os.path.join(SCENE_DIR, "scene.json"), "w") as f:
        json.dump(scene, f, indent=1)
        f.write("\n")
    with open(os.path.join(SCENE_DIR, "render_args.txt"), "w") as f:
        f.write(" ".join(RENDER_ARGS) + "\n")


def sun_direction():
    az, el = math.radians(SUN_AZ), math.radians(SUN_EL)
    return [math.sin(az) * math.cos(el), math.sin(el), math.cos(az) * math.cos(el)]


def render(spp, passes, threads):
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    mi.set_log_level(mi.LogLevel.Warn)
    import numpy as np
    if threads:
        mi.Thread.thread().set_thread_count(threads) if hasattr(mi.Thread, "set_thread_count") else None
    cam = CAMERA
    d = {
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": -1, "hide_emitters": False},
        "sensor": {
            "type": "perspective", "fov": cam["fov_y_deg"], "fov_axis": "y", "near_clip": 0.001, "far_clip": 1000.0,
            "to_world": mi.ScalarTransform4f().look_at(origin=cam["origin"], target=cam["target"], up=cam["up"]),
            "sampler": {"type": "independent", "sample_count": spp},
            "film": {"type": "hdrfilm", "width": cam["width"], "height": cam["height"], "pixel_format": "rgb",
                     "component_format": "float32", "rfilter": {"type": "box"}, "sample_border": False},
        },
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": SKY}},
        "sun": {"type": "directional", "direction": [-c for c in sun_direction()],
                "irradiance": {"type": "rgb", "value": SUN_IRRADIANCE}},
    }
    for name, _, material in scene_objects():
        if "glass" in material:
            bsdf = {"type": "thindielectric", "int_ior": GLASS_IOR, "ext_ior": 1.0,
                    "specular_transmittance": {"type": "rgb", "value": GLASS_TINT}}
        else:
            bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": material["albedo"]}}
        d["shape_" + name] = {"type": "obj", "filename": os.path.join(SCENE_DIR, name + ".obj"),
                              "face_normals": True, "bsdf": bsdf}
    scene = mi.load_dict(d)
    total = None
    for p in range(passes):
        image = np.array(mi.render(scene, seed=p, spp=spp))
        total = image if total is None else total + image
        # The average so far, after every pass: a long render can be stopped.
        mi.Bitmap((total / (p + 1)).astype(np.float32)).write(os.path.join(SCENE_DIR, "reference.exr"))
        print(f"pass {p + 1}/{passes}: {(p + 1) * spp} spp written", file=sys.stderr, flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=["write-scene", "render"])
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--passes", type=int, default=16)
    ap.add_argument("--threads", type=int, default=0)
    a = ap.parse_args()
    if a.what == "write-scene":
        write_scene()
    else:
        render(a.spp, a.passes, a.threads)


if __name__ == "__main__":
    main()
