"""A reference scene's scene.json as a Mitsuba 3 scene dictionary.

The scene is rendered as its reference was: ideal diffuse surfaces (an albedo
texture where the object names one) or the object's "finish" (a plastic as
`roughplastic`, a metal as `roughconductor`, a mirror as `conductor`, with
portico's parameters: docs/materials.md), one-sided Lambertian area lights, a
pinhole camera with a box pixel filter, and the `path` integrator. Objects
Mitsuba's `path` would render otherwise than portico (thin glass, whose
sunlight only `volpath` passes) and scenes lit by a sky are refused, naming
the object.
"""
import math
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


def ggx_alpha(roughness):
    """The GGX alpha of a perceptual roughness, as portico takes it (surface_bsdf.h)."""
    return max(roughness * roughness, 0.01)


def conductor_index(colour):
    """The complex index (eta, k) per channel whose normal-incidence
    reflectance is `colour` and whose edge tint is white (Gulbrandsen 2014
    with g = 1), as portico fits a metal's colour (common/transport/fresnel.h)."""
    eta, k = [], []
    for c in colour:
        r = min(max(float(c), 0.0), 0.9999)
        n = (1 - r) / (1 + r)
        eta.append(n)
        k.append(math.sqrt(max(0.0, (r * (n + 1) ** 2 - (n - 1) ** 2) / (1 - r))))
    return eta, k


def finish_bsdf(o, reflectance):
    """The Mitsuba BSDF of a building.json object with a "finish"."""
    f = o["finish"]
    kind = f["type"]
    if kind == "plastic":
        return {"type": "roughplastic", "distribution": "ggx", "alpha": ggx_alpha(f.get("roughness", 0.1)),
                "int_ior": f.get("ior", 1.5), "ext_ior": 1.0, "nonlinear": False,
                "diffuse_reflectance": reflectance,
                "specular_reflectance": {"type": "rgb", "value": f.get("specular", [1.0, 1.0, 1.0])}}
    eta, k = conductor_index(f.get("colour", [0.9, 0.9, 0.9]))
    index = {"eta": {"type": "rgb", "value": eta}, "k": {"type": "rgb", "value": k}}
    roughness = f.get("roughness", 0.3) if kind == "metal" else 0.0
    if roughness == 0:
        return {"type": "conductor", **index}
    return {"type": "roughconductor", "distribution": "ggx", "alpha": ggx_alpha(roughness), **index}


def scene_dict(mi, scene_dir, sc, spp, max_depth=-1):
    cam = sc["camera"]
    d = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth, "hide_emitters": False},
        "sensor": {
            "type": "perspective", "fov": cam["fov_y_deg"], "fov_axis": "y",
            "near_clip": 0.001, "far_clip": 1000.0,
            "to_world": mi.ScalarTransform4f().look_at(origin=cam["origin"], target=cam["target"], up=cam["up"]),
            "sampler": {"type": "independent", "sample_count": spp},
            "film": {"type": "hdrfilm", "width": cam["width"], "height": cam["height"], "pixel_format": "rgb",
                     "component_format": "float32", "rfilter": {"type": "box"}, "sample_border": False},
        },
    }
    for i, o in enumerate(sc["objects"]):
        if "_texture" in o:
            # Bilinear, repeating, the image's sRGB values linearised: as portico looks textures up.
            reflectance = {"type": "bitmap", "filename": os.path.join(scene_dir, o["_texture"]),
                           "filter_type": "bilinear", "wrap_mode": "repeat", "raw": False}
        else:
            reflectance = {"type": "rgb", "value": o.get("albedo", [0.0, 0.0, 0.0])}
        bsdf = finish_bsdf(o, reflectance) if o.get("finish") else {"type": "diffuse", "reflectance": reflectance}
        shape = {"type": "obj", "filename": os.path.join(scene_dir, o["obj"]), "face_normals": True, "bsdf": bsdf}
        if o.get("emission") is not None:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": o["emission"]}}
        # Mitsuba reserves the dot in ids.
        d[f"shape_{i:02d}_{o['name'].replace('.', '_')}"] = shape
    return d
