#!/usr/bin/env python3
"""The glossy reference scenes (tests/scenes/glossy_cabinet, mirror_room) and their Mitsuba 3 references.

  render_glossy_references.py write-scene            # writes both scenes' OBJs and scene.json
  render_glossy_references.py render [--spp N] [--pass-spp P] [--threads T] [SCENE ...]   # reference.exr

Both are the room of cornell_closed (2 x 2 x 3 m, red and green side walls,
a 0.4 x 0.4 m ceiling lamp of radiance 15), seen from near its front wall at
256 x 256 (docs/materials.md):

- glossy_cabinet: its floor a polished plastic (the walls' albedo under a
  coating of index 1.5, roughness 0.3), a brushed copper cabinet (a metal of
  colour COPPER, roughness 0.4) where the tall box stood, and the short box
  a varnished wood plastic (roughness 0.5);
- mirror_room: a 1.2 x 1.2 m mirror (colour 0.9) 1 mm in front of the back
  wall, and both boxes as in cornell_closed.

References: Mitsuba 3.9.1 (llvm_ad_rgb, `path`, unbounded depth), the
finishes as python/portico_mitsuba converts them (roughplastic,
roughconductor, conductor with the index portico fits to a metal's colour).

Run with (about 4 minutes each on 2 threads):
  DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 VENV/bin/python tests/tools/render_glossy_references.py render
"""
import argparse, json, os, shutil, sys

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = os.path.join(HERE, "..", "scenes")
sys.path.insert(0, os.path.join(HERE, "..", "..", "python"))

WHITE = [0.725, 0.71, 0.68]
COPPER = [0.95, 0.64, 0.54]
ROOM = ["floor", "ceiling", "back_wall", "front_wall", "left_wall", "right_wall", "light"]
MIRROR = dict(x=(-0.6, 0.6), y=(0.3, 1.5), z=-0.999)


def write_obj(path, name, tris):
    with open(path, "w") as f:
        f.write(f"# {name}: {len(tris)} triangles, metres, +Y up, counter-clockwise seen from the front\no {name}\n")
        for tri in tris:
            for v in tri:
                f.write("v {:.6f} {:.6f} {:.6f}\n".format(*v))
        for i in range(len(tris)):
            f.write("f {} {} {}\n".format(3 * i + 1, 3 * i + 2, 3 * i + 3))


def cornell_objects():
    src = json.load(open(os.path.join(SCENES, "cornell_closed", "scene.json")))
    return {o["name"]: o for o in src["objects"]}, src


def scene_json(base, name, description, objects):
    sc = {k: v for k, v in base.items() if k not in ("objects", "name", "description", "material_model")}
    sc["name"] = name
    sc["description"] = description
    sc["material_model"] = ("albedo = Lambertian reflectance; an object's 'finish' makes it a plastic (GGX coating of "
                            "index ior over its albedo), a metal (GGX conductor of normal reflectance 'colour') or a "
                            "mirror; docs/materials.md. One-sided: back faces are black and never seen.")
    sc["objects"] = objects
    return sc


def copy_room(dst, names, cornell):
    objects = []
    for n in names:
        o = dict(cornell[n])
        shutil.copy(os.path.join(SCENES, "cornell_closed", o["obj"]), os.path.join(dst, o["obj"]))
        objects.append(o)
    return objects


def write_scenes():
    cornell, base = cornell_objects()
    # glossy_cabinet
    dst = os.path.join(SCENES, "glossy_cabinet")
    os.makedirs(dst, exist_ok=True)
    objects = copy_room(dst, ROOM + ["short_box", "tall_box"], cornell)
    for o in objects:
        if o["name"] == "floor":
            o["finish"] = {"type": "plastic", "roughness": 0.3, "ior": 1.5}
        if o["name"] == "short_box":
            o["albedo"] = [0.45, 0.28, 0.15]
            o["finish"] = {"type": "plastic", "roughness": 0.5, "ior": 1.5}
        if o["name"] == "tall_box":
            o["name"] = "cabinet"
            del o["albedo"]
            o["finish"] = {"type": "metal", "colour": COPPER, "roughness": 0.4}
    json.dump(scene_json(base, "glossy_cabinet",
                         "cornell_closed's room with a polished plastic floor (roughness 0.3), a copper cabinet (metal, "
                         "roughness 0.4) for the tall box and a varnished wood short box (plastic, roughness 0.5).",
                         objects), open(os.path.join(dst, "scene.json"), "w"), indent=2)
    # mirror_room
    dst = os.path.join(SCENES, "mirror_room")
    os.makedirs(dst, exist_ok=True)
    objects = copy_room(dst, ROOM + ["short_box", "tall_box"], cornell)
    (x0, x1), (y0, y1), z = MIRROR["x"], MIRROR["y"], MIRROR["z"]
    write_obj(os.path.join(dst, "mirror.obj"), "mirror",
              [((x0, y0, z), (x1, y0, z), (x1, y1, z)), ((x0, y0, z), (x1, y1, z), (x0, y1, z))])
    objects.append({"obj": "mirror.obj", "name": "mirror", "finish": {"type": "mirror", "colour": [0.9, 0.9, 0.9]},
                    "emission": None, "triangles": 2, "area_m2": round((x1 - x0) * (y1 - y0), 6)})
    json.dump(scene_json(base, "mirror_room",
                         "cornell_closed with a 1.2 x 1.2 m mirror (colour 0.9) 1 mm in front of its back wall.",
                         objects), open(os.path.join(dst, "scene.json"), "w"), indent=2)


def render(names, spp, pass_spp, threads):
    import numpy as np
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    import drjit as dr
    dr.set_thread_count(threads)
    from portico_mitsuba.scene import scene_dict
    for name in names:
        dst = os.path.join(SCENES, name)
        sc = json.load(open(os.path.join(dst, "scene.json")))
        scene = mi.load_dict(scene_dict(mi, dst, sc, pass_spp))
        passes = max(1, spp // pass_spp)
        total = None
        for p in range(passes):
            img = np.array(mi.render(scene, spp=pass_spp, seed=p), dtype=np.float64)[..., :3]
            total = img if total is None else total + img
        mi.Bitmap((total / passes).astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB).write(
            os.path.join(dst, "reference.exr"))
        print(f"{name}: {passes} x {pass_spp} spp", flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("command", choices=["write-scene", "render"])
    ap.add_argument("scenes", nargs="*", default=["glossy_cabinet", "mirror_room"])
    ap.add_argument("--spp", type=int, default=4096)
    ap.add_argument("--pass-spp", type=int, default=256)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    if a.command == "write-scene":
        write_scenes()
    else:
        render(a.scenes, a.spp, a.pass_spp, a.threads)


if __name__ == "__main__":
    main()
