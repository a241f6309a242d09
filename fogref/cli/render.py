"""``fogref render SCENE --out X.exr``: path-trace a scene to a ground-truth EXR.

The options are those of :func:`fogref.render.render.render`, with its defaults.  This
module imports nothing heavy: the renderer (Mitsuba, Dr.Jit) is imported when it runs.
"""

from __future__ import annotations

from dataclasses import dataclass

from fogref.cli.checks import Address, Choice, Integer, Number, PathArg, SceneArg
from fogref.cli.spec import UsageError, api_arguments, assignments, option, refuse, switch
from fogref.render.variant import VARIANTS

NAME = "render"
SOURCE = "fogref render"
HELP = "path-trace a scene to a ground-truth EXR (+ PNG preview)"
DESCRIPTION = (
    "Path-trace a Mitsuba 3 scene (fogpath integrator, heightfog medium) into a ground-truth EXR "
    "of every G-buffer and fog channel, with a PNG preview beside it.  An interrupted render "
    "(Ctrl-C) keeps a checkpoint and resumes when the same command is run again; the same command "
    "with a larger --spp adds samples to the finished truth."
)
EPILOG = "exit codes: 0 written, 2 usage or input error, 130 interrupted (run again to resume)"
API = "fogref.render.render:render"
#: ``--pixel-filter`` values (fogref.render.render.PIXEL_FILTERS, checked equal by tests/test_cli_spec.py)
PIXEL_FILTERS = ("centre", "box")
#: ``--exr-compression`` values (fogref.exrio.EXR_COMPRESSIONS, checked equal by tests/test_cli_spec.py)
EXR_COMPRESSIONS = ("zip", "zips", "rle", "piz", "none")


@dataclass
class Options:
    scene: str = option(
        help="Mitsuba XML scene with the fogpath integrator and a heightfog medium, or a shipped "
        "scene's name (valley, open_plane, ...)",
        positional=True,
        check=SceneArg(),
        metavar="SCENE",
    )
    out: str = option(
        help="output EXR path (a PNG preview goes beside it unless --no-png)",
        short="-o",
        check=PathArg(role="output"),
        metavar="X.exr",
    )
    spp: int = option(
        64,
        "samples per pixel; more than the truth already at --out holds (same scene, files and "
        "seed): the samples are added to it",
        check=Integer(1, 1 << 20),
        api=API,
    )
    seed: int = option(
        0, "random seed: the same seed gives the same pixels", check=Integer(0, (1 << 31) - 1), api=API
    )
    variant: str | None = option(
        None,
        "Mitsuba variant (a pass holds 2^25 samples on a GPU, about 7 GB: with less memory, set "
        "$FOGREF_MAX_LANES to fewer, e.g. 8388608)",
        check=Choice(VARIANTS),
        api=API,
        default_text="$FOGREF_VARIANT, else llvm_ad_rgb",
    )
    overrides: dict | None = assignments(
        "set a scene XML $default, e.g. --set res=64 (each NAME once)", flag="--set", api=API
    )
    quiet: bool = switch("no progress bar", api=API, api_name="progress", negates=True)
    no_resume: bool = switch(
        "start afresh: ignore the checkpoint of an interrupted run and the truth at --out",
        api=API,
        api_name="resume",
        negates=True,
    )
    no_png: bool = switch("no PNG preview beside the EXR", api=API, api_name="png", negates=True)
    no_moments: bool = switch(
        "do not keep the float64 sums beside the EXR (<out>.moments.npz, 576 bytes per pixel) "
        "that let a later --spp add samples",
        api=API,
        api_name="keep_moments",
        negates=True,
    )
    pixel_filter: str = option(
        "centre",
        "centre: every sample through the pixel centre, exact G-buffer and T "
        "(for truths); box: samples spread over the pixel (anti-aliased pictures)",
        check=Choice(PIXEL_FILTERS),
        api=API,
    )
    exr_compression: str = option(
        "zip",
        "the EXR's lossless compression: zip (the smallest file), zips, rle, piz, or none "
        "(the fastest to write, about 1.7x the size of zip); the values are the same",
        check=Choice(EXR_COMPRESSIONS),
        api=API,
    )
    checkpoint_seconds: float = option(
        60.0,
        "seconds between checkpoints of an interruptible render (one is "
        "also written on Ctrl-C); 0: after every pass",
        check=Number(0.0, 1e9, unit="s"),
        metavar="S",
        api=API,
    )
    scheduler: str | None = option(
        None,
        "a running Dask scheduler (tcp://HOST:8786): its workers render the passes (same pixels)",
        check=Address(),
        metavar="ADDRESS",
        api=API,
        default_text="this process, or a LocalCluster with --workers",
    )
    workers: int | None = option(
        None,
        "render the passes on a LocalCluster of N single-threaded worker processes (same pixels)",
        check=Integer(1, 4096),
        api=API,
        metavar="N",
        default_text="none: this process",
    )
    worker_timeout: float = option(
        600.0,
        "with --scheduler: seconds to wait for its first worker (it says that it waits), then an error",
        check=Number(0.0, 1e6, lo_open=True, unit="s"),
        metavar="S",
        api=API,
    )


def run(o: Options, given=frozenset()) -> int:
    """Render; print the EXR's path."""
    # here, not at module level: parsing a command line imports no renderer (test_cli_spec)
    from fogref.render.render import render

    refuse(
        Options, given, ("scheduler",), ("workers",), SOURCE, "the workers of a running scheduler are its own"
    )
    if "worker_timeout" in given and "scheduler" not in given:
        raise UsageError(f"{SOURCE}: --worker-timeout applies only with --scheduler")
    path = render(o.scene, o.out, **{**api_arguments(o, API), "overrides": o.overrides or {}})
    print(path)
    return 0
