"""Blender Cycles side of ``benchmarks/cycles_peer.py``; runs under a Python that has ``bpy``.

    <bpy python> benchmarks/_cycles_worker.py        # driven by cycles_peer.py over stdin

Reads JSON lines on stdin and answers with lines that start with ``@@CY `` (Blender
prints its own log lines on stdout, which the driver skips):

* first line ``{"spec": ..., "res": [w, h], "max_depth": D, "threads": T, "exr": path}``:
  builds the scene (fogref's y-up metres converted to Blender's z-up, see
  :func:`to_blender`), sets the fair Cycles settings (:data:`FAIR`), answers
  ``{"import_s", "build_s", "versions"}``;
* then ``{"spp": n, "seed": s, "persistent": bool}``: renders, writes linear float32
  RGBA to ``exr`` (outside the timed region), answers ``{"wall_s"}``.

Only the standard library and (in :func:`main`) ``bpy`` / ``mathutils`` are imported here: ``bpy``'s
wheel pins a numpy that fogref's lock does not allow, so it lives in its own venv.
"""

from __future__ import annotations

import json
import math
import sys
import time

bpy = Vector = None  # imported by main(): cycles_peer.py imports this file without bpy
IMPORT_S = 0.0


def to_blender(p):
    """fogref (x, y, z), y up -> Blender (x, -z, y), z up: a proper rotation (+90 deg
    about x), so handedness and images are preserved."""
    return (float(p[0]), -float(p[2]), float(p[1]))


def fair_settings(max_depth: int) -> dict:
    """Scene.cycles settings that make Cycles an unbiased peer of fogref's path tracer
    at Mitsuba ``max_depth`` D (D = 2 is direct light only = Cycles' 0 bounces)."""
    b = max(max_depth - 2, 0)
    return {
        "device": "CPU",
        "use_adaptive_sampling": False,  # fixed spp, like fogref
        "use_denoising": False,
        "use_guiding": False,
        "sample_clamp_direct": 0.0,
        "sample_clamp_indirect": 0.0,  # default 10: clamps (biases) indirect light
        "light_sampling_threshold": 0.0,  # default 0.01: drops weak light samples
        "use_light_tree": True,  # default; unbiased (one sun + world background)
        "min_light_bounces": 0,
        "max_bounces": b,
        "diffuse_bounces": b,
        "volume_bounces": b,  # default 0: single scattering only
        "glossy_bounces": b,
        "transmission_bounces": b,
        "transparent_max_bounces": 64,  # the fog box's volume-only surface is crossed
        "caustics_reflective": True,
        "caustics_refractive": True,
        "blur_glossy": 0.0,
        "volume_biased": False,  # null scattering (Blender 5.0), not ray marching
        "volume_step_rate": 1.0,  # used only by the biased ray marcher
        "volume_max_steps": 1024,
        "pixel_filter_type": "BOX",
        "filter_width": 1.0,  # Mitsuba's box rfilter: one pixel
        "use_animated_seed": False,
        "film_exposure": 1.0,
    }


#: the rest of what build() sets, as the report lists it
OTHER_SETTINGS = [
    "- `scene.cycles.samples` = the spp and `scene.cycles.seed` = a seed per render (fixed per run, "
    "varied across repeats, `use_animated_seed = False`)",
    "- `scene.render.threads_mode = 'FIXED'`, `threads`, `use_persistent_data = True` (steady renders "
    "keep the synced scene, like fogref keeps its loaded scene); `film_transparent = False`",
    "- `view_settings.view_transform = 'Standard'`, `look = 'None'`, `exposure = 0`, `gamma = 1`; "
    "output `OPEN_EXR`, `RGBA`, `color_depth = '32'` (linear float), written after the clock stops",
    "- sun: `Light.type = 'SUN'`, `angle = 0` (delta), `energy` = max(E), `color` = E / max(E); world "
    "`Background` color = sky radiance, strength 1; camera `sensor_fit = 'HORIZONTAL'`, `angle` = fov, "
    "`clip_start = 1e-4`, `clip_end = 1e7` (the default 100 m would cut the fog)",
    "- fog: a volume-only material on the fog box mesh: `Volume Scatter` (white, density sigma_t "
    "rho(z) albedo, `phase = 'HENYEY_GREENSTEIN'`) + `Volume Absorption` (black, density sigma_t "
    "rho(z) (1 - albedo)); rho from Math nodes on `Geometry.Position` z; "
    "`material.cycles.volume_sampling = 'MULTIPLE_IMPORTANCE'`",
]


