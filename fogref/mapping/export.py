"""Paste-ready engine settings: a model's fog parameters, the camera and the sun, as each engine's
users write them.

:func:`export` turns a built-in model's settings (a fit, a translation, ``--param``), a
:class:`Camera` and a :class:`Sun` (fogref's frame: **y-up, right-handed, metres**; the sun
direction points toward the sun) into text for one engine (:data:`ENGINES`):

==========  ============  =====================================================================
engine      model         what is written
==========  ============  =====================================================================
unreal      ``ue4``       UE Python (Editor scripting): ExponentialHeightFog, DirectionalLight,
                          CameraActor; z-up, left-handed, cm (``world_to_unreal``)
godot       ``godot``     an ``Environment`` ``.tres`` and a ``.tscn`` with WorldEnvironment,
                          Camera3D and DirectionalLight3D (y-up, right-handed, metres, -Z forward)
bevy        ``bevy``      Rust: a system spawning Camera3d + DistanceFog + Exposure and a
                          DirectionalLight (Bevy 0.15+; y-up, right-handed, metres)
threejs     ``threejs``   JavaScript (ES module): ``scene.fog``, a DirectionalLight, the camera
unity       ``unity``     C#: RenderSettings fog, the camera and the sun (y-up, **left-handed**:
                          ``z -> -z``; the light's intensity is the irradiance / pi, since the
                          built-in Standard BRDF leaves out the diffuse 1/pi)
hdrp        ``hdrp``      C#: the Fog volume override, the camera and the sun (as unity)
filament    ``filament``  JavaScript: ``view.setFogOptions``, a SUN light, the camera
==========  ============  =====================================================================

Units.  fogref's radiance unit is read as 1 cd/m² and its irradiance unit as 1 lux, so a
light's colour times its intensity is fogref's sun irradiance in lux and the fog colours keep
their values (every engine here sets the exposure to 1, or has no exposure, in the written
snippet: Bevy ``Exposure { ev100: -log2(1.2) }``, Filament ``setExposureDirect(1)``).  Colours
are written in the space each engine's API or file takes (:mod:`fogref.models.terms`).

Where the engine's fog lobe is scaled by the sun light itself, the fog's colour is divided so
that the engine's product equals the fit:

* Unreal multiplies DirectionalInscatteringColor by the sun light's luminance
  (``FogRendering.cpp``; :data:`UNREAL_LUMINANCE_WEIGHTS`): written
  ``DirectionalInscatteringColor * SunLuminance / Y(light)``.
* Bevy multiplies ``directional_light_color`` by the light's colour times illuminance times
  exposure: written ``directional_light_color * light_color / E`` per channel.
* Godot's lobe is the shader's light (linear colour times ``light_energy`` times pi: Godot
  multiplies the energy by pi without physical light units, ``light_storage.cpp``) times
  ``fog_sun_scatter``: the shader's light is the sun (``light_energy = max(E) / pi``) and
  ``fog_sun_scatter`` is the least-squares scale ``s = (sun_color . E) / (E . E)``; the snippet
  states how far ``s E`` is from ``sun_color``.
* Filament's lobe is the sun light's colour times intensity with no scale of its own: the light
  is written as the fitted ``lightColorIntensity`` (the fog as fitted) and the snippet states
  the physical sun's irradiance beside it.

Each writer returns ``{suffix: text}`` (Godot two files, the others one).

Examples
--------
>>> from fogref.models.threejs import ThreeFogParams
>>> cam = Camera(origin=(0.0, 2.0, 0.0), target=(0.15, 2.35, 1.0))
>>> sun = Sun(direction=(0.4, 0.139, 0.906), irradiance=(3.2, 2.9, 2.4))
>>> text = export("threejs", ThreeFogParams(mode="FogExp2", density=0.001), cam, sun)[".mjs"]
>>> "new THREE.FogExp2(" in text
True
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from fogref.display import luminance
from fogref.errors import ParameterError, did_you_mean
from fogref.models.resolve import resolve_model
from fogref.models.terms import linear_to_srgb
from fogref.models.ue4 import direction_to_unreal, unreal_rotator, world_to_unreal

__all__ = ["ENGINES", "Camera", "Sun", "export", "light_split"]

#: ``--engine`` name -> the registry name of the model whose settings it writes.
ENGINES = {
    "unreal": "ue4",
    "godot": "godot",
    "bevy": "bevy",
    "threejs": "threejs",
    "unity": "unity",
    "hdrp": "hdrp",
    "filament": "filament",
}
#: ``FLinearColor::ComputeLuminance`` weights of R, G, B (Unreal,
#: ``Engine/Source/Runtime/Core/Public/Math/Color.h``): the sun luminance that multiplies the
#: fog's DirectionalInscatteringColor.
UNREAL_LUMINANCE_WEIGHTS = (0.3, 0.59, 0.11)
#: Bevy's ``Exposure::ev100`` for an exposure of 1 (``exposure = 2^-ev100 / 1.2``).
BEVY_UNIT_EV100 = -math.log2(1.2)


@dataclass(frozen=True)
class Camera:
    """A pinhole camera in fogref's frame: ``origin`` and ``target`` [m], ``up`` (any vector not
    along the view), the horizontal field of view ``fov_deg`` [deg], ``resolution`` (W, H) [px]
    and the clip planes [m]."""

    origin: Sequence[float]
    target: Sequence[float]
    up: Sequence[float] = (0.0, 1.0, 0.0)
    fov_deg: float = 70.0
    resolution: Sequence[int] = (320, 180)
    near: float = 0.1
    far: float = 20000.0

    @property
    def forward(self) -> np.ndarray:
        f = np.asarray(self.target, float) - np.asarray(self.origin, float)
        n = float(np.linalg.norm(f))
        if not n > 0:
            raise ParameterError("<Camera>", "target", "equals the origin: the camera has no view direction")
        return f / n

    @property
    def right(self) -> np.ndarray:
        r = np.cross(self.forward, np.asarray(self.up, float))
        n = float(np.linalg.norm(r))
        if not n > 0:
            raise ParameterError("<Camera>", "up", "is along the view direction")
        return r / n

    @property
    def true_up(self) -> np.ndarray:
        """The camera's orthonormal up (``right x forward``)."""
        return np.cross(self.right, self.forward)

    @property
    def aspect(self) -> float:
        return float(self.resolution[0]) / float(self.resolution[1])

    @property
    def fov_y_deg(self) -> float:
        """The vertical field of view [deg] (Godot, Bevy, three.js, Unity and Filament take it)."""
        return math.degrees(2 * math.atan(math.tan(math.radians(self.fov_deg) / 2) / self.aspect))


