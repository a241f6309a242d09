"""Studies of the game fog models against the truth (Unreal first).

Modules (one concept each):

* :mod:`~fogref.study.fit`     ``fogref fit``'s scene reading and the cosine-lobe vs HG
  table's pages (the fits themselves are :mod:`fogref.mapping`)
* :mod:`~fogref.study.budget`  the error budget: a telescoping chain from the
  path-traced truth to Unreal, one effect per step
* :mod:`~fogref.study.unreal`  ``fogref study``: fit + comparison + budget + README

Command line (added to fogref's CLI by :func:`add_cli`)::

    fogref fit [--scene XML | --exr EXR | physical flags] [--lobe-table [--out reports/fit]]
    fogref study [EXR] [--out reports/unreal_study] [--renders out/study] [--no-compare]
"""

from __future__ import annotations

import argparse
import json
import sys

__all__ = ["add_cli"]


#: ``fogref fit --directions``: allowed range (the fit solves for six colour values, the
#: exponent and the start distance over ``directions x 12`` views).
DIRECTIONS_RANGE = (8, 100_000)


def _check_number(option: str, value, lo=None, hi=None, lo_open=False, hi_open=False, what="") -> None:
    """FogrefError naming ``option``, the value and the allowed range unless ``lo <= value <= hi``
    (strict where ``*_open``) and finite."""
    import math

    from fogref.errors import FogrefError

    ok = value is not None and isinstance(value, (int, float)) and math.isfinite(value)
    ok = ok and (lo is None or (value > lo if lo_open else value >= lo))
    ok = ok and (hi is None or (value < hi if hi_open else value <= hi))
    if not ok:
        lo_s = "-inf" if lo is None else f"{lo:g}"
        hi_s = "inf" if hi is None else f"{hi:g}"
        rng = f"{'(' if lo_open or lo is None else '['}{lo_s}, {hi_s}{')' if hi_open or hi is None else ']'}"
        raise FogrefError(f"{option}: {value!r} is out of range: {what + ' ' if what else ''}must be a finite number "
                          f"in {rng}")


def check_fit_args(a) -> None:
    """Refuse out-of-range ``fogref fit`` flags before any work (FogrefError naming the option)."""
    from fogref.errors import FogrefError

    if a.directions is not None and not (isinstance(a.directions, int)
                                         and DIRECTIONS_RANGE[0] <= a.directions <= DIRECTIONS_RANGE[1]):
        raise FogrefError(f"--directions: {a.directions!r} is out of range: the number of view directions must be "
                          f"an integer in [{DIRECTIONS_RANGE[0]}, {DIRECTIONS_RANGE[1]}]")
    for opt, v, lo, hi, lo_open, hi_open, what in (
            ("--sigma-t", a.sigma_t, 0.0, None, False, False, "extinction [1/m]"),
            ("--falloff", a.falloff, 0.0, None, False, False, "falloff [1/m]"),
            ("--height", a.height, None, None, False, False, "height [m]"),
            ("--albedo", a.albedo, 0.0, 1.0, False, False, "albedo"),
            ("--g", a.g, -1.0, 1.0, True, True, "Henyey–Greenstein g")):
        if v is not None:
            _check_number(opt, v, lo, hi, lo_open, hi_open, what)
    for opt, vec, lo, what in (("--sun-irradiance", a.sun_irradiance, 0.0, "sun irradiance (each of R, G, B)"),
                               ("--sky", a.sky, 0.0, "sky radiance (each of R, G, B)"),
                               ("--camera", a.camera, None, "camera position [m]"),
                               ("--sun-dir", a.sun_dir, None, "sun direction")):
        for v in vec or ():
            _check_number(opt, v, lo, None, False, False, what)
    if a.sun_dir and not any(a.sun_dir):
        raise FogrefError("--sun-dir: (0, 0, 0) is not a direction")


def check_physical(pf, source: str) -> None:
    """Refuse a physical scene whose sun irradiance or sky radiance is negative or not finite
    (from a scene, an EXR header or flags)."""
    import math

    from fogref.errors import FogrefError

    for name, vec in (("sun irradiance", pf.sun_irradiance), ("sky radiance", pf.sky_radiance)):
        vals = [float(v) for v in (vec or ())]
        if any(not math.isfinite(v) or v < 0 for v in vals):
            raise FogrefError(f"{source}: {name} {tuple(vals)} is out of range: each of R, G, B must be a finite "
                              "number >= 0")