def _link(nt, a, b):
    nt.links.new(a, b)


def _diffuse_material(name, rgb):
    m = bpy.data.materials.new(name)
    nt = m.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (*rgb, 1.0)
    d.inputs["Roughness"].default_value = 0.0  # Lambert
    _link(nt, d.outputs["BSDF"], out.inputs["Surface"])
    return m


def _fog_material(fog):
    """sigma_t(z) = sigma_t0 * sum_k density_k exp(-falloff_k (z - height_k)) on the world
    z (= fogref's y); Volume Scatter (white, density sigma_t * albedo, HG g) + Volume
    Absorption (black, density sigma_t * (1 - albedo))."""
    m = bpy.data.materials.new("fog")
    nt = m.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    _link(nt, geo.outputs["Position"], sep.inputs[0])
    rho = None
    for dens, fall, h in fog["layers"]:
        sub = nt.nodes.new("ShaderNodeMath")
        sub.operation = "SUBTRACT"
        _link(nt, sep.outputs["Z"], sub.inputs[0])
        sub.inputs[1].default_value = h
        mul = nt.nodes.new("ShaderNodeMath")
        mul.operation = "MULTIPLY"
        _link(nt, sub.outputs[0], mul.inputs[0])
        mul.inputs[1].default_value = -fall
        ex = nt.nodes.new("ShaderNodeMath")
        ex.operation = "EXPONENT"
        _link(nt, mul.outputs[0], ex.inputs[0])
        sc = nt.nodes.new("ShaderNodeMath")
        sc.operation = "MULTIPLY"
        _link(nt, ex.outputs[0], sc.inputs[0])
        sc.inputs[1].default_value = dens
        if rho is None:
            rho = sc.outputs[0]
        else:
            add = nt.nodes.new("ShaderNodeMath")
            add.operation = "ADD"
            _link(nt, rho, add.inputs[0])
            _link(nt, sc.outputs[0], add.inputs[1])
            rho = add.outputs[0]
    a = fog["albedo"]
    sig = []
    for k in (fog["sigma_t"] * a, fog["sigma_t"] * (1.0 - a)):
        n = nt.nodes.new("ShaderNodeMath")
        n.operation = "MULTIPLY"
        _link(nt, rho, n.inputs[0])
        n.inputs[1].default_value = k
        sig.append(n.outputs[0])
    scat = nt.nodes.new("ShaderNodeVolumeScatter")
    scat.phase = "HENYEY_GREENSTEIN"
    scat.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    scat.inputs["Anisotropy"].default_value = fog["g"]
    _link(nt, sig[0], scat.inputs["Density"])
    absn = nt.nodes.new("ShaderNodeVolumeAbsorption")
    absn.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    _link(nt, sig[1], absn.inputs["Density"])
    add = nt.nodes.new("ShaderNodeAddShader")
    _link(nt, scat.outputs[0], add.inputs[0])
    _link(nt, absn.outputs[0], add.inputs[1])
    _link(nt, add.outputs[0], out.inputs["Volume"])
    m.cycles.volume_sampling = "MULTIPLE_IMPORTANCE"  # default: distance + equiangular
    return m


