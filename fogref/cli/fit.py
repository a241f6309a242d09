"""``fogref fit``: a fog model's free parameters fitted to a physical fog (Unreal by default).

``--model NAME`` (any model: a built-in name or ``module.path:Class``) fits its free parameters
(:mod:`fogref.mapping.free`) with :func:`fogref.mapping.fit.fit_model`, over the sun elevations
of ``--sun-elevation``; every parameter gets its uncertainty.  Unreal without ``--generic``,
``--sun-elevation`` or ``--param`` keeps its own fit and output.

The physical fog comes from a scene (``--scene``), a truth's header (``--exr``) or flags
(each flag also overrides the scene's or the EXR's value).  The fit is
:func:`fogref.mapping.fit_unreal`; JSON on stdout, the details-panel values on stderr.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass, replace

from fogref import params
from fogref.cli.checks import RGB, Integer, Number, PathArg, SceneArg, Text, Vector
from fogref.cli.spec import UsageError, assignments, option, switch
from fogref.gbuffer import load_truth
from fogref.mapping import PhysicalScene, fit_unreal, lobe_table, sample_views
from fogref.mapping.build import parse_param_assignments
from fogref.mapping.fit import fit_model, model_class
from fogref.media import ExpLayer, FogMedium
from fogref.models.terms import note, unreal_field
from fogref.study.fit import physical_from_scene, write_lobe_table

NAME = "fit"
SOURCE = "fogref fit"
HELP = "fit a fog model's parameters (default Unreal's colours and lobe) to a physical fog (prints JSON)"
DESCRIPTION = (
    "Find Unreal's FogInscatteringColor, DirectionalInscatteringColor, DirectionalInscatteringExponent "
    "and DirectionalInscatteringStartDistance that best match the closed-form single scattering of "
    "a physical fog.  JSON on stdout; the details-panel values on stderr.  Without --scene or --exr "
    "the fog is the valley's, changed by the flags.  --model fits another model's free parameters "
    "(fogref.mapping.free), each with its uncertainty."
)
EPILOG = "exit codes: 0 fitted, 2 usage or input error"
FIT = "fogref.mapping:fit_unreal"
#: ``--directions``: allowed range (the fit solves for six colour values, the exponent and the start
#: distance over ``directions x 12`` views).
DIRECTIONS_RANGE = (8, 100_000)
#: The fog, sun, sky and camera without --scene or --exr: scenes/valley.xml's $defaults.
VALLEY = {
    "sigma_t": 0.000960906,
    "falloff": 0.0138629,
    "height": 0.0,
    "albedo": 0.9,
    "g": 0.6,
    "sun_dir": (0.4, 0.139, 0.906),
    "sun_irradiance": (3.2, 2.9, 2.4),
    "sky": (0.2, 0.3, 0.5),
    "camera": (0.0, 2.0, 0.0),
}
SOURCE_GROUP = (
    "the physical fog: a scene, a truth, or flags (flags override the scene's or the truth's values)"
)


def _valley(name: str) -> str:
    v = VALLEY[name]
    return "the scene's; else the valley's " + (
        ",".join(f"{x:g}" for x in v) if isinstance(v, tuple) else f"{v:g}"
    )


MODEL_GROUP = "the model (default Unreal)"


@dataclass
class Options:
    model: str = option(
        "ue4",
        "fog model: a built-in name (ue4, unity, godot, ...) or module.path:Class",
        check=Text(),
        metavar="NAME",
        group=MODEL_GROUP,
    )
    param: dict | None = assignments(
        "fix a model setting in the engine's units; a colour is linear RGB (VALUE: JSON if it parses)",
        metavar="KEY=VALUE",
        group=MODEL_GROUP,
    )
    sun_elevation: list | None = option(
        None,
        "a sun elevation to fit over (repeat for several; fitted together)",
        repeat=True,
        check=Number(-90.0, 90.0, unit="deg"),
        metavar="DEG",
        group=MODEL_GROUP,
        default_text="the scene's sun",
    )
    generic: bool = switch(
        "Unreal too through the generic fit (every parameter with its uncertainty)", group=MODEL_GROUP
    )
    scene: str | None = option(
        None,
        "fogref XML scene (fog, sun, sky, camera), or a shipped scene's name (valley, open_plane, ...)",
        check=SceneArg(),
        metavar="XML",
        group=SOURCE_GROUP,
    )
    exr: str | None = option(
        None,
        "ground-truth EXR (its fogref.params header)",
        check=PathArg(role="input"),
        metavar="EXR",
        group=SOURCE_GROUP,
    )
    sigma_t: float | None = option(
        None,
        "extinction at the layer height",
        check=Number(0.0, unit="1/m"),
        group=SOURCE_GROUP,
        default_text=_valley("sigma_t"),
    )
    falloff: float | None = option(
        None,
        "exponential falloff b",
        check=Number(0.0, unit="1/m"),
        group=SOURCE_GROUP,
        default_text=_valley("falloff"),
    )
    height: float | None = option(
        None,
        "layer reference height",
        check=Number(unit="m"),
        group=SOURCE_GROUP,
        default_text=_valley("height"),
    )
    albedo: float | None = option(
        None,
        "single-scattering albedo",
        check=Number(0.0, 1.0),
        group=SOURCE_GROUP,
        default_text=_valley("albedo"),
    )
    g: float | None = option(
        None,
        "Henyey-Greenstein asymmetry",
        check=Number(-1.0, 1.0, True, True),
        group=SOURCE_GROUP,
        default_text=_valley("g"),
    )
    sun_dir: tuple | None = option(
        None,
        "direction toward the sun (y-up; not 0,0,0)",
        check=Vector(3),
        nargs=3,
        metavar=("X", "Y", "Z"),
        group=SOURCE_GROUP,
        default_text=_valley("sun_dir"),
    )
    sun_irradiance: tuple | None = option(
        None,
        "sun irradiance (linear RGB)",
        check=RGB(0.0),
        nargs=3,
        metavar=("R", "G", "B"),
        group=SOURCE_GROUP,
        default_text=_valley("sun_irradiance"),
    )
    sky: tuple | None = option(
        None,
        "uniform sky radiance (linear RGB)",
        check=RGB(0.0),
        nargs=3,
        metavar=("R", "G", "B"),
        group=SOURCE_GROUP,
        default_text=_valley("sky"),
    )
    camera: tuple | None = option(
        None,
        "camera position",
        check=Vector(3, unit="m"),
        nargs=3,
        metavar=("X", "Y", "Z"),
        group=SOURCE_GROUP,
        default_text=_valley("camera"),
    )
    directions: int | None = option(
        None,
        "fix the number of view directions on the sphere",
        check=Integer(*DIRECTIONS_RANGE),
        default_text="doubled from 128 until the fit converges, as --from-scene, study and sweep do",
    )
    no_sun_attenuation: bool = switch(
        "fit to the unattenuated single scattering", api=FIT, api_name="sun_attenuation", negates=True
    )
    no_start_distance: bool = switch(
        "keep DirectionalInscatteringStartDistance 0", api=FIT, api_name="fit_start", negates=True
    )
    lobe_table: bool = switch("also tabulate the best lobe for g = -0.9..0.9")
    out: str = option("out/fit", "folder of the lobe table", check=PathArg())


def check_physical(pf, source: str) -> None:
    """Refuse a physical scene whose sun irradiance or sky radiance is negative or not finite
    (from a scene, an EXR header or flags)."""
    params.rgb(pf.sun_irradiance, "sun_irradiance", source=source, lo=0.0)
    if pf.sky_radiance is not None:
        params.rgb(pf.sky_radiance, "sky_radiance", source=source, lo=0.0)


def physical_from_options(o: Options):
    """The :class:`fogref.mapping.PhysicalScene` of the options: the scene's, the truth's or
    :data:`VALLEY`, each flag given overriding its value."""
    if o.scene and o.exr:
        raise UsageError(f"{SOURCE}: give --scene or --exr, not both")
    if o.sun_dir is not None and not any(o.sun_dir):
        raise UsageError(f"{SOURCE}: --sun-dir (0, 0, 0) is not a direction")
    if o.scene:
        pf = physical_from_scene(o.scene, camera=o.camera)
    elif o.exr:
        pf = PhysicalScene.from_params(load_truth(o.exr).params, camera=o.camera)  # refuses a foreign EXR
    else:
        v = {k: getattr(o, k) if getattr(o, k) is not None else d for k, d in VALLEY.items()}
        med = FogMedium(
            sigma_t=v["sigma_t"],
            albedo=v["albedo"],
            g=v["g"],
            layers=(ExpLayer(1.0, v["falloff"], v["height"]),),
            source="<fogref fit flags>",
        )
        return PhysicalScene(
            med, tuple(v["sun_dir"]), tuple(v["sun_irradiance"]), tuple(v["sky"]), tuple(v["camera"])
        )
    m = pf.medium
    kw = {k: v for k, v in (("sigma_t", o.sigma_t), ("albedo", o.albedo), ("g", o.g)) if v is not None}
    if kw:
        m = replace(m, **kw)
    if o.falloff is not None or o.height is not None:
        L = m.layers[0]
        falloff = L.falloff if o.falloff is None else o.falloff
        height = L.height if o.height is None else o.height
        m = replace(m, layers=(ExpLayer(L.density, falloff, height), *m.layers[1:]))
    pf = replace(pf, medium=m)
    for k, v in (("sun_direction", o.sun_dir), ("sun_irradiance", o.sun_irradiance), ("sky_radiance", o.sky)):
        if v:  # one replace each, in this order (each re-normalises the sun direction)
            pf = replace(pf, **{k: tuple(v)})
    return pf


def physical_doc(pf) -> dict:
    return {
        "sigma_t": list(pf.medium.sigma_t),
        "albedo": list(pf.medium.albedo),
        "g": pf.medium.g,
        "layers": [vars(L) if hasattr(L, "__dict__") else repr(L) for L in pf.medium.layers],
        "sun_direction": list(pf.sun_direction),
        "sun_irradiance": list(pf.sun_irradiance),
        "sky_radiance": list(pf.sky_radiance),
        "camera": list(pf.camera),
    }


def run_generic(o: Options, pf) -> int:
    """Any model through :func:`fogref.mapping.fit.fit_model`: JSON on stdout, a table on stderr."""
    fixed = parse_param_assignments(f"{k}={v}" for k, v in (o.param or {}).items())
    r = fit_model(
        o.model,
        pf,
        views=o.directions,
        sun_elevations=o.sun_elevation,
        params=fixed,
        transmittance_weight=1.0,
    )
    print(json.dumps({"physical": physical_doc(pf), **r.to_dict()}, indent=2))
    print(
        f"{r.model}: best fit (± uncertainty from the Jacobian; spread over two direction counts):",
        file=sys.stderr,
    )
    for k, v in r.values.items():
        sp = f"  spread {r.spread[k]:.2g}" if r.spread else ""
        unit = note(r.model, k, v)
        print(f"  {k:42s} {v:.6g} ± {r.uncertainty[k]:.2g}{sp}  {unit}".rstrip(), file=sys.stderr)
    print(
        f"  (inscatter relative RMSE over {r.n_views} views: {r.rel_rmse:.3f}; transmittance RMSE "
        f"{r.rmse_T:.3f})",
        file=sys.stderr,
    )
    if r.ill_posed:
        print(
            f"fogref fit: warning: {r.model}: {', '.join(r.ill_posed)} not determined by the {r.n_dirs} "
            "directions (uncertainty larger than the value): the fit is ill-posed there; give more "
            "--directions (or leave it out: the count then converges)",
            file=sys.stderr,
        )
    return 0


def run(o: Options, given=frozenset()) -> int:
    cls = model_class(o.model)  # an unknown model: "did you mean", before any work
    pf = physical_from_options(o)
    check_physical(pf, o.scene or o.exr or "fogref fit flags")
    if getattr(cls, "name", None) != "ue4" or o.generic or o.sun_elevation or o.param:
        if o.lobe_table:
            raise UsageError(f"{SOURCE}: --lobe-table is Unreal's own fit (without --model/--generic)")
        return run_generic(o, pf)
    # the one fit: its direction count by the convergence criterion, unless --directions fixes it
    views = None if o.directions is None else sample_views(pf.camera, n_dirs=o.directions)
    r = fit_unreal(pf, views, sun_attenuation=not o.no_sun_attenuation, fit_start=not o.no_start_distance)
    if views is None:
        views = sample_views(pf.camera, n_dirs=r.history["n_dirs"])
    doc = {"physical": physical_doc(pf), **r.to_dict()}
    if o.lobe_table:
        rows = lobe_table(pf=pf, views=views)
        write_lobe_table(rows, o.out, scene_name=o.scene or o.exr or "the flags'")
        doc["lobe_table"] = str(o.out)
    print(json.dumps(doc, indent=2))
    print("Unreal Exponential Height Fog (details panel):", file=sys.stderr)
    for k, v in r.editor_properties().items():
        unit = note("ue4", unreal_field(k), v)
        if isinstance(v, list):
            v = "(R=%.4g, G=%.4g, B=%.4g)" % tuple(v)
        elif isinstance(v, float):
            v = f"{v:.6g}"
        print(f"  {k:42s} {v}  {unit}".rstrip(), file=sys.stderr)
    print(f"  (inscatter relative RMSE over {r.n_views} views: {r.rel_rmse:.3f})", file=sys.stderr)
    return 0
