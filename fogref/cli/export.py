"""``fogref export --engine NAME``: paste-ready fog, camera and sun settings for an engine.

The fog settings come from a JSON file (``fogref fit --model NAME``'s, ``fogref fit``'s for
Unreal, ``fogref translate --to NAME``'s, or a fit table such as ``reports/fit/engines.json``),
from ``--param`` (on top of the JSON's, or of the model's defaults), or, with neither, from a
fit of the model to ``--scene``.  The camera and the sun are the scene's (a fit's own sun where
its JSON records one).  A shell over :func:`fogref.study.export.export_engine`.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

from fogref.atomic import write_text_atomic
from fogref.cli.checks import Choice, Number, PathArg, SceneArg
from fogref.cli.spec import UsageError, assignments, option
from fogref.errors import FogrefError
from fogref.mapping.build import parse_param_assignments
from fogref.mapping.export import ENGINES
from fogref.shipped_scenes import resolve_scene
from fogref.study.export import export_engine

NAME = "export"
SOURCE = "fogref export"
HELP = "write paste-ready fog, camera and sun settings for an engine (UE Python, Godot .tres, Rust, ...)"
DESCRIPTION = (
    "Write an engine's fog settings with the camera and the sun, as its users paste them: Unreal "
    "(UE Python), Godot (Environment .tres + .tscn), Bevy (Rust), three.js and Filament (JavaScript), "
    "Unity and HDRP (C#); each in the engine's units, axes and colour spaces.  Settings from a fit or "
    "translate JSON, --param, or a fit of the model to --scene."
)
EPILOG = "exit codes: 0 written, 2 usage or input error"
API = "fogref.study.export:export_engine"
ENGINE_NAMES = tuple(ENGINES)  #: ``--engine`` values


@dataclass
class Options:
    engine: str = option(help="the engine", check=Choice(ENGINE_NAMES), metavar="NAME")
    json: str | None = option(
        None,
        "settings from the JSON of fogref fit (--model), fogref translate or a fit table (engines.json)",
        check=PathArg(must_exist=True),
        metavar="FILE",
        api=API,
        api_name="json_path",
    )
    sun_elevation: float | None = option(
        None,
        "the fit table's row at this sun elevation",
        check=Number(-90.0, 90.0, unit="deg"),
        metavar="DEG",
        default_text="the table's first (the scene's own sun)",
        api=API,
    )
    param: dict | None = assignments(
        "a setting in the engine model's names and units; a colour is linear RGB (VALUE parsed as JSON)",
        metavar="KEY=VALUE",
        api=API,
        api_name="params",
    )
    scene: str = option(
        "valley",
        "scene of the camera and the sun (and of the fit without --json and --param)",
        check=SceneArg(),
        metavar="XML",
        api=API,
    )
    out: str | None = option(
        None,
        "file to write (Godot: the .tres; its .tscn goes beside)",
        check=PathArg(),
        metavar="PATH",
        default_text="standard output",
    )


def run(o: Options, given=frozenset()) -> int:
    params = parse_param_assignments(f"{k}={v}" for k, v in (o.param or {}).items())
    if o.sun_elevation is not None and not o.json:
        raise UsageError(f"{SOURCE}: --sun-elevation picks a row of a fit table given with --json")
    files = export_engine(o.engine, o.json, params, o.scene, o.sun_elevation)
    if o.out is None:
        for suffix, text in files.items():
            if len(files) > 1:
                print(f"# ---- {suffix}")
            sys.stdout.write(text)
        return 0
    out = Path(o.out)
    paths = [out if i == 0 else out.with_suffix(suffix) for i, suffix in enumerate(files)]
    inputs = {Path(p).resolve() for p in (resolve_scene(o.scene), o.json) if p}
    for path in paths:
        if path.resolve() in inputs:
            raise FogrefError(f"{path}: is an input of this export; choose another --out")
    for path, text in zip(paths, files.values()):
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(path, text)
        print(path)
    return 0
