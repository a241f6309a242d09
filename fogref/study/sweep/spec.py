"""The sweep file: ``SWEEP.toml`` read and validated into a :class:`SweepSpec`, one table at a time.

The schema is in :mod:`fogref.study.sweep`'s docstring.  :func:`load_sweep` reads
the TOML and hands each table to its reader (``[sweep]``, ``[render]``,
``[[models]]``, ``[design]``, ``[parameters.*]``, ``[execution]``, ``[outputs]``);
every reader raises one :class:`~fogref.errors.FogrefError` line naming the file,
the table or key and the allowed values.  The readers are in
:mod:`~fogref.study.sweep.sections` and :mod:`~fogref.study.sweep.parameters` (``[parameters.*]``
and the checks across tables), the value checks they share in :mod:`~fogref.study.sweep.values`.
"""

from __future__ import annotations

from pathlib import Path

from fogref import params as P
from fogref.errors import FogrefError, ParameterError
from fogref.study.sweep.parameters import design_size, read_parameters
from fogref.study.sweep.sections import (
    DESIGN_KINDS,
    MAX_CONFIGS,
    SEED_POLICIES,
    UE_PATHTRACER_FIELDS,
    read_closed_form,
    read_design,
    read_execution,
    read_models,
    read_outputs,
    read_render,
    read_sweep,
    ue_settings,
)
from fogref.study.sweep.values import as_str, toml_error, toml_src

try:
    import tomllib  # Python >= 3.11
except ImportError:  # pragma: no cover
    import tomli as tomllib  # type: ignore[no-redef]

__all__ = ["DESIGN_KINDS", "MAX_CONFIGS", "SEED_POLICIES", "SweepSpec", "as_str", "design_size", "load_sweep"]

#: The tables of a sweep file per ``[sweep] kind``: ``render`` (each configuration renders and compares)
#: or ``ue_pathtracer`` (closed form, nothing rendered: :mod:`fogref.study.sweep`'s docstring).
_TOP_KEYS = {"render": {"sweep", "render", "design", "parameters", "models", "execution", "outputs"}}
_TOP_KEYS["ue_pathtracer"] = _TOP_KEYS["render"] - {"render", "models"} | {"fixed", "sun", "views"}


class SweepSpec:
    """A validated sweep: what :func:`load_sweep` returns.

    Attributes
    ----------
    path : Path
        The TOML file.
    name, kind : str
        The sweep's name; ``render`` or ``ue_pathtracer`` (closed form: ``closed_form`` holds its
        ``fixed``, ``sun``, ``views`` and ``threshold``; no scenes, cache, spp, seed or seed policy).
    scenes : list of Path
        Scene files.
    out, cache : Path
        Output folder and ground-truth cache folder.
    spp, seed : int
        Samples per pixel; base seed.
    seed_policy : str
        ``"fixed"`` or ``"per_config"``.
    pixel_filter : str
        Passed to the render driver.
    overrides : dict
        Fixed scene ``$defaults`` (strings).
    parameters : dict
        label -> parameter spec (``target``, ``kind`` ``scene``/``model``, ``model``,
        ``scale``, ``values`` or ``range``/``log``/``num``).
    design : dict
        ``kind``, ``n``, ``seed``, ``max_configs`` (the size limit, default :data:`MAX_CONFIGS`).
    models : list of dict
        ``name``, ``label``, ``from_scene``, ``params``.
    retries : int
        Dask retries per configuration.
    table : str
        Table base name.  plots : bool.  plot_metrics : list of str or None.
    budget : bool
        Unreal's error budget for every "ue4" model.
    perceptual : bool
        The comparisons' perceptual metrics (ΔE2000, FLIP); False leaves them out.
    """

    def __init__(self, **kw):
        self.__dict__.update(kw)