@dataclass(frozen=True)
class Sun:
    """The sun: ``direction`` toward it (fogref frame, any length) and its ``irradiance`` RGB on a
    plane facing it (fogref's units, read as lux)."""

    direction: Sequence[float]
    irradiance: Sequence[float]

    @property
    def w(self) -> np.ndarray:
        w = np.asarray(self.direction, float)
        return w / np.linalg.norm(w)


def light_split(rgb: Any) -> tuple[tuple[float, float, float], float]:
    """A light's linear colour (largest channel 1) and intensity whose product is ``rgb``.

    >>> light_split((3.2, 1.6, 0.0))
    ((1.0, 0.5, 0.0), 3.2)
    >>> light_split((0.0, 0.0, 0.0))
    ((1.0, 1.0, 1.0), 0.0)
    """
    c = [float(x) for x in rgb[:3]]
    m = max(c)
    if not m > 0:
        return (1.0, 1.0, 1.0), 0.0
    return (c[0] / m, c[1] / m, c[2] / m), m


def _f(x: float) -> str:
    """A float as a literal every target language reads (always a '.' or an exponent)."""
    s = f"{float(x):.9g}"
    return s if ("." in s or "e" in s or "inf" in s or "nan" in s) else s + ".0"


def _fs(xs: Any) -> str:
    return ", ".join(_f(x) for x in xs)


def _header(comment: str, engine: str, source: str, lines: Sequence[str]) -> str:
    body = [
        f"fogref export --engine {engine}: {source}",
        "fogref's units: radiance 1 = 1 cd/m^2, irradiance 1 = 1 lux; exposure 1.",
        *lines,
    ]
    return "\n".join(f"{comment} {b}".rstrip() for b in body) + "\n"


# -- Unreal ---------------------------------------------------------------------------------------


def _srgb8(lin: Sequence[float]) -> tuple[int, int, int]:
    """An FColor (sRGB, 8 bits) of a linear colour in [0, 1]."""
    return tuple(int(round(min(max(c, 0.0), 1.0) * 255)) for c in linear_to_srgb(lin[:3]))  # type: ignore[return-value]


