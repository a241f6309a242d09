"""``fogref study [EXR]``: the Unreal study (fit, comparison, error budget, README) of a truth.

The work is :func:`fogref.study.unreal.run_study`; its defaults are the options' defaults.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from fogref.cli.checks import Number, PathArg
from fogref.cli.spec import option, processes_option, switch
from fogref.gbuffer import load_truth
from fogref.html.reports import write_study_html
from fogref.study.ue_pathtracer import split_study
from fogref.study.unreal import run_study

NAME = "study"
HELP = "the Unreal study of a truth: fit, compare, error budget, README"
DESCRIPTION = (
    "Derive Unreal parameters from the EXR's physical fog, compare, compute the error budget (a "
    "telescoping chain from the truth to Unreal, one effect per step) and write the report folder."
)
EPILOG = "exit codes: 0 written, 2 usage or input error"
STUDY = "fogref.study.unreal:run_study"
UNREAL = "Unreal settings of the study's model"


@dataclass
class Options:
    exr: str = option(
        "out/valley.exr", "ground-truth EXR", positional=True, check=PathArg(role="input"), metavar="EXR"
    )
    out: str = option("out/unreal_study", "report folder", check=PathArg(), api=STUDY, api_name="out_dir")
    renders: str = option(
        "out/study",
        "cache folder of the budget's extra renders",
        check=PathArg(),
        api=STUDY,
        api_name="renders_dir",
    )
    scene: str | None = option(
        None, "the EXR's scene, if its recorded path is not found", check=PathArg(), api=STUDY
    )
    no_compare: bool = switch(
        "skip the fogref.compare report", api=STUDY, api_name="compare_report", negates=True
    )
    processes: int | None = processes_option("the comparison's figures")
    ue_pathtracer: bool = switch(
        "also split what a UE user sees into raster EHF vs UE's path-traced fog and UE's path-traced "
        "fog vs the exact fog, each with its noise (fogref.study.ue_pathtracer.split_study): a section "
        "of budget.md, summary.json's ue_pathtracer_split and ue_pathtracer_split.json"
    )
    start_distance: float | None = option(
        None, "Unreal StartDistance", check=Number(0.0, unit="cm"), group=UNREAL, default_text="0"
    )
    max_opacity: float | None = option(
        None, "Unreal FogMaxOpacity", check=Number(0.0, 1.0), group=UNREAL, default_text="1"
    )
    cutoff: float | None = option(
        None,
        "Unreal FogCutoffDistance (0: off)",
        check=Number(0.0, unit="cm"),
        group=UNREAL,
        default_text="0",
    )


def run(o: Options, given=frozenset()) -> int:
    named = {"StartDistance": o.start_distance, "FogMaxOpacity": o.max_opacity, "FogCutoffDistance": o.cutoff}
    settings = {k: v for k, v in named.items() if v is not None}
    run_study(
        o.exr,
        o.out,
        o.renders,
        scene=o.scene,
        compare_report=not o.no_compare,
        settings=settings,
        processes=o.processes,
    )
    if o.ue_pathtracer:
        split_study(o.exr, o.out, Path(o.renders) / "ue_pathtracer", scene=o.scene)

    print(f"html: {write_study_html(o.out, load_truth(o.exr))}")
    return 0