def _read_toml(path: Path) -> tuple[dict, str]:
    """The parsed file and its ``[sweep] kind`` (a key of ``_TOP_KEYS``, default ``render``), its
    tables checked against the kind's."""
    if not path.is_file():
        raise FogrefError(f"{path}: no such sweep file")
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as e:
        raise FogrefError(f"{path}: not valid TOML ({e})") from None
    sw = doc["sweep"] if isinstance(doc.get("sweep"), dict) else {}
    kind = P.choice(sw.get("kind", "render"), "kind", tuple(_TOP_KEYS), toml_src(path, "sweep"))
    allowed = _TOP_KEYS[kind]
    if set(doc) - allowed:
        bad = sorted(set(doc) - allowed)
        raise toml_error(path, None, f"unknown table(s) {bad} for kind '{kind}'; allowed: {sorted(allowed)}")
    return doc, kind


def load_sweep(path) -> SweepSpec:
    """Read and validate a sweep TOML file.

    Parameters
    ----------
    path : str or Path
        The ``SWEEP.toml`` (schema in :mod:`fogref.study.sweep`'s docstring).

    Returns
    -------
    SweepSpec

    Raises
    ------
    FogrefError
        One line naming the file, the key and the allowed values for anything malformed
        (values pass through :mod:`fogref.params`): an unknown table or key, a scene that
        does not exist, a parameter that is not a ``$default`` of every scene or not
        ``<model>.<parameter>`` of a listed model (did-you-mean), a value the scene or its
        medium refuses (the medium's own ranges), a repeated value, two labels of one
        target, a target both swept and fixed, a design larger than ``[design]
        max_configs`` (default :data:`MAX_CONFIGS`; sized before anything is built), a
        table path outside the output folder, an unknown design kind, seed policy,
        pixel filter or model.
    """
    path = Path(path)
    doc, kind = _read_toml(path)
    if kind == "ue_pathtracer":
        return _closed_form_sweep(path, doc)
    sweep = read_sweep(path, doc)
    render = read_render(path, doc)
    models = read_models(path, doc)
    design = read_design(path, doc)
    parameters = read_parameters(path, doc, sweep["scenes"], models, design, render["overrides"])
    for m in models:
        del m["fields"]
    return SweepSpec(
        path=path,
        kind="render",
        **sweep,
        **render,
        parameters=parameters,
        design=design,
        models=models,
        **read_execution(path, doc),
        **read_outputs(path, doc, sweep["out"]),
    )


def _closed_form_sweep(path: Path, doc: dict) -> SweepSpec:
    """A ``ue_pathtracer`` sweep: no scene, no render; its parameters are editor values of its one
    model ``ue_pathtracer`` (:data:`~fogref.study.sweep.sections.UE_PATHTRACER_FIELDS`)."""
    cf = read_closed_form(path, doc)
    fixed = {k: v for k, v in cf["closed_form"]["fixed"].items() if k != "camera"}
    model = {"name": "ue_pathtracer", "label": "ue_pathtracer", "from_scene": False, "params": fixed}
    design = read_design(path, doc)
    parameters = read_parameters(path, doc, [], [{**model, "fields": UE_PATHTRACER_FIELDS}], design, {})
    for label, p in parameters.items():
        for v in p.get("values", p.get("range", [])):
            ue_settings(path, f"parameters.{label}", {**fixed, p["target"]: v * p["scale"]}, v)
    return SweepSpec(
        path=path,
        kind="ue_pathtracer",
        **cf,
        **dict(scenes=[], cache=None, spp=None, seed=None, seed_policy=None),
        parameters=parameters,
        design=design,
        models=[model],
        **read_execution(path, doc),
        **_no_perceptual_option(path, read_outputs(path, doc, cf["out"]), doc),
    )


def _no_perceptual_option(path: Path, outputs: dict, doc: dict) -> dict:
    """A closed-form sweep's ``[outputs]``: it compares no images, so ``perceptual`` is refused."""
    if "perceptual" in (doc.get("outputs") or {}):
        raise ParameterError(
            toml_src(path, "outputs"),
            "perceptual",
            "a ue_pathtracer sweep compares closed forms, no images: it has no perceptual metrics to "
            "leave out",
        )
    return outputs
