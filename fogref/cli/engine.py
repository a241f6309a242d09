"""``fogref engine render TRUTH_OR_SCENE --engine threejs --out DIR``: the real engine's images of a view.

The view (camera, geometry, sun, sky, resolution) is the truth's (its scene file, checked
against its header) or the scene's (with ``--set``); the fog settings are the engine's
defaults, or with ``--from-scene`` the mapping of the scene's fog (:mod:`fogref.mapping`, the
settings ``fogref compare --model NAME --from-scene`` evaluates), then the settings the view
fixes (PlayCanvas's clip planes), and ``--param`` values override any of them; ``engine.json``
says where each came from (``fog_settings_source``).  Writes the files of
:data:`fogref.engines.render.FILES`, ready for ``fogref compare TRUTH --image DIR/final.exr
--transmittance DIR/T.exr --inscatter DIR/inscatter.exr`` or ``--image DIR/canvas.png``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from fogref.atomic import refuse_overwriting_inputs
from fogref.cli.checks import Choice, Number, PathArg
from fogref.cli.spec import assignments, option, refuse, switch
from fogref.engines import ENGINES, engine_module
from fogref.engines.render import output_paths, render_and_write
from fogref.engines.view import view_from_scene, view_from_truth
from fogref.errors import FogrefError
from fogref.gbuffer import load_truth
from fogref.mapping.build import build_model, current_parameters, parse_param_assignments
from fogref.mapping.registry import MAPPINGS

NAME = "engine"
SOURCE = "fogref engine"
HELP = "render a truth's or scene's view with a real web engine (three.js, Babylon.js, PlayCanvas, Filament)"
DESCRIPTION = (
    "Render the view of a ground-truth EXR (its scene file) or of a scene XML with a real engine "
    "(three.js, Babylon.js, PlayCanvas or Filament from node_modules, in headless Chromium, SwiftShader "
    "WebGL): its linear float render target (final.exr with distance and hit channels, T.exr, inscatter.exr, "
    "surface.exr), its 8-bit canvas as the engine ships it (canvas.png) and engine.json (version, "
    "fog settings and where each came from, the difference from fogref's port of the engine, the "
    "camera against the truth's)."
)
EPILOG = "exit codes: 0 written, 2 usage or input error (also: no Chromium or chromedriver, no node_modules)"
API = "fogref.engines.render:render_and_write"


@dataclass
class Options:
    action: str = option(help="what to do", positional=True, check=Choice(("render",)), metavar="ACTION")
    input: str = option(
        help="ground-truth EXR (fogref render) or scene XML",
        positional=True,
        check=PathArg(must_exist=True),
        metavar="TRUTH_OR_SCENE",
    )
    out: str = option(help="folder for the engine's images", check=PathArg(), metavar="DIR")
    engine: str = option("threejs", "the engine", check=Choice(tuple(ENGINES)), api=API)
    param: dict | None = assignments(
        "set an engine fog setting, in the engine model's names (fogref.models; VALUE parsed as JSON "
        "when possible; each KEY once)",
        metavar="KEY=VALUE",
    )
    from_scene: bool = switch(
        "the fog settings from the scene's fog (fogref.mapping); --param values then override"
    )
    overrides: dict | None = assignments(
        "set a scene XML $default (a scene input only), e.g. --set res=32", flag="--set"
    )
    scene: str | None = option(
        None,
        "the truth's scene file, where its header's fogref.scene is not (a truth input only)",
        check=PathArg(must_exist=True),
        metavar="FILE",
    )
    timeout: float = option(
        300.0,
        "seconds before a page that does not answer is called hung",
        check=Number(0.0, lo_open=True, unit="s"),
        api=API,
    )


def is_truth(path) -> bool:
    """True for an EXR (a truth), False for anything else (a scene XML)."""
    return Path(path).suffix.lower() == ".exr"


def engine_model(engine: str, param: dict | None, scene_params: dict | None, view=None):
    """The engine's fogref model (fog settings) and where each setting came from.

    The settings start from the model's defaults, or with ``scene_params`` from the registered
    mapping of the scene's fog (:func:`fogref.mapping.build.build_model`, as ``fogref compare
    --model NAME --from-scene`` builds it); then the settings a ``view``
    (:class:`~fogref.engines.view.EngineView`) fixes for the engine (its module's
    ``view_settings(near, far)``: PlayCanvas's clip planes); then ``param``.  Returns ``(model,
    sources)``, ``sources``: setting name -> where it came from.  A scene the mapping refuses
    gets its one-line error with the way out (``--param``)."""
    mod = engine_module(engine)
    given = parse_param_assignments([f"{k}={v}" for k, v in (param or {}).items()])
    fixed = {}
    if view is not None and hasattr(mod, "view_settings"):
        fixed = {k: v for k, v in mod.view_settings(*view.clip_planes()).items() if k not in given}
    try:
        model = build_model(mod.MODEL, {**fixed, **given}, scene_params)
    except FogrefError as e:
        if scene_params is None:
            raise
        raise FogrefError(
            f"{e}; give {engine}'s fog settings with --param KEY=VALUE instead of --from-scene"
        ) from None
    if scene_params is None:
        start = "the model's default (fogref.models)"
    else:
        fn = MAPPINGS.get(mod.MODEL)
        where = f"{fn.__module__}.{fn.__name__}" if fn is not None else f"{mod.MODEL}.from_physical"
        start = f"the scene (its fog, sky, camera) through {where} (--from-scene)"
    by_view = "the view: the engine camera's clip planes (fogref.engines.view.EngineView.clip_planes)"
    sources = {
        k: "--param" if k in given else by_view if k in fixed else start for k in current_parameters(model)
    }
    return model, sources


def run(o: Options, given=frozenset()) -> int:
    """Render, write, print one line per finding; 0 on success."""
    outputs = [(p, f"engine {k} file") for k, p in output_paths(o.out).items()]
    refuse_overwriting_inputs(
        outputs, [(o.input, "input")] + ([(o.scene, "scene")] if o.scene else []), "--out"
    )
    truth = None
    if is_truth(o.input):
        refuse(
            Options, given, ("input",), ("overrides",), SOURCE, "a truth's view is its own; render a scene"
        )

        truth = load_truth(o.input)
        view = view_from_truth(truth, o.scene)
    else:
        refuse(Options, given, ("input",), ("scene",), SOURCE, "--scene names a truth's scene")
        view = view_from_scene(o.input, o.overrides)
    scene_params = (truth.params if truth is not None else view.params) if o.from_scene else None
    model, sources = engine_model(o.engine, o.param, scene_params, view)
    inputs = [(o.input, "input")] + ([(view.source, "scene")] if truth is not None else [])
    r, paths, record = render_and_write(view, model, o.out, o.engine, truth, inputs, o.timeout, sources)
    H, W = view.shape
    print(f"{o.engine} {r.version} in Chromium {r.browser} ({r.renderer}): {W}x{H} px in {r.seconds:.1f} s")
    for line in record["summary"]:
        print(line)
    for role, p in paths.items():
        print(f"{role}: {p}")
    return 0
