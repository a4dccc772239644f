"""A reference scene's scene.json as a Mitsuba 3 scene dictionary.

The scene is rendered as its reference was: ideal diffuse surfaces (an albedo
texture where the object names one), one-sided Lambertian area lights, a
pinhole camera with a box pixel filter, and the `path` integrator. Objects
Mitsuba's `path` would render otherwise than portico (thin glass, whose
sunlight only `volpath` passes) and scenes lit by a sky are refused, naming
the object.
"""
import os


class UnsupportedScene(ValueError):
    pass


def check_supported(scene_dir, sc):
    where = os.path.join(scene_dir, "scene.json")
    if os.path.exists(os.path.join(scene_dir, "render_args.txt")):
        raise UnsupportedScene(f"{where}: lit by render_args.txt (sun or sky), which this ladder does not render")
    for o in sc["objects"]:
        if o.get("glass") is not None:
            raise UnsupportedScene(f"{where}: object {o['name']!r} is glass; this ladder renders diffuse and "
                                   "emitting objects only")


def base_dict(mi, origin, target, up, fov_y_deg, width, height, spp, max_depth=-1):
    """The path integrator and a pinhole camera with a box pixel filter, as portico renders."""
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth, "hide_emitters": False},
        "sensor": {
            "type": "perspective", "fov": fov_y_deg, "fov_axis": "y",
            "near_clip": 0.001, "far_clip": 10000.0,
            "to_world": mi.ScalarTransform4f().look_at(origin=origin, target=target, up=up),
            "sampler": {"type": "independent", "sample_count": spp},
            "film": {"type": "hdrfilm", "width": width, "height": height, "pixel_format": "rgb",
                     "component_format": "float32", "rfilter": {"type": "box"}, "sample_border": False},
        },
    }


def scene_dict(mi, scene_dir, sc, spp, max_depth=-1):
    cam = sc["camera"]
    d = base_dict(mi, cam["origin"], cam["target"], cam["up"], cam["fov_y_deg"], cam["width"], cam["height"], spp,
                  max_depth)
    for i, o in enumerate(sc["objects"]):
        if "_texture" in o:
            # Bilinear, repeating, the image's sRGB values linearised: as portico looks textures up.
            reflectance = {"type": "bitmap", "filename": os.path.join(scene_dir, o["_texture"]),
                           "filter_type": "bilinear", "wrap_mode": "repeat", "raw": False}
        else:
            reflectance = {"type": "rgb", "value": o["albedo"]}
        shape = {"type": "obj", "filename": os.path.join(scene_dir, o["obj"]), "face_normals": True,
                 "bsdf": {"type": "diffuse", "reflectance": reflectance}}
        if o.get("emission") is not None:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": o["emission"]}}
        # Mitsuba reserves the dot in ids.
        d[f"shape_{i:02d}_{o['name'].replace('.', '_')}"] = shape
    return d