def _srgb8_to_linear(c8: Sequence[int]) -> tuple[float, ...]:
    """FLinearColor(FColor): the sRGB decoding of 8-bit values (``sRGBToLinearTable``)."""
    return tuple(x / 12.92 if x <= 0.04045 else ((x + 0.055) / 1.055) ** 2.4 for x in (c / 255.0 for c in c8))


def unreal_plan(p: Any, cam: Camera, sun: Sun) -> dict:
    """The values the Unreal snippet writes (also what the tests read back)."""
    colour, intensity = light_split(sun.irradiance)
    c8 = _srgb8(colour)
    light_lum = float(np.dot(UNREAL_LUMINANCE_WEIGHTS, _srgb8_to_linear(c8))) * intensity
    scale = p.SunLuminance / light_lum if light_lum > 0 else 0.0
    fwd = direction_to_unreal(cam.forward)
    return {
        "fog_location_cm": (0.0, 0.0, p.FogHeight),
        "FogInscatteringColor": tuple(p.FogInscatteringColor),
        "DirectionalInscatteringColor": tuple(c * scale for c in p.DirectionalInscatteringColor),
        "light_color_srgb8": c8,
        "light_intensity_lux": intensity,
        "light_luminance": light_lum,
        "sun_rotation": unreal_rotator(direction_to_unreal(-sun.w)),
        "camera_location_cm": tuple(float(x) for x in world_to_unreal(cam.origin)),
        "camera_rotation": unreal_rotator(fwd, direction_to_unreal(cam.true_up)),
        "camera_fov_deg": cam.fov_deg,
        "aspect": cam.aspect,
    }


def _unreal(p: Any, cam: Camera, sun: Sun, source: str) -> dict[str, str]:
    q = unreal_plan(p, cam, sun)

    def rot(r: dict) -> str:
        return f"unreal.Rotator(roll={_f(r['roll'])}, pitch={_f(r['pitch'])}, yaw={_f(r['yaw'])})"

    def lin(c: Sequence[float]) -> str:
        return f"unreal.LinearColor({_fs(c)}, 1.0)"

    r, g, b = q["light_color_srgb8"]
    s = p.SecondFogData
    head = _header(
        "#",
        "unreal",
        source,
        [
            "Run in the Unreal Editor (Python Editor Script Plugin): Tools > Execute Python Script.",
            "Unreal is z-up, left-handed, cm: (x, y, z)_ue = 100 (x, z, y)_fogref.",
            "Colours: FLinearColor values are linear (as the details panel shows them); the light's",
            "FColor is sRGB.  DirectionalInscatteringColor is the fit's, divided by the sun light's",
            f"luminance {q['light_luminance']:.6g} (Unreal multiplies it back on the CPU).",
            "UE 5.1+ names the colours ...Luminance: set_first() takes either name.",
        ],
    )
    fog_props = [
        ("fog_density", _f(p.FogDensity), True),
        ("fog_height_falloff", _f(p.FogHeightFalloff), True),
        ("fog_max_opacity", _f(p.FogMaxOpacity), True),
        ("start_distance", _f(p.StartDistance), True),
        ("fog_cutoff_distance", _f(p.FogCutoffDistance), True),
        ("end_distance", _f(p.EndDistance), p.EndDistance > 0),
        ("directional_inscattering_exponent", _f(p.DirectionalInscatteringExponent), True),
        ("directional_inscattering_start_distance", _f(p.DirectionalInscatteringStartDistance), True),
    ]
    lines = [
        head,
        "import unreal",
        "",
        "",
        "def set_first(obj, names, value, required=True):",
        '    """Set the first of ``names`` that ``obj`` has (property names differ between versions)."""',
        "    for name in names:",
        "        try:",
        "            obj.set_editor_property(name, value)",
        "            return name",
        "        except Exception:",
        "            pass",
        "    if required:",
        '        raise RuntimeError(f"{obj.get_name()} has none of {names}")',
        "    return None",
        "",
        "",
        "try:  # UE 5",
        "    spawn = unreal.get_editor_subsystem(unreal.EditorActorSubsystem).spawn_actor_from_class",
        "except AttributeError:  # UE 4.26-4.27",
        "    spawn = unreal.EditorLevelLibrary.spawn_actor_from_class",
        "",
        "fog_actor = spawn(",
        f"    unreal.ExponentialHeightFog, unreal.Vector({_fs(q['fog_location_cm'])})",
        ")",
        "fog = fog_actor.get_component_by_class(unreal.ExponentialHeightFogComponent)",
    ]
    for name, value, required in fog_props:
        if required:
            lines.append(f'set_first(fog, ["{name}"], {value})')
    lines += [
        "set_first(fog, ['fog_inscattering_color', 'fog_inscattering_luminance'], "
        f"{lin(q['FogInscatteringColor'])})",
        "set_first(fog, ['directional_inscattering_color', 'directional_inscattering_luminance'], "
        f"{lin(q['DirectionalInscatteringColor'])})",
    ]
    if s.FogDensity > 0:
        lines += [
            "second = unreal.ExponentialHeightFogData()",
            f"second.set_editor_property('fog_density', {_f(s.FogDensity)})",
            f"second.set_editor_property('fog_height_falloff', {_f(s.FogHeightFalloff)})",
            f"second.set_editor_property('fog_height_offset', {_f(s.FogHeightOffset)})",
            "set_first(fog, ['second_fog_data'], second)",
        ]
    lines += [
        "",
        "# the sun: its X axis is the direction the light travels; intensity in lux",
        "sun_actor = spawn(",
        f"    unreal.DirectionalLight, unreal.Vector(0.0, 0.0, 0.0), {rot(q['sun_rotation'])}",
        ")",
        "sun = sun_actor.get_component_by_class(unreal.DirectionalLightComponent)",
        f"sun.set_editor_property('intensity', {_f(q['light_intensity_lux'])})",
        f"sun.set_editor_property('light_color', unreal.Color(r={r}, g={g}, b={b}, a=255))",
        "set_first(sun, ['atmosphere_sun_light', 'used_as_atmosphere_sun_light'], True, required=False)",
        "",
        "# the camera: horizontal field of view [deg]",
        "camera_actor = spawn(",
        f"    unreal.CameraActor, unreal.Vector({_fs(q['camera_location_cm'])}), {rot(q['camera_rotation'])}",
        ")",
        "camera = camera_actor.get_component_by_class(unreal.CameraComponent)",
        f"camera.set_editor_property('field_of_view', {_f(q['camera_fov_deg'])})",
        f"camera.set_editor_property('aspect_ratio', {_f(q['aspect'])})",
    ]
    return {".py": "\n".join(lines) + "\n"}


