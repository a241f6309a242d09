"""``fogref translate``: one engine's fog settings carried to another's through the physical truth.

:func:`fogref.mapping.translate.translate`: the source's settings -> its physical fog (the exact
extinction mapping where one exists, else fitted; the light fitted) -> the target's best fit.
JSON on stdout; on stderr the source settings fogref filled in (each with where it took it
from: the engine's defaults without ``--scene``, that scene's fit with it), the target's settings
with their units and colour spaces, and the error no setting can remove.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass

from fogref.cli.checks import Integer, Number, SceneArg, Text
from fogref.cli.spec import assignments, option
from fogref.mapping.build import parse_param_assignments
from fogref.mapping.fit import model_class
from fogref.models.terms import describe, note
from fogref.study.fit import translate

NAME = "translate"
SOURCE = "fogref translate"
HELP = "carry one engine's fog settings to another's through the physical fog (prints JSON)"
DESCRIPTION = (
    "Translate fog settings between engines: the source model's settings (--param) become a physical "
    "fog (the exact extinction mapping where one exists), and the target model is fitted to it.  Reports "
    "the residual error no target setting can remove, against the physical fog and against the source."
)
EPILOG = "exit codes: 0 translated, 2 usage or input error"
API = "fogref.study.fit:translate"


@dataclass
class Options:
    source: str = option(
        help="source model (ue4, unity, godot, ... or module.path:Class)",
        flag="--from",
        check=Text(),
        metavar="NAME",
    )
    target: str = option(help="target model", flag="--to", check=Text(), metavar="NAME")
    param: dict | None = assignments(
        "a source setting in the engine's units; a colour is linear RGB (VALUE parsed as JSON when possible)",
        metavar="KEY=VALUE",
    )
    scene: str | None = option(
        None,
        "reference scene (camera, albedo, sun, light); the source settings not given then come "
        "from its fit (a path or a shipped scene's name)",
        check=SceneArg(),
        metavar="XML",
        api=API,
        default_text="the shipped valley scene for camera, albedo and sun; the engine's defaults "
        "for the settings not given",
    )
    sun_elevation: list | None = option(
        None,
        "a sun elevation to fit over (repeat for several)",
        repeat=True,
        check=Number(-90.0, 90.0, unit="deg"),
        metavar="DEG",
        default_text="the scene's sun",
    )
    directions: int = option(512, "view directions on the sphere", check=Integer(8, 100_000))


def run(o: Options, given=frozenset()) -> int:
    model_class(o.source), model_class(o.target)  # unknown names: "did you mean", before any work
    params = parse_param_assignments(f"{k}={v}" for k, v in (o.param or {}).items())
    t = translate(o.source, o.target, params, o.scene, views=o.directions, sun_elevations=o.sun_elevation)
    print(json.dumps(t.to_dict(), indent=2))
    r = t.target
    print(f"{t.source} settings not given, filled in:", file=sys.stderr)
    for origin in dict.fromkeys(d["from"] for d in t.filled.values()):
        print(f"  from {origin}:", file=sys.stderr)
        for k, d in t.filled.items():
            if d["from"] == origin:
                print(f"    {k:40s} {describe(t.source, k, d['value'])}", file=sys.stderr)
    print(f"{t.source} -> {r.model} (physical extinction: {t.physical['extinction']}):", file=sys.stderr)
    for k, v in r.values.items():
        print(f"  {k:42s} {v:.6g} ± {r.uncertainty[k]:.2g}  {note(r.model, k, v)}".rstrip(), file=sys.stderr)
    print(
        f"  residual (inscatter relative RMSE): vs the physical fog {t.residual_vs_truth:.3f}, vs the "
        f"source {t.residual_vs_source:.3f}; physical fog vs source {t.source_vs_physical:.3f}",
        file=sys.stderr,
    )
    if r.note:
        print(f"  {r.model} cannot represent: {r.note}", file=sys.stderr)
    return 0
