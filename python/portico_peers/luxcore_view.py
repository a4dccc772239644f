"""A store view (store_view.py) rendered by LuxCoreRender (PyPI `pyluxcore`).

Its path tracer (PATHCPU) with no depth limit short of 64 bounces (Russian
roulette from the third), optionally with its PhotonGI indirect cache: the
nearest open-source photon-mapping peer of portico (photons traced once,
their radiance cached and looked up where a path meets a diffuse surface
after its first bounce). Matte surfaces shade both sides as portico's do;
lights emit on their front, with the radiance the store gives them (no
power normalisation). Pinhole camera (LuxCore's field of view spans the
image's wider side: it is set from the store's vertical one), each sample counted in its own pixel only (a box pixel filter).

pyluxcore crashes at interpreter exit: callers end with os._exit.
"""
import math
import os
import time

DEPTH = 64


def image_path(view_dir, spp, photongi):
    return os.path.join(view_dir, f"luxcore-{'photongi-' if photongi else ''}{spp}.exr")


def _properties(pyluxcore, values):
    props = pyluxcore.Properties()
    for name, value in values.items():
        props.Set(pyluxcore.Property(name, value))
    return props


def _config(pyluxcore, view_dir, view, spp, threads, photongi, seed):
    cam = view["camera"]
    if cam["width"] < cam["height"]:
        raise ValueError(f"camera {cam['name']!r}: taller than wide; LuxCore's field of view would be vertical")
    scene_values, config = {}, {}
    scene_values["scene.camera.type"] = "perspective"
    scene_values["scene.camera.lookat.orig"] = [float(c) for c in cam["origin"]]
    scene_values["scene.camera.lookat.target"] = [float(c) for c in cam["look_at"]]
    scene_values["scene.camera.up"] = [float(c) for c in cam["up"]]
    # LuxCore's field of view spans the image's wider side.
    half_x = math.atan(math.tan(math.radians(cam["fov_y_deg"]) / 2) * cam["width"] / cam["height"])
    scene_values["scene.camera.fieldofview"] = math.degrees(2 * half_x)
    # Its default screen window, lowered by one pixel: LuxCore's images
    # come out one row lower than portico's and Mitsuba's (measured on the
    # edges of cornell_closed's light: +1.00 px in y).
    frame = cam["width"] / cam["height"]
    row = 2.0 / cam["width"]
    scene_values["scene.camera.screenwindow"] = [-1.0, 1.0, -1.0 / frame - row, 1.0 / frame - row]
    for i, m in enumerate(view["materials"]):
        name = f"m{i:02d}"
        scene_values[f"scene.materials.{name}.type"] = "matte"
        scene_values[f"scene.materials.{name}.kd"] = [float(c) for c in m["albedo"]]
        if m["emission"]:
            scene_values[f"scene.materials.{name}.emission"] = [float(c) for c in m["emission"]]
            scene_values[f"scene.materials.{name}.emission.gain"] = [1.0, 1.0, 1.0]
            scene_values[f"scene.materials.{name}.emission.power"] = 0.0
            scene_values[f"scene.materials.{name}.emission.efficency"] = 0.0
            scene_values[f"scene.materials.{name}.emission.normalizebycolor"] = False
        scene_values[f"scene.shapes.{name}.type"] = "mesh"
        scene_values[f"scene.shapes.{name}.ply"] = os.path.join(view_dir, m["ply"])
        scene_values[f"scene.objects.{name}.shape"] = name
        scene_values[f"scene.objects.{name}.material"] = name
    scene = pyluxcore.Scene()
    scene.Parse(_properties(pyluxcore, scene_values))

    config["renderengine.type"] = "PATHCPU"
    config["renderengine.seed"] = seed
    config["sampler.type"] = "SOBOL"
    config["native.threads.count"] = threads
    config["film.width"] = int(cam["width"])
    config["film.height"] = int(cam["height"])
    config["film.filter.type"] = "NONE"
    config["film.imagepipelines.0.0.type"] = "NOP"
    config["film.outputs.0.type"] = "RGB"
    config["film.outputs.0.filename"] = image_path(view_dir, spp, photongi)
    for kind in ("total", "diffuse", "glossy", "specular"):
        config[f"path.pathdepth.{kind}"] = DEPTH
    config["path.clamping.variance.maxvalue"] = 0.0
    config["path.forceblackbackground.enable"] = True
    config["batch.haltspp"] = spp
    config["batch.halttime"] = 0
    config["path.photongi.indirect.enabled"] = bool(photongi)
    config["path.photongi.caustic.enabled"] = False
    if photongi:
        config["path.photongi.sampler.type"] = "METROPOLIS"
        config["path.photongi.photon.maxcount"] = int(photongi)
        config["path.photongi.indirect.maxsize"] = 0   # stop at the halt threshold, as the Blender add-on does
    return pyluxcore.RenderConfig(_properties(pyluxcore, config), scene)


def render(view_dir, view, counts, threads, photongi=0, out=print):
    import contextlib
    import sys
    with contextlib.redirect_stdout(sys.stderr):   # it lists the libraries it loads
        import pyluxcore
    pyluxcore.Init(lambda message: None)
    out("spp,seconds,image")
    sessions = []   # kept: a session's destructor can abort the process (pyluxcore 2.11)
    for spp in counts:
        config = _config(pyluxcore, view_dir, view, spp, threads, photongi, seed=spp)
        session = pyluxcore.RenderSession(config)
        sessions.append(session)
        started = time.perf_counter()
        session.Start()
        while not session.HasDone():
            time.sleep(0.01)
            session.UpdateStats()
        seconds = time.perf_counter() - started
        session.GetFilm().SaveOutputs()
        out(f"{spp},{seconds:.3f},{image_path(view_dir, spp, photongi)}")
