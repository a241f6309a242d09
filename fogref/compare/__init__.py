"""Compare game fog models with the path-traced ground truth.

Modules (one concept each):

* :mod:`~fogref.compare.metrics`       RMSE, relMSE, ΔE2000, HDR-FLIP, per-pixel maps
* :mod:`~fogref.compare.report`        ``compare()``: evaluate a model on a truth
  (:func:`fogref.gbuffer.load_truth`, the one reader), write the report
* :mod:`~fogref.compare.binning`       errors binned by distance or sun angle
* :mod:`~fogref.compare.plots`         heatmaps, side-by-side pictures, binned plots
* :mod:`~fogref.compare.tonemap`       the shared display tone map
* (the model is built by :func:`fogref.mapping.build.build_model` from ``--model``, ``--param``,
  ``--from-scene``; names resolved by :func:`fogref.models.resolve.resolve_model`)

Command line (added to fogref's CLI by :func:`add_cli`)::

    fogref compare EXR --model ue4 [--param KEY=VALUE ...] [--from-scene]
                       [--out reports/compare/NAME] [--precision float32] [--sky-distance M]
                       [--no-figures]
    fogref compare EXR --model my_pkg.my_module:MyFog ...          (see docs/byo.md)
    fogref compare EXR --image ENGINE.exr [--transmittance T.exr] [--inscatter L.exr | --fog-colour C.exr]
                       [--encoding linear|srgb] [--exposure X] [--out DIR]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from fogref.compare.report import DEFAULT_SKY_DISTANCE, compare

__all__ = ["DEFAULT_SKY_DISTANCE", "add_cli", "compare", "main", "run_compare_command"]


def default_out_dir(exr_path, model_name: str) -> Path:
    """``reports/compare/<EXR stem>-<model>`` (relative to the working directory)."""
    return Path("reports") / "compare" / f"{Path(exr_path).stem}-{model_name}"


def run_compare_command(args: argparse.Namespace) -> int:
    """Handler of ``fogref compare``: build the model, call :func:`compare`, print a summary.

    Options are checked before anything is read (FogrefError naming the option);
    warnings (model non-finite values, excluded pixels) go to stderr.
    """
    from fogref.compare.foreign import run_image_command, wants_images
    from fogref.compare.report import check_sky_distance
    from fogref.errors import FogrefError
    from fogref.gbuffer import load_truth
    from fogref.mapping.build import build_model, parse_param_assignments

    if wants_images(args):
        if args.model:
            raise FogrefError("give --model or the engine's images (--image/--transmittance/--inscatter), not both")
        return run_image_command(args)
    if not args.model:
        raise FogrefError("give --model NAME (or module.path:Class) or an engine's image with --image FILE")
    sky_distance = check_sky_distance(args.sky_distance, "--sky-distance")
    truth = load_truth(args.exr)
    model = build_model(args.model, parse_param_assignments(args.param), truth.params if args.from_scene else None)
    out = Path(args.out) if args.out else default_out_dir(args.exr, args.model)
    report = compare(truth, model, out, precision=args.precision, sky_distance=sky_distance,
                     figures=not args.no_figures)
    final = report["metrics"]["final"]["all"]

    def pm(key):
        v = final.get(key)
        return "—" if v is None else f"{v:.4g} ± {final.get(key + '_stderr', 0):.2g}"

    print(f"{args.model} vs {args.exr}: final RMSE {pm('rmse')} (noise floor {final.get('rmse_noise_floor', 0):.2g}"
          f"{', below the noise' if final.get('rmse_below_noise') else ''}), relMSE {pm('relmse')}, "
          f"mean error {pm('mean_error')}, ΔE2000 mean {final.get('delta_e2000_mean', 0):.3g}, "
          f"FLIP mean {final.get('flip_mean', 0):.3g}")
    for w in report["warnings"]:
        print(f"fogref compare: warning: {w}", file=sys.stderr)
    print(f"report: {out / 'index.md'}")
    return 0


def add_cli(subparsers) -> argparse.ArgumentParser:
    """Add the ``compare`` subcommand to an argparse ``subparsers`` object.

    The parser's ``func`` default is :func:`run_compare_command`, so a main program
    dispatches with ``args.func(args)``.  Returns the new subparser.
    """
    p = subparsers.add_parser("compare", help=_HELP, description=_DESCRIPTION)
    _configure(p)
    return p


_HELP = "measure a game fog model against a ground-truth EXR and write a report"
_DESCRIPTION = (
    "Evaluate a game fog model on the pixels of a ground-truth EXR and write metrics.json, errors.exr, "
    "PNG heatmaps, error-vs-distance/sun-angle plots and index.md."
)


def _configure(p: argparse.ArgumentParser) -> None:
    """The ``compare`` arguments, shared by :func:`add_cli` and :func:`main`."""
    p.add_argument("exr", help="ground-truth EXR written by the fogref renderer")
    p.add_argument("--model", default=None,
                   help="fog model: a built-in name (e.g. ue4), module.path:Class, or a 'fogref.models' entry point")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                   help="set a model parameter by name (VALUE parsed as JSON when possible); repeatable")
    p.add_argument("--from-scene", action="store_true",
                   help="derive the model parameters from the EXR's physical fog (model.from_physical); "
                   "--param values then override")
    p.add_argument("--out", default=None, help="report folder (default reports/compare/<EXR stem>-<model>)")
    p.add_argument("--precision", choices=("float32", "float64"), default="float32",
                   help="arithmetic precision of the model evaluation")
    p.add_argument("--sky-distance", type=float, default=DEFAULT_SKY_DISTANCE, metavar="M",
                   help=f"distance [m] at which sky pixels are fogged, finite and > 0 "
                   f"(default {DEFAULT_SKY_DISTANCE:g})")
    p.add_argument("--no-figures", action="store_true",
                   help="write only metrics.json, errors.exr and index.md (no PNGs; faster, for CI)")
    from fogref.compare.foreign import add_arguments

    add_arguments(p)
    p.set_defaults(func=run_compare_command)


def main(argv=None) -> int:
    """Stand-alone entry point: ``python -m fogref.compare EXR --model NAME ...``.

    Same options as ``fogref compare``; ``argv`` excludes the program name.
    """
    parser = argparse.ArgumentParser(prog="fogref compare", description=_DESCRIPTION)
    _configure(parser)
    args = parser.parse_args(argv)
    return args.func(args)
