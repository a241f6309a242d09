"""``fogref compare EXR (--model NAME | --image FILE ... | --engine NAME)``: check a fog, gate CI.

Three modes: a fog model (``--model``, with ``--param``, ``--from-scene``, ``--precision``,
``--sky-distance``), an engine's images (``--image``/``--transmittance``/``--inscatter``/
``--fog-colour``, with ``--encoding`` and ``--exposure``), or a real engine rendered here
(``--engine``, with ``--param``, ``--from-scene``, ``--engine-output``, ``--scene``: its images,
written under ``OUT/engine``, are then checked as ``--image`` checks an engine's images).  An
option of another mode is refused, not ignored.  The verdict is
:func:`fogref.compare.check.check`'s (the checker of ``assert_fog_matches``); exit codes: 0 pass,
1 fail, 2 usage or input error, 3 inconclusive (:mod:`fogref.compare.gate`).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

from fogref.atomic import check_output_file
from fogref.cli.checks import Check, Choice, Number, PathArg
from fogref.cli.compare_batch import ImageList, run_batch
from fogref.cli.engine import engine_model
from fogref.cli.spec import UsageError, api_arguments, assignments, option, processes_option, refuse, switch
from fogref.compare import gate
from fogref.compare.check import check
from fogref.compare.foreign import ENCODINGS, load_engine_images
from fogref.compare.gate import parse_distance_bands, parse_tolerances
from fogref.compare.report import compare, compare_images, refuse_output_over_input, report_paths
from fogref.compare.workers import start_workers
from fogref.engines import ENGINES
from fogref.engines.render import render_and_write
from fogref.engines.view import view_from_truth
from fogref.gbuffer import load_truth
from fogref.html.reports import write_compare_html
from fogref.mapping.build import build_model, parse_param_assignments

NAME = "compare"
SOURCE = "fogref compare"
HELP = (
    "check a game fog model or an engine's images against a ground-truth EXR; report; "
    "exit 0 pass, 1 fail, 2 error, 3 inconclusive"
)
DESCRIPTION = (
    "Check a game fog model (--model) or an engine's images (--image/--transmittance/--inscatter) against "
    "a ground-truth EXR with fogref.compare.check.check (the checker of assert_fog_matches: confidence "
    "intervals with the truth's noise removed, a verdict per part, region and metric) and write "
    "metrics.json, check.json, errors.exr, PNG heatmaps, error-vs-distance/sun-angle plots and index.md."
)
EPILOG = (
    "exit codes: 0 pass, 1 fail, 2 usage or input error, 3 inconclusive (no row fails but an "
    "interval straddles its tolerance; --inconclusive fail|pass maps it to 1|0)"
)
COMPARE = "fogref.compare.report:compare"
CHECK = "fogref.compare.check:check"
IMAGES = "fogref.compare.foreign:load_engine_images"
MODEL_GROUP = "a fog model"
IMAGE_GROUP = "an engine's images (instead of --model)"
ENGINE_GROUP = "a real engine rendered here (instead of --model or --image; with --param, --from-scene)"
GATE_GROUP = "verdict (fogref.compare.check.check, as assert_fog_matches)"
#: the options of each mode (field names)
MODEL_ONLY = ("model", "param", "from_scene", "precision", "sky_distance")
IMAGE_ONLY = ("image", "transmittance", "inscatter", "fog_colour", "encoding", "exposure")
ENGINE_ONLY = ("engine", "engine_output", "scene")


def _engine_image(help: str):
    """An engine image option of :func:`~fogref.compare.foreign.load_engine_images` (a file read)."""
    return option(None, help, check=PathArg(role="input"), metavar="FILE", group=IMAGE_GROUP, api=IMAGES)


class Tolerances(Check):
    """``--tolerance PART[/REGION][:METRIC]=VALUE`` options (:func:`fogref.compare.gate.parse_tolerances`)."""

    metavar = "PART[/REGION][:METRIC]=VALUE"
    takes_list = True

    def parse(self, raw, name, source):
        return parse_tolerances(raw)


class DistanceBands(Check):
    """``--distance-bands 100,1000`` [m] (:func:`fogref.compare.gate.parse_distance_bands`)."""

    metavar = "M,M"

    def parse(self, raw, name, source):
        return parse_distance_bands(raw)

    def describe(self):
        return "increasing distances [m] > 0, or 'none'"


@dataclass
class Options:
    exr: str = option(
        help="ground-truth EXR written by fogref render",
        positional=True,
        check=PathArg(role="input"),
        metavar="EXR",
    )
    out: str | None = option(
        None, "report folder", check=PathArg(), default_text="out/compare/<EXR stem>-<model or image stem>"
    )
    no_figures: bool = switch(
        "no figures: write only metrics.json, check.json, errors.exr, index.md and report.html, the "
        "viewer without its plots (no PNGs; faster, for CI)",
        api=COMPARE,
        api_name="figures",
        negates=True,
    )
    no_perceptual: bool = switch(
        "leave out the perceptual metrics, ΔE2000 and HDR-FLIP (their maps, means, noise floors and "
        "heatmaps): every other value is the same, in a fraction of the time (FLIP is most of a "
        "comparison's work; for CI and large images)",
        api=COMPARE,
        api_name="perceptual",
        negates=True,
    )
    processes: int | None = processes_option("the report's figures")
    model: str | None = option(
        None,
        "fog model: a built-in name (e.g. ue4), module.path:Class, or a 'fogref.models' entry point",
        group=MODEL_GROUP,
        metavar="NAME",
    )
    param: dict | None = assignments(
        "set a model parameter (VALUE parsed as JSON when possible; each KEY once)",
        metavar="KEY=VALUE",
        group=MODEL_GROUP,
    )
    from_scene: bool = switch(
        "derive the model parameters from the EXR's physical fog (model.from_physical); "
        "--param values then override",
        group=MODEL_GROUP,
    )
    precision: str = option(
        "float32",
        "arithmetic precision of the model evaluation",
        check=Choice(("float32", "float64")),
        group=MODEL_GROUP,
        api=COMPARE,
    )
    sky_distance: float = option(
        1.0e5,
        "distance at which sky pixels are fogged",
        check=Number(0.0, lo_open=True, unit="m"),
        metavar="M",
        group=MODEL_GROUP,
        api=COMPARE,
    )
    image: str | None = option(
        None,
        "the engine's final image (.exr, .png, .hdr) of the truth's view and resolution; several "
        "files or a pattern: one report each and one table (fogref.cli.compare_batch)",
        check=ImageList(),
        nargs="+",
        metavar="FILE",
        group=IMAGE_GROUP,
        api=IMAGES,
    )
    transmittance: str | None = _engine_image("the engine's fog transmittance image")
    inscatter: str | None = _engine_image("the engine's fog inscatter image")
    fog_colour: str | None = _engine_image(
        "the engine's fog colour C (final = lerp(scene, C, 1 - T)); needs --transmittance"
    )
    encoding: str = option(
        "auto",
        "how the radiance images are encoded (auto: an 8-bit PNG is sRGB, EXR/HDR "
        "linear; the transmittance is always linear); the encoding used is in the report",
        check=Choice(ENCODINGS),
        group=IMAGE_GROUP,
        api=IMAGES,
    )
    exposure: float = option(
        1.0,
        "the engine's exposure scale; radiance images are divided by it",
        check=Number(0.0, lo_open=True),
        metavar="X",
        group=IMAGE_GROUP,
        api=IMAGES,
    )
    engine: str | None = option(
        None,
        "render the truth's view with this engine (its scene file; fog from --from-scene and --param) "
        "and check its images",
        check=Choice(tuple(ENGINES)),
        group=ENGINE_GROUP,
    )
    engine_output: str = option(
        "linear",
        "which images of the engine to check: linear (its float render target: final, T, inscatter) "
        "or canvas (the 8-bit sRGB canvas it ships)",
        check=Choice(("linear", "canvas")),
        group=ENGINE_GROUP,
    )
    scene: str | None = option(
        None,
        "the truth's scene file, where its header's fogref.scene is not",
        check=PathArg(must_exist=True),
        metavar="FILE",
        group=ENGINE_GROUP,
    )
    tolerance: dict | None = option(
        None,
        "tolerance of a row: METRIC rel_rmse (default), rel_bias, rmse or bias; "
        "VALUE a number >= 0 or 'none' to only report; e.g. inscatter/sky=0.05, "
        "T:rel_bias=0.001",
        repeat=True,
        check=Tolerances(),
        group=GATE_GROUP,
        api=CHECK,
        api_name="tolerances",
    )
    distance_bands: tuple = option(
        (100.0, 1000.0),
        "edges of the distance-band regions",
        check=DistanceBands(),
        group=GATE_GROUP,
        api=CHECK,
    )
    confidence: float = option(
        0.99,
        "two-sided level of the intervals",
        check=Number(0.0, 1.0, lo_open=True, hi_open=True),
        metavar="C",
        group=GATE_GROUP,
        api=CHECK,
    )
    inconclusive: str | None = option(
        None,
        "exit 1 (fail) or 0 (pass) on an inconclusive verdict instead of 3",
        check=Choice(("fail", "pass")),
        group=GATE_GROUP,
    )
    json: str | None = option(
        None,
        "write every row (estimate, interval, tolerance, verdict), the verdict and the exit code",
        check=PathArg(role="output"),
        metavar="FILE",
        group=GATE_GROUP,
    )
    junit: str | None = option(
        None,
        "write JUnit XML: a testcase per row with a tolerance (failure: fail and "
        "inconclusive; skipped: no pixels, or inconclusive with --inconclusive pass)",
        check=PathArg(role="output"),
        metavar="FILE",
        group=GATE_GROUP,
    )


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

    print(
        f"{name} vs {exr}: final RMSE {pm('rmse')} (noise floor {final.get('rmse_noise_floor', 0):.2g}"
        f"{', below the noise' if final.get('rmse_below_noise') else ''}), relMSE {pm('relmse')}, "
        f"mean error {pm('mean_error')}"
        + (
            f", ΔE2000 mean {final['delta_e2000_mean']:.3g}, FLIP mean {final['flip_mean']:.3g}"
            if "flip_mean" in final
            else ""
        )
    )


def check_modes(o: Options, given) -> bool:
    """True for the images mode, False for a model or an engine; UsageError for several, none, or an
    option of another mode (refused, not ignored)."""
    images = any(n in given for n in IMAGE_ONLY[:4])
    if sum((images, bool(o.model), bool(o.engine))) > 1:
        raise UsageError(
            "give --model, the engine's images (--image/--transmittance/--inscatter) or --engine: "
            "one, not both"
        )
    if not images and not o.model and not o.engine:
        raise UsageError(
            "give --model NAME (or module.path:Class), an engine's image with --image FILE, or --engine NAME"
        )
    if o.engine:
        refuse(
            Options,
            given,
            ("engine",),
            IMAGE_ONLY + ("precision", "sky_distance"),
            SOURCE,
            "not an engine's option",
        )
        return False
    refuse(Options, given, IMAGE_ONLY[:4] + ("model",), ENGINE_ONLY, SOURCE, "options of --engine")
    if images:
        refuse(Options, given, IMAGE_ONLY[:4], MODEL_ONLY, SOURCE, "options of a --model comparison")
    else:
        refuse(Options, given, ("model",), IMAGE_ONLY, SOURCE, "options of an engine's images")
    return images


def _out_dir(o: Options) -> Path:
    """The report folder: ``--out``, else :func:`default_out_dir` of the model or the first image."""
    if o.out:
        return Path(o.out)
    name = o.model or o.engine or Path(o.image or o.inscatter or o.transmittance or o.fog_colour).stem
    return default_out_dir(o.exr, name)


def _refuse_outputs_over_inputs(o: Options) -> None:
    """A ParameterError (exit 2) before any work when a file the run writes
    (the report's files and figures, ``--json``, ``--junit``) resolves to an input (the truth, an
    engine image) or two outputs to the same file (:func:`fogref.compare.report.refuse_output_over_input`)."""
    inputs = [
        ("EXR", o.exr),
        ("--image", o.image),
        ("--transmittance", o.transmittance),
        ("--inscatter", o.inscatter),
        ("--fog-colour", o.fog_colour),
    ]
    report = [("--out", p) for p in [*report_paths(_out_dir(o)), _out_dir(o) / "report.html"]]
    for _, p in report:
        check_output_file(p, f"{SOURCE}: --out")
    gate = [(n, p) for n, p in (("--json", o.json), ("--junit", o.junit)) if p]
    refuse_output_over_input(report + gate, inputs, SOURCE)
    # --json/--junit must not replace a report file nor each other
    refuse_output_over_input(gate[1:], gate[:1], SOURCE, what="output")
    refuse_output_over_input(gate, report, SOURCE, what="output")


def _engine_images(o: Options, truth):
    """Render the truth's view with ``--engine`` into ``OUT/engine`` and read back the images of
    ``--engine-output``; returns ``(EngineImages, the engine's record)``."""
    view = view_from_truth(truth, o.scene)
    model, sources = engine_model(o.engine, o.param, truth.params if o.from_scene else None, view)
    inputs = [(o.exr, "EXR"), (view.source, "scene")]
    _, paths, record = render_and_write(
        view, model, _out_dir(o) / "engine", o.engine, truth, inputs, sources=sources
    )
    if o.engine_output == "canvas":
        imgs = load_engine_images(paths["canvas"], shape=truth.shape, truth_name=str(o.exr))
    else:
        imgs = load_engine_images(
            paths["final"],
            paths.get("transmittance"),
            paths.get("inscatter"),
            shape=truth.shape,
            truth_name=str(o.exr),
        )
    return imgs, record


def run(o: Options, given=frozenset()) -> int:
    """Check the candidate, write the report, return the exit code (see :data:`EPILOG`).

    Options are checked before anything is read; warnings (model non-finite values,
    excluded pixels) go to stderr.
    """
    images = check_modes(o, given)
    if images and isinstance(o.image, tuple):  # several images: one table (fogref.cli.compare_batch)
        return run_batch(o, given, default_out_dir(o.exr, "batch"), api_arguments(o, CHECK))
    options = api_arguments(o, CHECK)
    _refuse_outputs_over_inputs(o)
    if not o.no_figures:
        start_workers(o.processes)  # they import matplotlib while the truth is read and checked
    truth = load_truth(o.exr)
    extra = {}
    if o.engine:
        imgs, extra["engine"] = _engine_images(o, truth)
    elif images:
        imgs = load_engine_images(**api_arguments(o, IMAGES), shape=truth.shape, truth_name=str(o.exr))
    out = _out_dir(o)
    if o.engine or images:
        result = check(truth, imgs, **options)
        report = compare_images(
            truth,
            imgs,
            out,
            figures=not o.no_figures,
            perceptual=not o.no_perceptual,
            processes=o.processes,
            check=result,
            engine=extra.get("engine"),
        )
        extra["encodings"] = report["images"]["encodings"]
        for line in extra.get("engine", {}).get("summary", ()):
            print(line)
    else:
        assignments = [f"{k}={v}" for k, v in (o.param or {}).items()]
        model = build_model(
            o.model, parse_param_assignments(assignments), truth.params if o.from_scene else None
        )
        result = check(truth, model, **options, precision=o.precision, sky_distance=o.sky_distance)
        report = compare(truth, model, out, check=result, processes=o.processes, **api_arguments(o, COMPARE))
        _print_metrics(o.model, o.exr, report["metrics"]["final"]["all"])
    for w in report["warnings"]:
        print(f"fogref compare: warning: {w}", file=sys.stderr)
    print(f"report: {out / 'index.md'}")

    print(f"html: {write_compare_html(out, truth)}")
    return gate.finish(o, result, report=str(out), **extra)
