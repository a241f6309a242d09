"""The unit and colour space of every parameter of the built-in models, and where their defaults are from.

One definition per parameter, read by every output that prints a model's settings (``fogref fit``,
``translate``, ``study``, ``export``, the fit table).  A :class:`Term` gives

* ``unit``: the engine's unit of the value as fogref holds it (``"cm"``, ``"m"``, ``"1/m"``,
  ``"deg"``, ``"lux"``; ``"1"`` for a plain factor; Unreal's FogDensity and FogHeightFalloff are
  editor values, shown with what the shader makes of them);
* ``colour``: for a colour, the space the **engine's UI** (colour picker, serialised file or the
  code users type) uses: ``"linear"`` or ``"sRGB"``.  fogref itself holds every colour as
  **linear** RGB in the scene's radiance units (the shader's value); :func:`ui_colour` converts
  to the UI's space.

The colour spaces, from each engine's source:

* Unreal: ``FLinearColor`` properties (``ExponentialHeightFogComponent.h``): the details panel's
  R, G, B are linear (its picker's "Hex sRGB" field is the sRGB of the same colour).
* Godot 4: ``Color`` properties are sRGB in the inspector and in ``.tres`` files;
  ``render_scene_data_rd.cpp`` applies ``srgb_to_linear`` to ``fog_light_color``.
* Unity built-in: ``RenderSettings.fogColor`` and material ``Color`` properties are sRGB
  (gamma); a Linear-colour-space project linearises them for the shader (``Color.linear``).
* HDRP: ``Fog.cs`` passes the ``ColorParameter`` values to the constant buffer as they are
  (``cb._FogColor = new Color(fogColor.r, fogColor.g, fogColor.b, 0.0f)``): linear.
* Filament: ``View::FogOptions::color`` is a ``LinearColor``.
* Bevy: ``Color`` is an enum; fogref writes ``Color::linear_rgba`` (``Color::srgb`` would be sRGB).
* PlayCanvas: ``scene.fogColor`` is raised to the power 2.2 on the CPU before the shader
  (``"gamma 2.2"``).
* Babylon.js: ``scene.fogColor`` goes to the StandardMaterial shader as given: what you type is
  the shader's value.
* three.js (r152+, ``ColorManagement.enabled``): ``Color.setRGB(r, g, b, LinearSRGBColorSpace)``
  takes linear values; a hex ``0xRRGGBB`` is sRGB.

Examples
--------
>>> term("ue4", "StartDistance").unit
'cm'
>>> term("godot", "fog_light_color[2]").colour
'sRGB'
>>> describe("godot", "fog_light_color", (0.231082, 0.266417, 0.327964))
'(0.231, 0.266, 0.328) linear; sRGB in the engine: (0.518, 0.553, 0.608)'
>>> describe("ue4", "StartDistance", 3.80773e-06)
'3.81e-06 cm'
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

__all__ = [
    "DEFAULTS_FROM",
    "ENGINE",
    "TERMS",
    "Term",
    "annotate",
    "describe",
    "note",
    "linear_to_srgb",
    "term",
    "ui_colour",
    "unreal_field",
    "with_unit",
]


@dataclass(frozen=True)
class Term:
    """A parameter's unit (``"1"``: a plain factor; ``""``: no number, a mode or a name) and,
    for a colour, the space of the engine's UI (``"linear"`` or ``"sRGB"``; ``None``: not a
    colour)."""

    unit: str
    colour: str | None = None


_LIN = Term("linear RGB, scene radiance units", "linear")
_SRGB = Term("linear RGB, scene radiance units", "sRGB")
_DIR = Term("unit vector toward the sun, fogref frame (y-up)")
_MODE = Term("")
_ONE = Term("1")
_M = Term("m")
_PER_M = Term("1/m")

#: registry name -> parameter -> :class:`Term`.  A parameter not listed here has no unit fogref
#: knows (a user model); :func:`term` says so.
TERMS: dict[str, dict[str, Term]] = {
    "ue4": {
        "FogDensity": Term("editor value; the shader's density is value/1000 per cm (exp2)"),
        "FogHeightFalloff": Term("editor value; the shader's falloff is value/1000 per cm (exp2)"),
        "FogHeight": Term("cm"),
        "SecondFogData": Term("FogDensity, FogHeightFalloff: editor values; FogHeightOffset: cm"),
        "FogInscatteringColor": Term("linear RGB, scene radiance units", "linear"),
        "FogMaxOpacity": _ONE,
        "StartDistance": Term("cm"),
        "FogCutoffDistance": Term("cm"),
        "EndDistance": Term("cm"),
        "DirectionalInscatteringExponent": _ONE,
        "DirectionalInscatteringStartDistance": Term("cm"),
        "DirectionalInscatteringColor": Term(
            "linear RGB, scene radiance units per unit of the sun's luminance", "linear"
        ),
        "InscatteringLightDirection": Term("unit vector toward the sun, Unreal frame (z-up)"),
        "SunLuminance": Term("lux (the sun light's luminance)"),
        "ExpFogMatchesVolumetricFog": _MODE,
        "SkyAtmosphereAffectsHeightFog": _MODE,
        "VolumetricFogScatteringDistribution": Term("1 (the Henyey-Greenstein g)"),
        "VolumetricFogAlbedo": Term("linear RGB, 0..1", "linear"),
        "VolumetricFogEmissive": _LIN,
        "AtmosphereLightIlluminance": Term("linear RGB, scene radiance units x sr", "linear"),
        "SkyAtmosphereAmbient": _LIN,
    },
    "ue5_lfv": {
        "Location": Term("cm, Unreal frame (z-up)"),
        "FogUniformScale": Term("cm (the radius)"),
        "RadialFogExtinction": _PER_M,
        "HeightFogExtinction": _PER_M,
        "HeightFogFalloff": Term("editor value; the shader's falloff is max(value, 1)/100 per unit radius"),
        "HeightFogOffset": Term("unit-sphere units"),
        "FogAlbedo": Term("linear RGB, 0..1", "linear"),
        "FogPhaseG": Term("1 (the Henyey-Greenstein g)"),
        "FogEmissive": _LIN,
        "FogStartDistance": Term("cm"),
        "GlobalStartDistance": Term("cm"),
        "DirectionalLightDirection": Term("unit vector toward the sun, Unreal frame (z-up)"),
        "DirectionalLightColor": Term("linear RGB illuminance, scene radiance units x sr", "linear"),
        "SkyLighting": _LIN,
        "HeightFog": Term("the Exponential Height Fog behind the volume (ue4's parameters)"),
    },
    "unity": {
        "fogMode": _MODE,
        "fogDensity": _PER_M,
        "fogStartDistance": _M,
        "fogEndDistance": _M,
        "fogColor": _SRGB,
        "fog_coordinate": _MODE,
        "camera_forward": Term("unit view direction, fogref frame (y-up)"),
        "clip_near": _M,
        "clip_far": _M,
    },
    "hdrp": {
        "meanFreePath": _M,
        "baseHeight": _M,
        "maximumHeight": _M,
        "albedo": Term("linear RGB, 0..1", "linear"),
        "color": _LIN,
        "maxFogDistance": _M,
    },
    "filament": {
        "distance": _M,
        "cutOffDistance": _M,
        "maximumOpacity": _ONE,
        "height": _M,
        "heightFalloff": _PER_M,
        "color": _LIN,
        "density": _PER_M,
        "inScatteringStart": _M,
        "inScatteringSize": Term("1 (the lobe's exponent; < 0: no lobe)"),
        "lightDirection": _DIR,
        "lightColorIntensity": Term("linear RGB + intensity, scene radiance units", "linear"),
        "output": _MODE,
    },
    "altitude": {
        "_FogStart": _M,
        "_FogEnd": _M,
        "_FogPower": _ONE,
        "_FogColor": Term("RGB: linear, scene radiance units; A: density 1/m", "sRGB"),
    },
    "box": {
        "box_min": _M,
        "box_max": _M,
        "density": Term("1/m (modes thickness, beer); 1 (ratio)"),
        "fog_color": _SRGB,
        "mode": _MODE,
    },
    "godot": {
        "fog_mode": _MODE,
        "fog_light_color": _SRGB,
        "fog_light_energy": _ONE,
        "fog_sun_scatter": _ONE,
        "fog_density": Term("1/m (exponential mode); 1 (depth mode)"),
        "fog_aerial_perspective": _ONE,
        "fog_sky_affect": _ONE,
        "fog_height": _M,
        "fog_height_density": _PER_M,
        "fog_depth_curve": _ONE,
        "fog_depth_begin": _M,
        "fog_depth_end": _M,
        "z_far": _M,
        "sun_direction": _DIR,
        "sun_color": Term("linear RGB, the shader's light: linearised light_color x light_energy x pi"),
        "sky_color": Term("linear RGB, scene radiance units", "linear"),
        "sky_distance": _M,
    },
    "bevy": {
        "falloff": _MODE,
        "start": _M,
        "end": _M,
        "density": _PER_M,
        "extinction": Term("1/m per channel"),
        "inscattering": Term("1/m per channel"),
        "color": Term("linear RGBA, scene radiance units", "linear"),
        "directional_light_color": Term("linear RGBA, per unit of the light's colour", "linear"),
        "directional_light_exponent": _ONE,
        "light_direction": _DIR,
        "light_color": Term("linear RGB times illuminance times exposure", "linear"),
    },
    "threejs": {
        "mode": _MODE,
        "color": _LIN,
        "near": _M,
        "far": _M,
        "density": _PER_M,
        "camera_forward": Term("unit view direction, fogref frame (y-up)"),
        "output": _MODE,
        "sky_distance": _M,
    },
    "babylon": {
        "fogMode": _MODE,
        "fogDensity": _PER_M,
        "fogStart": _M,
        "fogEnd": _M,
        # StandardMaterial uses scene.fogColor in the shader as given, with no conversion
        "fogColor": _LIN,
        "sky_distance": _M,
    },
    "playcanvas": {
        "type": _MODE,
        # the engine raises the colour to the power 2.2 on the CPU before the shader
        "color": Term("linear RGB, scene radiance units", "gamma 2.2"),
        "density": _PER_M,
        "start": _M,
        "end": _M,
        "nearClip": _M,
        "farClip": _M,
        "camera_forward": Term("unit view direction, fogref frame (y-up)"),
        "sky_distance": _M,
    },
}

#: registry name -> the engine, and the source file its defaults (each model's ``Params``) are from.
DEFAULTS_FROM: dict[str, str] = {
    "ue4": "Unreal's UExponentialHeightFogComponent constructor "
    "(Engine/Source/Runtime/Engine/Private/Components/ExponentialHeightFogComponent.cpp)",
    "unity": "Unity's Lighting window fog defaults (Unity Manual, Lighting window: Exponential Squared, "
    "density 0.01, start 0 m, end 300 m, colour (0.5, 0.5, 0.5) sRGB)",
    "hdrp": "HDRP's Fog volume component (com.unity.render-pipelines.high-definition, "
    "Runtime/Lighting/AtmosphericScattering/Fog.cs; fogref models its Constant Color mode)",
    "filament": "Filament's View::FogOptions (filament/include/filament/Options.h)",
    "altitude": "the altitude-fog shader's material defaults",
    "box": "the box-fog shader's material defaults",
    "godot": "Godot 4's Environment (scene/resources/environment.h) and Camera3D's far plane",
    "bevy": "Bevy's DistanceFog::default() (crates/bevy_pbr/src/fog.rs)",
    "ue5_lfv": "Unreal's ULocalFogVolumeComponent defaults "
    "(Engine/Source/Runtime/Engine/Classes/Components/LocalFogVolumeComponent.h)",
    "babylon": "Babylon.js's Scene fog defaults (packages/dev/core/src/scene.ts: fogDensity 0.1, "
    "fogStart 0, fogEnd 1000, fogColor (0.2, 0.2, 0.3))",
    "playcanvas": "PlayCanvas's Scene fog defaults (src/scene/scene.js and fog-params.js)",
    "threejs": "three.js's Fog and FogExp2 constructors (src/scenes/Fog.js, src/scenes/FogExp2.js; "
    "their colour has no default, fogref's is white)",
}

#: registry name -> the engine's name in prose.
ENGINE: dict[str, str] = {
    "ue4": "Unreal",
    "unity": "Unity (built-in)",
    "hdrp": "Unity HDRP",
    "filament": "Filament",
    "altitude": "Unity altitude fog",
    "box": "Unity box fog",
    "godot": "Godot 4",
    "bevy": "Bevy",
    "threejs": "three.js",
    "ue5_lfv": "Unreal (Local Fog Volume)",
    "babylon": "Babylon.js",
    "playcanvas": "PlayCanvas",
}


def unreal_field(label: str) -> str:
    """The ``UE4FogParams`` field of a label of Unreal's details panel.

    >>> unreal_field("Directional Inscattering Start Distance"), unreal_field("Fog Height Offset")
    ('DirectionalInscatteringStartDistance', 'FogHeight')
    """
    return {"Fog Height Offset": "FogHeight"}.get(label, label.replace(" ", ""))


def term(model: str, name: str) -> Term | None:
    """The :class:`Term` of ``model``'s parameter ``name`` (``"color[0]"``: the field ``color``);
    None when fogref does not know it (a user model, a name not in :data:`TERMS`).

    >>> term("bevy", "density").unit, term("my_pkg:Fog", "density")
    ('1/m', None)
    """
    return TERMS.get(model, {}).get(name.partition("[")[0])


def linear_to_srgb(c: Sequence[float]) -> tuple[float, ...]:
    """IEC 61966-2-1 sRGB encoding of linear values, extended above 1 with the same curve (an HDR
    colour stays HDR) and odd below 0: the inverse of Godot's ``Color.srgb_to_linear``
    (:func:`fogref.models.godot.srgb_to_linear`).

    >>> [round(x, 4) for x in linear_to_srgb((0.0, 0.0031308, 0.231082, 1.0, 2.0))]
    [0.0, 0.0404, 0.518, 1.0, 1.3532]
    """
    out = []
    for x in c:
        a = abs(float(x))
        y = a * 12.92 if a <= 0.0031308 else 1.055 * a ** (1 / 2.4) - 0.055
        out.append(math.copysign(y, float(x)))
    return tuple(out)


def ui_colour(model: str, name: str, linear: Sequence[float]) -> tuple[float, ...]:
    """``linear`` (fogref's value of colour ``name``) in the space of ``model``'s UI
    (:attr:`Term.colour`); a 4th component (alpha, a density) is kept as is.

    >>> [round(x, 3) for x in ui_colour("unity", "fogColor", (0.214, 0.214, 0.214))]
    [0.5, 0.5, 0.5]
    """
    t = term(model, name)
    vals = [float(x) for x in linear]
    if t is None or t.colour == "linear":
        return tuple(vals)
    if t.colour == "gamma 2.2":
        return tuple(math.copysign(abs(x) ** (1 / 2.2), x) for x in vals[:3]) + tuple(vals[3:])
    if t.colour == "sRGB":
        return linear_to_srgb(vals[:3]) + tuple(vals[3:])
    return tuple(vals)


def _num(x: float) -> str:
    return f"{x:.3g}"


def note(model: str, name: str, value: Any = None) -> str:
    """The unit of ``model``'s parameter ``name``, or for a colour its space and (given
    ``value``, fogref's linear value) the engine's sRGB where its UI is sRGB; ``""`` for a mode or
    a plain factor, "unit not known to fogref" for a user model.

    >>> note("ue4", "StartDistance"), note("ue4", "FogInscatteringColor")
    ('cm', 'linear; the engine shows linear')
    >>> note("godot", "fog_light_color[0]", 0.231082)
    'linear; sRGB in the engine: 0.518'
    """
    t = term(model, name)
    if t is None:
        return "unit not known to fogref"
    channel = _channel(name)
    if t.colour is None or (channel or 0) >= 3:
        return "" if t.unit in ("", "1") else t.unit
    if t.colour == "linear" or value is None:
        return f"linear; the engine shows {t.colour}"
    vals = list(value) if isinstance(value, (list, tuple, np.ndarray)) else [value]
    ui = ", ".join(_num(v) for v in ui_colour(model, name, vals))
    return f"linear; {t.colour} in the engine: " + (f"({ui})" if channel is None else ui)


def describe(model: str, name: str, value: Any) -> str:
    """``value`` of ``model``'s parameter ``name`` as text followed by its :func:`note`.

    >>> describe("ue4", "FogInscatteringColor", [0.221, 0.307, 0.48])
    '(0.221, 0.307, 0.48) linear; the engine shows linear'
    >>> describe("threejs", "mode", "FogExp2"), describe("x:Y", "k", 2.0)
    ('FogExp2', '2 (unit not known to fogref)')
    """
    if isinstance(value, (list, tuple, np.ndarray)):
        shown = "(" + ", ".join(_num(float(v)) for v in value) + ")"
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        shown = _num(float(value))
    else:
        return str(value)
    n = note(model, name, value)
    if term(model, name) is None:
        return f"{shown} ({n})"
    return f"{shown} {n}" if n else shown


def with_unit(model: str, name: str) -> str:
    """``name`` with its unit or colour space in brackets, for a table's first column.

    >>> with_unit("ue4", "StartDistance"), with_unit("godot", "fog_light_color[0]")
    ('StartDistance [cm]', 'fog_light_color[0] [linear; the engine shows sRGB]')
    >>> with_unit("ue4", "FogMaxOpacity"), with_unit("x:Y", "k")
    ('FogMaxOpacity [1]', 'k')
    """
    t = term(model, name)
    if t is None or not t.unit:
        return name
    if t.colour is not None and (_channel(name) or 0) < 3:
        return f"{name} [linear; the engine shows {t.colour}]"
    return f"{name} [{t.unit}]"


def annotate(model: str, name: str, value: Any = None) -> dict:
    """The JSON fields that go with a parameter's value: ``unit``, and for a colour ``space``
    (always ``"linear"``: fogref's value), ``engine_space`` and, given ``value``,
    ``engine_value`` (the value in the engine UI's space).  Empty when fogref does not know it.

    >>> annotate("godot", "fog_light_color", (0.231082, 0.266417, 0.327964))["engine_value"]
    [0.518, 0.553, 0.608]
    >>> annotate("ue4", "StartDistance")
    {'unit': 'cm'}
    """
    t = term(model, name)
    if t is None:
        return {}
    out: dict = {"unit": t.unit}
    channel = _channel(name)
    if t.colour is not None and (channel is None or channel < 3):
        out.update(space="linear", engine_space=t.colour)
        if value is not None and channel is None:
            out["engine_value"] = [round(v, 6) for v in ui_colour(model, name, value)]
        elif value is not None:
            out["engine_value"] = round(ui_colour(model, name, [float(value)])[0], 6)
    return out


def _channel(name: str) -> int | None:
    """The index of ``"field[i]"``, None for a whole field."""
    _, bracket, rest = name.partition("[")
    return int(rest.rstrip("]")) if bracket else None