# -- Godot ----------------------------------------------------------------------------------------


def _basis_text(x: np.ndarray, y: np.ndarray, z: np.ndarray, origin: Sequence[float]) -> str:
    """Godot's ``Transform3D(...)``: the basis row by row (its columns are the local axes), then
    the origin (``variant_parser.cpp``)."""
    m = np.stack([x, y, z], axis=1)
    return "Transform3D(" + _fs([*m.reshape(-1), *origin]) + ")"


def _frame(z: np.ndarray, up: Sequence[float] = (0.0, 1.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """X and Y axes completing a right-handed frame around the unit axis ``z``."""
    u = np.asarray(up, float)
    if abs(float(u @ z)) > 0.999:
        u = np.array([0.0, 0.0, 1.0])
    x = np.cross(u, z)
    x /= np.linalg.norm(x)
    return x, np.cross(z, x)


def godot_plan(p: Any, cam: Camera, sun: Sun) -> dict:
    """The values the Godot files write."""
    E = np.asarray(sun.irradiance, float)[:3]
    colour, energy = light_split(E)
    ee = float(E @ E)
    s = float(np.asarray(p.sun_color, float) @ E) / ee if ee > 0 else 0.0
    lobe = s * E
    target = np.asarray(p.sun_color, float)
    denom = float(np.linalg.norm(target))
    return {
        "fog_light_color_srgb": linear_to_srgb(p.fog_light_color),
        "fog_sun_scatter": p.fog_sun_scatter * s,
        "sun_lobe_relative_error": float(np.linalg.norm(lobe - target)) / denom if denom > 0 else 0.0,
        "light_color_srgb": linear_to_srgb(colour),
        "light_energy": energy / math.pi,
        "light_intensity_lux": energy,
        "light_z": sun.w,
        "camera_x": cam.right,
        "camera_y": cam.true_up,
        "camera_z": -cam.forward,
    }


def _godot(p: Any, cam: Camera, sun: Sun, source: str) -> dict[str, str]:
    q = godot_plan(p, cam, sun)
    head = [
        "Godot 4 (y-up, right-handed, metres, like fogref; cameras and lights look along -Z).",
        "Colours are sRGB, as the inspector shows them and .tres files store them.",
        "The shader's light is light_color (linear) x light_energy x pi (light_storage.cpp) = the sun's",
        "irradiance.  The sun lobe is that light x fog_sun_scatter: fog_sun_scatter scales the",
        f"sun (E) to the fitted sun_color, whose direction differs from E's by "
        f"{q['sun_lobe_relative_error']:.3g} (relative).",
        f"With physical light units: light_energy = 1, light_intensity_lux = {q['light_intensity_lux']:.6g}.",
    ]
    depth = p.fog_mode == "depth"
    env = [
        '[gd_resource type="Environment" format=3]',
        "",
        _header(";", "godot", source, head).rstrip("\n"),
        "",
        "[resource]",
        "fog_enabled = true",
        f"fog_mode = {1 if depth else 0}",
        f"fog_light_color = Color({_fs(q['fog_light_color_srgb'])}, 1.0)",
        f"fog_light_energy = {_f(p.fog_light_energy)}",
        f"fog_sun_scatter = {_f(q['fog_sun_scatter'])}",
        f"fog_density = {_f(p.fog_density)}",
        f"fog_aerial_perspective = {_f(p.fog_aerial_perspective)}",
        f"fog_sky_affect = {_f(p.fog_sky_affect)}",
        f"fog_height = {_f(p.fog_height)}",
        f"fog_height_density = {_f(p.fog_height_density)}",
        f"fog_depth_curve = {_f(p.fog_depth_curve)}",
        f"fog_depth_begin = {_f(p.fog_depth_begin)}",
        f"fog_depth_end = {_f(p.fog_depth_end)}",
    ]
    lx, ly = _frame(q["light_z"])
    tscn = [
        "[gd_scene load_steps=2 format=3]",
        "",
        _header(
            ";",
            "godot",
            source,
            ["The camera, the sun and res://fogref_environment.tres (save the .tres there)."],
        ).rstrip("\n"),
        "",
        '[ext_resource type="Environment" path="res://fogref_environment.tres" id="1"]',
        "",
        '[node name="Fogref" type="Node3D"]',
        "",
        '[node name="WorldEnvironment" type="WorldEnvironment" parent="."]',
        'environment = ExtResource("1")',
        "",
        '[node name="Camera3D" type="Camera3D" parent="."]',
        f"transform = {_basis_text(q['camera_x'], q['camera_y'], q['camera_z'], cam.origin)}",
        f"fov = {_f(cam.fov_y_deg)}",
        f"near = {_f(cam.near)}",
        f"far = {_f(p.z_far)}",
        "",
        '[node name="Sun" type="DirectionalLight3D" parent="."]',
        f"transform = {_basis_text(lx, ly, q['light_z'], (0.0, 0.0, 0.0))}",
        f"light_color = Color({_fs(q['light_color_srgb'])}, 1.0)",
        f"light_energy = {_f(q['light_energy'])}",
    ]
    return {".tres": "\n".join(env) + "\n", ".tscn": "\n".join(tscn) + "\n"}


# -- Bevy -----------------------------------------------------------------------------------------


def bevy_plan(p: Any, cam: Camera, sun: Sun) -> dict:
    """The values the Rust snippet writes."""
    E = np.asarray(sun.irradiance, float)[:3]
    colour, illuminance = light_split(E)
    dl = list(p.directional_light_color)
    for i in range(3):
        dl[i] = dl[i] * p.light_color[i] / E[i] if E[i] > 0 else 0.0
    return {"light_color": colour, "illuminance": illuminance, "directional_light_color": tuple(dl)}


def _v3(v: Any) -> str:
    return f"Vec3::new({_fs(v)})"


def _bevy(p: Any, cam: Camera, sun: Sun, source: str) -> dict[str, str]:
    q = bevy_plan(p, cam, sun)
    if p.falloff == "Linear":
        falloff = f"FogFalloff::Linear {{ start: {_f(p.start)}, end: {_f(p.end)} }}"
    elif p.falloff in ("Exponential", "ExponentialSquared"):
        falloff = f"FogFalloff::{p.falloff} {{ density: {_f(p.density)} }}"
    else:
        falloff = (
            f"FogFalloff::Atmospheric {{ extinction: {_v3(p.extinction)}, "
            f"inscattering: {_v3(p.inscattering)} }}"
        )
    head = [
        "Bevy 0.15+ (y-up, right-handed, metres, like fogref; -Z forward).  Colours: Color::linear_rgba.",
        "Exposure 1 (ev100 = -log2 1.2): the light's colour x illuminance is fogref's sun irradiance",
        "and directional_light_color is the fit's divided by it per channel (Bevy multiplies them).",
        "Add `.add_systems(Startup, spawn_fogref)` to your App.",
    ]
    lines = [
        _header("//", "bevy", source, head).rstrip("\n"),
        "use bevy::pbr::{DistanceFog, FogFalloff};",
        "use bevy::prelude::*;",
        "use bevy::render::camera::Exposure;",
        "",
        "pub fn spawn_fogref(mut commands: Commands) {",
        "    commands.spawn((",
        "        Camera3d::default(),",
        "        Projection::Perspective(PerspectiveProjection {",
        f"            fov: {_f(math.radians(cam.fov_y_deg))},",
        f"            near: {_f(cam.near)},",
        f"            far: {_f(cam.far)},",
        "            ..default()",
        "        }),",
        f"        Transform::from_translation({_v3(cam.origin)})",
        f"            .looking_at({_v3(cam.target)}, {_v3(cam.up)}),",
        f"        Exposure {{ ev100: {_f(BEVY_UNIT_EV100)} }},",
        "        DistanceFog {",
        f"            color: Color::linear_rgba({_fs(p.color)}),",
        f"            directional_light_color: Color::linear_rgba({_fs(q['directional_light_color'])}),",
        f"            directional_light_exponent: {_f(p.directional_light_exponent)},",
        f"            falloff: {falloff},",
        "        },",
        "    ));",
        "    commands.spawn((",
        "        DirectionalLight {",
        f"            color: Color::linear_rgb({_fs(q['light_color'])}),",
        f"            illuminance: {_f(q['illuminance'])},",
        "            ..default()",
        "        },",
        f"        Transform::default().looking_to({_v3(-sun.w)}, Vec3::Y),",
        "    ));",
        "}",
    ]
    return {".rs": "\n".join(lines) + "\n"}


# -- three.js -------------------------------------------------------------------------------------


def _three(p: Any, cam: Camera, sun: Sun, source: str) -> dict[str, str]:
    colour, intensity = light_split(sun.irradiance)
    fog = (
        f"new THREE.FogExp2(fogColor, {_f(p.density)})"
        if p.mode == "FogExp2"
        else f"new THREE.Fog(fogColor, {_f(p.near)}, {_f(p.far)})"
    )
    head = [
        "three.js r155+ (y-up, right-handed, metres, like fogref; the camera looks along -Z).",
        "Colours: setRGB(..., THREE.LinearSRGBColorSpace) takes linear values (a hex would be sRGB).",
        "The light's colour x intensity is fogref's sun irradiance; no tone mapping, exposure 1.",
    ]
    lines = [
        _header("//", "threejs", source, head).rstrip("\n"),
        "import * as THREE from 'three';",
        "",
        "export function applyFogref(scene) {",
        f"  const fogColor = new THREE.Color().setRGB({_fs(p.color)}, THREE.LinearSRGBColorSpace);",
        f"  scene.fog = {fog};",
        "",
        f"  const sun = new THREE.DirectionalLight(new THREE.Color().setRGB({_fs(colour)}, "
        f"THREE.LinearSRGBColorSpace), {_f(intensity)});",
        f"  sun.position.set({_fs(sun.w * 1000.0)});  // toward the sun; the target stays at the origin",
        "  scene.add(sun);",
        "  scene.add(sun.target);",
        "",
        "  const camera = new THREE.PerspectiveCamera("
        f"{_f(cam.fov_y_deg)}, {_f(cam.aspect)}, {_f(cam.near)}, {_f(cam.far)});",
        f"  camera.position.set({_fs(cam.origin)});",
        f"  camera.up.set({_fs(cam.up)});",
        f"  camera.lookAt({_fs(cam.target)});",
        "  return { camera, sun };",
        "}",
    ]
    return {".mjs": "\n".join(lines) + "\n"}


# -- Unity and HDRP -------------------------------------------------------------------------------


def _unity_vec(v: Any) -> str:
    """fogref (right-handed) -> Unity (left-handed, y-up): ``z -> -z``."""
    return f"new Vector3({_f(v[0])}f, {_f(v[1])}f, {_f(-v[2])}f)"


def _unity_colour_gamma(c: Any) -> str:
    return f"new Color({_f(c[0])}f, {_f(c[1])}f, {_f(c[2])}f).gamma"


def _unity_script(
    engine: str, source: str, head: list[str], fog: list[str], cam: Camera, sun: Sun
) -> dict[str, str]:
    """The C# class of ``engine`` ("unity" or "hdrp") whose ``Apply`` runs the ``fog`` lines, then
    sets the camera and the sun (in lux for HDRP)."""
    hdrp = engine == "hdrp"
    colour, intensity = light_split(sun.irradiance)
    if hdrp:
        unit = "lux (HDRP)"
    else:  # UnityStandardBRDF.cginc leaves out the diffuse 1/pi: the light carries it
        intensity /= math.pi
        unit = "built-in pipeline: irradiance / pi (its Standard BRDF leaves out the diffuse 1/pi)"
    lines = [
        _header("//", engine, source, head).rstrip("\n"),
        "using UnityEngine;",
        *(["using UnityEngine.Rendering;", "using UnityEngine.Rendering.HighDefinition;"] if hdrp else []),
        "",
        f"public static class {'FogrefHdrpFog' if hdrp else 'FogrefFog'}",
        "{",
        f"    public static void Apply({'VolumeProfile profile, ' if hdrp else ''}Camera camera, Light sun)",
        "    {",
        *fog,
        "        camera.transform.position = " + _unity_vec(cam.origin) + ";",
        "        camera.transform.rotation = Quaternion.LookRotation("
        + _unity_vec(cam.forward)
        + ", "
        + _unity_vec(cam.true_up)
        + ");",
        f"        camera.fieldOfView = {_f(cam.fov_y_deg)}f;  // vertical [deg]",
        f"        camera.nearClipPlane = {_f(cam.near)}f;",
        f"        camera.farClipPlane = {_f(cam.far)}f;",
        "        sun.type = LightType.Directional;",
        "        sun.transform.rotation = Quaternion.LookRotation(" + _unity_vec(-sun.w) + ");",
        f"        sun.color = {_unity_colour_gamma(colour)};  // linear -> Unity's sRGB Color",
        f"        sun.intensity = {_f(intensity)}f;  // {unit}",
        "    }",
        "}",
    ]
    return {".cs": "\n".join(lines) + "\n"}


def _unity(p: Any, cam: Camera, sun: Sun, source: str) -> dict[str, str]:
    mode = {"linear": "Linear", "exp": "Exponential", "exp2": "ExponentialSquared"}[p.fogMode]
    head = [
        "Unity built-in pipeline, Linear colour space (Player settings).  Unity is y-up, left-handed,",
        "metres: (x, y, z)_unity = (x, y, -z)_fogref.  Color values are sRGB: .gamma converts fogref's",
        f"linear values.  fogref's fog coordinate: {p.fog_coordinate} (Unity's built-in fog uses depth",
        "unless the shader computes the distance).",
    ]
    fog = [
        "        RenderSettings.fog = true;",
        f"        RenderSettings.fogMode = FogMode.{mode};",
        f"        RenderSettings.fogDensity = {_f(p.fogDensity)}f;",
        f"        RenderSettings.fogStartDistance = {_f(p.fogStartDistance)}f;",
        f"        RenderSettings.fogEndDistance = {_f(p.fogEndDistance)}f;",
        f"        RenderSettings.fogColor = {_unity_colour_gamma(p.fogColor)};",
    ]
    return _unity_script("unity", source, head, fog, cam, sun)


def _hdrp(p: Any, cam: Camera, sun: Sun, source: str) -> dict[str, str]:
    head = [
        "HDRP (y-up, left-handed, metres: (x, y, z)_unity = (x, y, -z)_fogref).  The Fog override's",
        "colours go to the shader as they are (Fog.cs): linear.  The sun's Light colour is sRGB (.gamma).",
    ]

    def col(c: Sequence[float]) -> str:
        return f"new Color({_f(c[0])}f, {_f(c[1])}f, {_f(c[2])}f)"

    fog = [
        "        if (!profile.TryGet(out Fog fog))",
        "            fog = profile.Add<Fog>(true);",
        "        fog.enabled.Override(true);",
        "        fog.colorMode.Override(FogColorMode.ConstantColor);",
        f"        fog.color.Override({col(p.color)});",
        f"        fog.albedo.Override({col(p.albedo)});",
        f"        fog.meanFreePath.Override({_f(p.meanFreePath)}f);",
        f"        fog.baseHeight.Override({_f(p.baseHeight)}f);",
        f"        fog.maximumHeight.Override({_f(p.maximumHeight)}f);",
        f"        fog.maxFogDistance.Override({_f(p.maxFogDistance)}f);",
    ]
    return _unity_script("hdrp", source, head, fog, cam, sun)


# -- Filament -------------------------------------------------------------------------------------


def _filament(p: Any, cam: Camera, sun: Sun, source: str) -> dict[str, str]:
    lc = p.lightColorIntensity
    lobe = [lc[i] * lc[3] for i in range(3)]
    colour, intensity = light_split(lobe)
    E = luminance(sun.irradiance)
    ratio = E / luminance(lobe) if luminance(lobe) > 0 else math.inf
    head = [
        "Filament (y-up, right-handed, metres, like fogref).  Colours are linear (LinearColor).",
        "The fog's sun lobe is the SUN light's colour x intensity: the light is the fitted",
        f"lightColorIntensity; the physical sun's luminance is {E:.6g} lux ({ratio:.4g} x this light).",
    ]
    cut = "Infinity" if math.isinf(p.cutOffDistance) else _f(p.cutOffDistance)
    up = cam.true_up
    lines = [
        _header("//", "filament", source, head).rstrip("\n"),
        "export function applyFogref(Filament, engine, scene, view, camera) {",
        "  view.setFogOptions({",
        "    enabled: true,",
        f"    distance: {_f(p.distance)},",
        f"    cutOffDistance: {cut},",
        f"    maximumOpacity: {_f(p.maximumOpacity)},",
        f"    height: {_f(p.height)},",
        f"    heightFalloff: {_f(p.heightFalloff)},",
        f"    color: [{_fs(p.color)}],",
        f"    density: {_f(p.density)},",
        f"    inScatteringStart: {_f(p.inScatteringStart)},",
        f"    inScatteringSize: {_f(p.inScatteringSize)},",
        "    fogColorFromIbl: false,",
        "  });",
        "  const sun = Filament.EntityManager.get().create();",
        "  Filament.LightManager.Builder(Filament.LightManager$Type.SUN)",
        f"    .color([{_fs(colour)}])",
        f"    .intensity({_f(intensity)})",
        f"    .direction([{_fs(-sun.w)}])",
        "    .build(engine, sun);",
        "  scene.addEntity(sun);",
        f"  camera.lookAt([{_fs(cam.origin)}], [{_fs(cam.target)}], [{_fs(up)}]);",
        f"  camera.setProjectionFov({_f(cam.fov_y_deg)}, {_f(cam.aspect)}, {_f(cam.near)}, "
        f"{_f(cam.far)}, Filament.Camera$Fov.VERTICAL);",
        "  camera.setExposureDirect(1.0);",
        "  return sun;",
        "}",
    ]
    return {".mjs": "\n".join(lines) + "\n"}


_WRITERS: dict[str, Callable[[Any, Camera, Sun, str], dict[str, str]]] = {
    "unreal": _unreal,
    "godot": _godot,
    "bevy": _bevy,
    "threejs": _three,
    "unity": _unity,
    "hdrp": _hdrp,
    "filament": _filament,
}


def export(engine: str, params: Any, camera: Camera, sun: Sun, source: str = "") -> dict[str, str]:
    """Paste-ready text for ``engine`` (:data:`ENGINES`): ``{suffix: text}``.

    ``params``: the model's ``Params`` dataclass (``ENGINES[engine]``'s model); ``camera``,
    ``sun``: fogref's frame; ``source``: one line saying where the settings come from (written
    at the top).  ParameterError for an unknown engine or settings of another model.
    """
    if engine not in _WRITERS:
        raise ParameterError(
            "fogref export",
            "--engine",
            f"{engine!r} is not one of {', '.join(ENGINES)}{did_you_mean(engine, ENGINES)}",
        )
    want = resolve_model(ENGINES[engine]).Params
    if not (dataclasses.is_dataclass(params) and isinstance(params, want)):
        raise ParameterError(
            "fogref export", "params", f"{engine} writes {want.__name__}, got {type(params).__name__}"
        )
    return _WRITERS[engine](params, camera, sun, source or "settings given to fogref.mapping.export")