def _box(name, lo, hi, mat):
    """Axis-aligned box (Blender coordinates), outward faces."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    v = [
        (x0, y0, z0),
        (x1, y0, z0),
        (x1, y1, z0),
        (x0, y1, z0),
        (x0, y0, z1),
        (x1, y0, z1),
        (x1, y1, z1),
        (x0, y1, z1),
    ]
    f = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    return _mesh(name, v, f, mat)


def _mesh(name, verts, faces, mat):
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    me.update()
    me.materials.append(mat)
    ob = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(ob)
    return ob


def _bbox(lo, hi):
    a, b = to_blender(lo), to_blender(hi)
    return [min(a[i], b[i]) for i in range(3)], [max(a[i], b[i]) for i in range(3)]


def build(cfg):
    spec, (w, h) = cfg["spec"], cfg["res"]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    for k, v in fair_settings(cfg["max_depth"]).items():
        setattr(sc.cycles, k, v)
    r = sc.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
    r.threads_mode, r.threads = "FIXED", cfg["threads"]
    r.film_transparent = False
    sc.view_settings.view_transform = "Standard"
    sc.view_settings.look = "None"
    sc.view_settings.exposure = 0.0
    sc.view_settings.gamma = 1.0
    im = r.image_settings
    im.file_format, im.color_mode, im.color_depth, im.exr_codec = "OPEN_EXR", "RGBA", "32", "NONE"
    # camera: fogref's look_at (up = +y) -> Blender camera looking down its -Z, up +Y
    cam = bpy.data.cameras.new("cam")
    cam.sensor_fit = "HORIZONTAL"
    cam.angle = math.radians(spec["fov"])
    cam.clip_start, cam.clip_end = 1e-4, 1e7  # defaults 0.1 / 100 m would cut the fog
    co = bpy.data.objects.new("cam", cam)
    sc.collection.objects.link(co)
    o, t = Vector(to_blender(spec["origin"])), Vector(to_blender(spec["target"]))
    co.location = o
    co.rotation_mode = "QUATERNION"
    co.rotation_quaternion = (t - o).to_track_quat("-Z", "Y")
    sc.camera = co
    if spec.get("sun") is not None:
        lamp = bpy.data.lights.new("sun", "SUN")
        lamp.angle = 0.0  # delta light, like Mitsuba's directional
        E = spec["sun"]
        s = max(E)
        lamp.energy = s  # W/m^2 irradiance on a surface facing the sun
        lamp.color = tuple(e / s for e in E)
        lo = bpy.data.objects.new("sun", lamp)
        sc.collection.objects.link(lo)
        lo.rotation_mode = "QUATERNION"
        lo.rotation_quaternion = Vector(to_blender(spec["sun_dir"])).to_track_quat("-Z", "Y")
    world = bpy.data.worlds.new("world")
    sc.world = world
    bg = world.node_tree.nodes.get("Background") or world.node_tree.nodes.new("ShaderNodeBackground")
    sky = spec.get("sky") or [0.0, 0.0, 0.0]
    bg.inputs["Color"].default_value = (*sky, 1.0)
    bg.inputs["Strength"].default_value = 1.0
    if not world.node_tree.nodes.get("World Output"):
        wo = world.node_tree.nodes.new("ShaderNodeOutputWorld")
        world.node_tree.links.new(bg.outputs[0], wo.inputs["Surface"])
    g = spec["ground"][0]
    _mesh(
        "ground",
        [(-g, -g, 0), (g, -g, 0), (g, g, 0), (-g, g, 0)],
        [(0, 1, 2, 3)],
        _diffuse_material("ground", spec["ground"][1]),
    )
    rock = _diffuse_material("rock", spec["rock"])
    for i, (s, ang, c) in enumerate(spec["boxes"]):
        assert ang == 0, "only axis-aligned boxes"
        _box(f"box{i}", *_bbox([c[k] - s[k] for k in range(3)], [c[k] + s[k] for k in range(3)]), rock)
    _box("fogbox", *_bbox(*spec["bounds"]), _fog_material(spec["fog"]))
    sc.frame_set(1)


def render(cmd, exr):
    sc = bpy.context.scene
    sc.cycles.samples = int(cmd["spp"])
    sc.cycles.seed = int(cmd["seed"])
    sc.render.use_persistent_data = bool(cmd.get("persistent", True))
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=False)
    wall = time.perf_counter() - t0
    bpy.data.images["Render Result"].save_render(exr)
    return wall


def reply(d):
    sys.stdout.write("@@CY " + json.dumps(d) + "\n")
    sys.stdout.flush()


def main():
    global bpy, Vector, IMPORT_S
    t0 = time.perf_counter()
    import bpy
    from mathutils import Vector

    IMPORT_S = time.perf_counter() - t0
    cfg = json.loads(sys.stdin.readline())
    t0 = time.perf_counter()
    build(cfg)
    reply(
        {
            "import_s": IMPORT_S,
            "build_s": time.perf_counter() - t0,
            "versions": {"blender": bpy.app.version_string},
        }
    )
    for line in sys.stdin:
        if not line.strip():
            continue
        cmd = json.loads(line)
        if cmd.get("quit"):
            break
        reply({"wall_s": render(cmd, cfg["exr"])})


if __name__ == "__main__":
    main()