def _physical_from_args(a):
    from fogref.mapping import PhysicalScene
    from fogref.media import ExpLayer, FogMedium
    from fogref.study.fit import physical_from_scene

    if a.scene and a.exr:
        from fogref.errors import FogrefError

        raise FogrefError("give --scene or --exr, not both")
    if a.scene:
        pf = physical_from_scene(a.scene, camera=a.camera)
    elif a.exr:
        from fogref.gbuffer import load_truth

        pf = PhysicalScene.from_params(load_truth(a.exr).params, camera=a.camera)  # refuses a foreign EXR
    else:
        med = FogMedium(sigma_t=a.sigma_t if a.sigma_t is not None else 0.000960906,
                        albedo=a.albedo if a.albedo is not None else 0.9,
                        g=a.g if a.g is not None else 0.6,
                        layers=(ExpLayer(1.0, a.falloff if a.falloff is not None else 0.0138629,
                                         a.height if a.height is not None else 0.0),),
                        source="<fogref fit flags>")
        pf = PhysicalScene(med, tuple(a.sun_dir or (0.4, 0.139, 0.906)), tuple(a.sun_irradiance or (3.2, 2.9, 2.4)),
                           tuple(a.sky or (0.2, 0.3, 0.5)), tuple(a.camera or (0.0, 2.0, 0.0)))
        return pf
    from dataclasses import replace

    m = pf.medium
    kw = {k: v for k, v in (("sigma_t", a.sigma_t), ("albedo", a.albedo), ("g", a.g)) if v is not None}
    if kw:
        m = replace(m, **kw)
    if a.falloff is not None or a.height is not None:
        L = m.layers[0]
        m = replace(m, layers=(ExpLayer(L.density, a.falloff if a.falloff is not None else L.falloff,
                                        a.height if a.height is not None else L.height),) + tuple(m.layers[1:]))
    pf = replace(pf, medium=m)
    if a.sun_dir:
        pf = replace(pf, sun_direction=tuple(a.sun_dir))
    if a.sun_irradiance:
        pf = replace(pf, sun_irradiance=tuple(a.sun_irradiance))
    if a.sky:
        pf = replace(pf, sky_radiance=tuple(a.sky))
    return pf


def cmd_fit(a) -> int:
    from fogref.mapping import fit_unreal, lobe_table, sample_views
    from fogref.study.fit import write_lobe_table

    check_fit_args(a)
    pf = _physical_from_args(a)
    check_physical(pf, a.scene or a.exr or "fogref fit flags")
    # the one fit: its direction count by the convergence criterion, unless --directions fixes it
    views = None if a.directions is None else sample_views(pf.camera, n_dirs=a.directions)
    r = fit_unreal(pf, views, sun_attenuation=not a.no_sun_attenuation, fit_start=not a.no_start_distance)
    if views is None:
        views = sample_views(pf.camera, n_dirs=r.history["n_dirs"])
    doc = {"physical": {"sigma_t": list(pf.medium.sigma_t), "albedo": list(pf.medium.albedo), "g": pf.medium.g,
                        "layers": [vars(L) if hasattr(L, "__dict__") else repr(L) for L in pf.medium.layers],
                        "sun_direction": list(pf.sun_direction), "sun_irradiance": list(pf.sun_irradiance),
                        "sky_radiance": list(pf.sky_radiance), "camera": list(pf.camera)},
           **r.to_dict()}
    if a.lobe_table:
        rows = lobe_table(pf=pf, views=views)
        write_lobe_table(rows, a.out, scene_name=a.scene or a.exr or "the flags'")
        doc["lobe_table"] = str(a.out)
    print(json.dumps(doc, indent=2))
    print("Unreal Exponential Height Fog (details panel):", file=sys.stderr)
    for k, v in r.editor_properties().items():
        if isinstance(v, list):
            v = "(R=%.4g, G=%.4g, B=%.4g)" % tuple(v)
        elif isinstance(v, float):
            v = f"{v:.6g}"
        print(f"  {k:42s} {v}", file=sys.stderr)
    print(f"  (inscatter relative RMSE over {r.n_views} views: {r.rel_rmse:.3f})", file=sys.stderr)
    return 0


