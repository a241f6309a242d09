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
* :mod:`~fogref.compare.gate`          the CLI's verdict options, exit codes, ``--json``/``--junit``

Command line (added to fogref's CLI by :func:`add_cli`)::

    fogref compare EXR --model ue4 [--param KEY=VALUE ...] [--from-scene]
                       [--out out/compare/NAME] [--precision float32] [--sky-distance M]
                       [--no-figures]
    fogref compare EXR --model my_pkg.my_module:MyFog ...          (see docs/byo.md)
    fogref compare EXR --image ENGINE.exr [--transmittance T.exr] [--inscatter L.exr | --fog-colour C.exr]
                       [--encoding auto|linear|srgb] [--exposure X] [--out DIR]
    either, gating CI (:mod:`~fogref.compare.gate`):
                       [--tolerance PART[/REGION][:METRIC]=VALUE ...] [--distance-bands 100,1000]
                       [--confidence 0.99] [--inconclusive fail|pass] [--json FILE] [--junit FILE]

Exit codes: 0 pass, 1 fail, 2 usage or input error, 3 inconclusive.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from fogref.compare.report import DEFAULT_SKY_DISTANCE, compare

__all__ = ["DEFAULT_SKY_DISTANCE", "add_cli", "compare", "main", "run_compare_command"]


def default_out_dir(exr_path, name: str) -> Path:
    """``out/compare/<EXR stem>-<name>`` (relative to the working directory; ``out/`` is git-ignored).

    ``name``: the model, or the stem of the engine's first image.

    >>> default_out_dir("renders/valley.exr", "ue4").as_posix()
    'out/compare/valley-ue4'
    """
    safe = "".join(c if c.isalnum() or c in "._-" else "_" for c in str(name))
    return Path("out") / "compare" / f"{Path(exr_path).stem}-{safe}"


def _print_metrics(name, exr, final: dict) -> None:
    """The descriptive one-line summary of a model's ``final`` part (RMSE with its noise floor, ...)."""
    def pm(key):
        v = final.get(key)
        return "—" if v is None else f"{v:.4g} ± {final.get(key + '_stderr', 0):.2g}"

    print(f"{name} vs {exr}: final RMSE {pm('rmse')} (noise floor {final.get('rmse_noise_floor', 0):.2g}"
          f"{', below the noise' if final.get('rmse_below_noise') else ''}), relMSE {pm('relmse')}, "
          f"mean error {pm('mean_error')}, ΔE2000 mean {final.get('delta_e2000_mean', 0):.3g}, "
          f"FLIP mean {final.get('flip_mean', 0):.3g}")


def run_compare_command(args: argparse.Namespace) -> int:
    """Handler of ``fogref compare``: check the candidate, write the report, return the exit code.

    The verdict is :func:`fogref.compare.check.check`'s; exit 0 pass, 1 fail, 3
    inconclusive (see :mod:`fogref.compare.gate`); a FogrefError (exit 2 in fogref's
    CLI) for a bad option or input.  Options are checked before anything is read;
    warnings (model non-finite values, excluded pixels) go to stderr.
    """
    from fogref.compare import gate
    from fogref.compare.check import check
    from fogref.compare.foreign import load_engine_images, wants_images
    from fogref.compare.report import check_sky_distance, compare_images
    from fogref.errors import FogrefError
    from fogref.gbuffer import load_truth
    from fogref.mapping.build import build_model, parse_param_assignments

    if wants_images(args) and args.model:
        raise FogrefError("give --model or the engine's images (--image/--transmittance/--inscatter), not both")
    if not wants_images(args) and not args.model:
        raise FogrefError("give --model NAME (or module.path:Class) or an engine's image with --image FILE")
    options = gate.check_options(args)
    sky_distance = check_sky_distance(args.sky_distance, "--sky-distance")
    truth = load_truth(args.exr)
    extra = {}
    if wants_images(args):
        images = load_engine_images(args.image, args.transmittance, args.inscatter, args.fog_colour,
                                    encoding=args.encoding, exposure=args.exposure, shape=truth.shape,
                                    truth_name=str(args.exr))
        stem = Path(args.image or args.inscatter or args.transmittance or args.fog_colour).stem
        out = Path(args.out) if args.out else default_out_dir(args.exr, stem)
        result = check(truth, images, **options)
        report = compare_images(truth, images, out, figures=not args.no_figures, check=result)
        extra["encodings"] = report["images"]["encodings"]
    else:
        model = build_model(args.model, parse_param_assignments(args.param),
                            truth.params if args.from_scene else None)
        out = Path(args.out) if args.out else default_out_dir(args.exr, args.model)
        result = check(truth, model, **options, precision=args.precision, sky_distance=sky_distance)
        report = compare(truth, model, out, precision=args.precision, sky_distance=sky_distance,
                         figures=not args.no_figures, check=result)
        _print_metrics(args.model, args.exr, report["metrics"]["final"]["all"])
    for w in report["warnings"]:
        print(f"fogref compare: warning: {w}", file=sys.stderr)
    print(f"report: {out / 'index.md'}")
    return gate.finish(args, result, report=str(out), **extra)


def add_cli(subparsers) -> argparse.ArgumentParser:
    """Add the ``compare`` subcommand to an argparse ``subparsers`` object.

    The parser's ``func`` default is :func:`run_compare_command`, so a main program
    dispatches with ``args.func(args)``.  Returns the new subparser.
    """
    from fogref.compare.gate import EXIT_HELP

    p = subparsers.add_parser("compare", help=_HELP, description=_DESCRIPTION, epilog=EXIT_HELP)
    _configure(p)
    return p


_HELP = "check a game fog model or an engine's images against a ground-truth EXR; report; exit code for CI"
_DESCRIPTION = (
    "Check a game fog model (--model) or an engine's images (--image/--transmittance/--inscatter) against "
    "a ground-truth EXR with fogref.compare.check.check (the checker of assert_fog_matches: confidence "
    "intervals with the truth's noise removed, a verdict per part, region and metric) and write "
    "metrics.json, check.json, errors.exr, PNG heatmaps, error-vs-distance/sun-angle plots and index.md."
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
    p.add_argument("--out", default=None,
                   help="report folder (default out/compare/<EXR stem>-<model or image stem>)")
    p.add_argument("--precision", choices=("float32", "float64"), default="float32",
                   help="arithmetic precision of the model evaluation")
    p.add_argument("--sky-distance", type=float, default=DEFAULT_SKY_DISTANCE, metavar="M",
                   help=f"distance [m] at which sky pixels are fogged, finite and > 0 "
                   f"(default {DEFAULT_SKY_DISTANCE:g})")
    p.add_argument("--no-figures", action="store_true",
                   help="write only metrics.json, errors.exr and index.md (no PNGs; faster, for CI)")
    from fogref.compare import foreign, gate

    foreign.add_arguments(p)
    gate.add_arguments(p)
    p.set_defaults(func=run_compare_command)


def main(argv=None) -> int:
    """Stand-alone entry point: ``python -m fogref.compare EXR --model NAME ...``.

    Same options as ``fogref compare``; ``argv`` excludes the program name.  Returns the
    exit code of the verdict; a FogrefError propagates (``python -m fogref.compare`` prints it
    in one line and exits 2, as ``fogref compare`` does).
    """
    from fogref.compare.gate import EXIT_HELP

    parser = argparse.ArgumentParser(prog="fogref compare", description=_DESCRIPTION, epilog=EXIT_HELP)
    _configure(parser)
    args = parser.parse_args(argv)
    return args.func(args)
