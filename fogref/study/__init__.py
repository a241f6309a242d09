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
        from fogref.exrio import read_exr

        _, attrs = read_exr(a.exr)
        pf = PhysicalScene.from_params(attrs["fogref.params"], camera=a.camera)
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

    pf = _physical_from_args(a)
    views = sample_views(pf.camera, n_dirs=a.directions)
    r = fit_unreal(pf, views, sun_attenuation=not a.no_sun_attenuation, fit_start=not a.no_start_distance)
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
    f.add_argument("--directions", type=int, default=400, help="view directions on the sphere (default 400)")
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