def cmd_study(a) -> int:
    from fogref.study.unreal import run_study

    for opt, v, lo, hi in (("--start-distance", a.start_distance, 0.0, None), ("--max-opacity", a.max_opacity, 0.0, 1.0),
                           ("--cutoff", a.cutoff, 0.0, None)):
        if v is not None:
            _check_number(opt, v, lo, hi, what="Unreal setting")
    settings = {k: v for k, v in (("StartDistance", a.start_distance), ("FogMaxOpacity", a.max_opacity),
                                  ("FogCutoffDistance", a.cutoff)) if v is not None}
    run_study(a.exr, a.out, a.renders, scene=a.scene, compare_report=not a.no_compare, settings=settings)
    return 0


def add_cli(subparsers) -> None:
    """Add the ``fit`` and ``study`` subcommands to an argparse ``subparsers`` object."""
    f = subparsers.add_parser("fit", help="fit Unreal's fog colours/exponent to a physical fog (prints JSON)",
                              description="Find Unreal's FogInscatteringColor, DirectionalInscatteringColor, "
                              "DirectionalInscatteringExponent and DirectionalInscatteringStartDistance that best "
                              "match the closed-form single scattering of a physical fog.  JSON on stdout; the "
                              "details-panel values on stderr.")
    f.add_argument("--scene", help="fogref XML scene (fog, sun, sky, camera)")
    f.add_argument("--exr", help="ground-truth EXR (its fogref.params header)")
    f.add_argument("--sigma-t", type=float, help="extinction at the layer height [1/m]")
    f.add_argument("--falloff", type=float, help="exponential falloff b [1/m]")
    f.add_argument("--height", type=float, help="layer reference height [m]")
    f.add_argument("--albedo", type=float, help="single-scattering albedo")
    f.add_argument("--g", type=float, help="Henyey–Greenstein asymmetry")
    f.add_argument("--sun-dir", type=float, nargs=3, metavar=("X", "Y", "Z"), help="direction toward the sun (y-up)")
    f.add_argument("--sun-irradiance", type=float, nargs=3, metavar=("R", "G", "B"))
    f.add_argument("--sky", type=float, nargs=3, metavar=("R", "G", "B"), help="uniform sky radiance")
    f.add_argument("--camera", type=float, nargs=3, metavar=("X", "Y", "Z"), help="camera position [m]")
    f.add_argument("--directions", type=int, default=None,
                   help=f"fix the number of view directions on the sphere, {DIRECTIONS_RANGE[0]}.."
                   f"{DIRECTIONS_RANGE[1]} (default: doubled from 128 until the fit converges, as "
                   "--from-scene, study and sweep do)")
    f.add_argument("--no-sun-attenuation", action="store_true", help="fit to the unattenuated single scattering")
    f.add_argument("--no-start-distance", action="store_true", help="keep DirectionalInscatteringStartDistance 0")
    f.add_argument("--lobe-table", action="store_true", help="also tabulate the best lobe for g = -0.9..0.9")
    f.add_argument("--out", default="reports/fit", help="folder of the lobe table (default reports/fit)")
    f.set_defaults(func=cmd_fit)

    s = subparsers.add_parser("study", help="the Unreal study: fit, compare, error budget, README",
                              description="Derive Unreal parameters from the EXR's physical fog, compare, "
                              "compute the error budget and write reports/unreal_study/.")
    s.add_argument("exr", nargs="?", default="out/valley.exr", help="ground-truth EXR (default out/valley.exr)")
    s.add_argument("--out", default="reports/unreal_study", help="report folder")
    s.add_argument("--renders", default="out/study", help="cache folder of the budget's extra renders")
    s.add_argument("--scene", default=None, help="the EXR's scene, if its recorded path is not found")
    s.add_argument("--no-compare", action="store_true", help="skip the fogref.compare report")
    s.add_argument("--start-distance", type=float, default=None, help="Unreal StartDistance [cm] (default 0)")
    s.add_argument("--max-opacity", type=float, default=None, help="Unreal FogMaxOpacity (default 1)")
    s.add_argument("--cutoff", type=float, default=None, help="Unreal FogCutoffDistance [cm] (default 0 = off)")
    s.set_defaults(func=cmd_study)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="fogref")
    add_cli(p.add_subparsers(dest="cmd", required=True))
    a = p.parse_args(argv)
    return a.func(a)
