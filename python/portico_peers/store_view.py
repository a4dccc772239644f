"""One named camera of a portico scene store, written for other renderers.

`portico scene export STORE -o view.gltf` gives the geometry grouped by
material (one glTF primitive per cell and material) and `portico scene info
--json` the named cameras. This module merges each material's triangles into
one little-endian PLY file and writes `view.json` beside them:

    {"store": ..., "camera": {"name", "origin", "look_at", "up", "fov_y_deg",
     "width", "height"},
     "materials": [{"name", "albedo": [r, g, b], "emission": [r, g, b] | null,
                    "hidden_from_camera": bool, "ply": "m04.ply",
                    "triangles": N}]}

Both peers read that folder (Mitsuba 3 from its own virtual environment,
LuxCoreRender from the project's), so only numpy is needed here.

portico shades both sides of every surface and emits on the lit side of a
light's triangles only (their winding's normal); the peers are set up to do
the same. Materials other than diffuse and emitting (glass, textures) are
refused, naming the material: the peers would render them otherwise.
"""
import json
import os
import sqlite3
import subprocess

import numpy as np

COMPONENT_DTYPES = {5125: np.uint32, 5123: np.uint16, 5121: np.uint8, 5126: np.float32}


class UnsupportedView(ValueError):
    pass


def _accessor(gltf, buffer, index):
    acc = gltf["accessors"][index]
    view = gltf["bufferViews"][acc["bufferView"]]
    dtype = np.dtype(COMPONENT_DTYPES[acc["componentType"]]).newbyteorder("<")
    width = {"SCALAR": 1, "VEC3": 3}[acc["type"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    data = np.frombuffer(buffer, dtype=dtype, count=acc["count"] * width, offset=start)
    return data.reshape(-1, width) if width > 1 else data


def _write_ply(path, vertices, triangles):
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\n"
              "property float x\nproperty float y\nproperty float z\n"
              f"element face {len(triangles)}\nproperty list uchar int vertex_indices\nend_header\n")
    faces = np.empty(len(triangles), dtype=[("n", "u1"), ("i", "<i4", 3)])
    faces["n"] = 3
    faces["i"] = triangles
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(np.ascontiguousarray(vertices, dtype="<f4").tobytes())
        f.write(faces.tobytes())


def check_store(store):
    """Refuses what the glTF export leaves out: glass, textures, point luminaires."""
    db = sqlite3.connect(f"file:{os.path.join(store, 'scene.db')}?mode=ro", uri=True)
    try:
        glass = db.execute("SELECT name FROM materials WHERE transmittance_r + transmittance_g + transmittance_b > 0 "
                           "ORDER BY id LIMIT 1").fetchone()
        if glass:
            raise UnsupportedView(f"{store}: material {glass[0]!r} is glass; the peers render diffuse and emitting "
                                  "surfaces only")
        textured = db.execute("SELECT m.name FROM material_textures t JOIN materials m ON m.id = t.material "
                              "ORDER BY m.id LIMIT 1").fetchone()
        if textured:
            raise UnsupportedView(f"{store}: material {textured[0]!r} is textured; the peers render plain colours only")
        tables = {r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
        if "point_lights" in tables and db.execute("SELECT count(*) FROM point_lights").fetchone()[0]:
            raise UnsupportedView(f"{store}: has point luminaires; the peers render area lights only")
    finally:
        db.close()


def _material(m):
    pbr = m.get("pbrMetallicRoughness", {})
    emission = None
    if "emissiveFactor" in m and any(m["emissiveFactor"]):
        strength = m.get("extensions", {}).get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0)
        emission = [c * strength for c in m["emissiveFactor"]]
    return {"name": m["name"], "albedo": pbr.get("baseColorFactor", [1, 1, 1, 1])[:3], "emission": emission,
            "hidden_from_camera": bool(m.get("extras", {}).get("hidden_from_camera", False))}


def _camera(info, name):
    cameras = info.get("cameras", [])
    if not cameras:
        raise UnsupportedView(f"store {info.get('store')!r} has no camera")
    chosen = cameras[0] if name is None else next((c for c in cameras if c["name"] == name), None)
    if chosen is None:
        raise UnsupportedView(f"camera {name!r} is not in the store (it has {', '.join(c['name'] for c in cameras)})")
    return {"name": chosen["name"], "origin": chosen["origin"], "look_at": chosen["look_at"], "up": chosen["up"],
            "fov_y_deg": chosen["fov"], "width": chosen["width"], "height": chosen["height"]}


def write_view(portico, store, camera_name, out_dir, width=None, height=None):
    """Exports STORE's geometry and the named camera into OUT_DIR; returns view.json's content."""
    check_store(store)
    os.makedirs(out_dir, exist_ok=True)
    gltf_path = os.path.join(out_dir, "export.gltf")
    subprocess.run([portico, "scene", "export", store, "-o", gltf_path], check=True, stdout=subprocess.DEVNULL)
    info = json.loads(subprocess.run([portico, "scene", "info", "--json", "--no-compress", store], check=True,
                                     capture_output=True, text=True).stdout)
    with open(gltf_path) as f:
        gltf = json.load(f)
    with open(os.path.join(out_dir, gltf["buffers"][0]["uri"]), "rb") as f:
        buffer = f.read()
    materials = [_material(m) for m in gltf["materials"]]
    vertices = {i: [] for i in range(len(materials))}
    triangles = {i: [] for i in range(len(materials))}
    counts = {i: 0 for i in range(len(materials))}
    for node in gltf["nodes"]:
        if "mesh" not in node:
            continue
        if "matrix" in node or "translation" in node or "rotation" in node or "scale" in node:
            raise UnsupportedView(f"node {node.get('name')!r} is transformed; the export writes world coordinates")
        for prim in gltf["meshes"][node["mesh"]]["primitives"]:
            m = prim["material"]
            positions = _accessor(gltf, buffer, prim["attributes"]["POSITION"])
            indices = _accessor(gltf, buffer, prim["indices"]).astype(np.int64).reshape(-1, 3)
            vertices[m].append(positions)
            triangles[m].append(indices + counts[m])
            counts[m] += len(positions)
    view = {"store": os.path.abspath(store), "camera": _camera(info, camera_name), "materials": []}
    if width:
        view["camera"]["width"] = width
    if height:
        view["camera"]["height"] = height
    for i, material in enumerate(materials):
        if not triangles[i]:
            continue
        ply = f"m{i:02d}.ply"
        tris = np.concatenate(triangles[i])
        _write_ply(os.path.join(out_dir, ply), np.concatenate(vertices[i]), tris)
        view["materials"].append(dict(material, ply=ply, triangles=int(len(tris))))
    os.remove(gltf_path)
    os.remove(os.path.join(out_dir, gltf["buffers"][0]["uri"]))
    with open(os.path.join(out_dir, "view.json"), "w") as f:
        json.dump(view, f, indent=1)
    return view


def read_view(view_dir):
    with open(os.path.join(view_dir, "view.json")) as f:
        return json.load(f)
