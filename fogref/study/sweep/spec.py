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
from fogref.errors import FogrefError
from fogref.mapping.unreal_pathtracer import settings_from
from fogref.study.sweep.parameters import design_size, read_parameters
from fogref.study.sweep.sections import (
    DESIGN_KINDS,
    MAX_CONFIGS,
    SEED_POLICIES,
    SWEEP_KINDS,
    UE_PATHTRACER_FIELDS,
    read_closed_form,
    read_design,
    read_execution,
    read_models,
    read_outputs,
    read_render,
    read_sweep,
)
from fogref.study.sweep.values import as_str, sweep_error, table_source

try:
    import tomllib  # Python >= 3.11
except ImportError:  # pragma: no cover
    import tomli as tomllib  # type: ignore[no-redef]

__all__ = ["DESIGN_KINDS", "MAX_CONFIGS", "SEED_POLICIES", "SweepSpec", "as_str", "design_size", "load_sweep"]

#: The tables of a sweep file, per ``[sweep] kind``.
_TOP_KEYS = {
    "render": {"sweep", "render", "design", "parameters", "models", "execution", "outputs"},
    "ue_pathtracer": {"sweep", "fixed", "sun", "views", "design", "parameters", "execution", "outputs"},
}


class SweepSpec:
    """A validated sweep: what :func:`load_sweep` returns.

    Attributes
    ----------
    path : Path
        The TOML file.
    name : str
        The sweep's name.
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
    """

    def __init__(self, **kw):
        self.__dict__.update(kw)


def _read_toml(path: Path) -> dict:
    if not path.is_file():
        raise FogrefError(f"{path}: no such sweep file")
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as e:
        raise FogrefError(f"{path}: not valid TOML ({e})") from None
    return doc


def _kind(path: Path, doc: dict) -> str:
    """``[sweep] kind`` (:data:`SWEEP_KINDS`, default ``render``), the file's tables checked against it."""
    sw = doc.get("sweep", {})
    kind = P.choice(
        sw.get("kind", "render") if isinstance(sw, dict) else "render",
        "kind",
        SWEEP_KINDS,
        table_source(path, "sweep"),
    )
    unknown = set(doc) - _TOP_KEYS[kind]
    if unknown:
        raise sweep_error(
            path,
            None,
            f"unknown table(s) {sorted(unknown)} for kind '{kind}'; allowed: {sorted(_TOP_KEYS[kind])}",
        )
    return kind


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
    doc = _read_toml(path)
    if _kind(path, doc) == "ue_pathtracer":
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
    """A ``ue_pathtracer`` sweep: no scene and no render; its parameters are the editor values of its
    one model, ``ue_pathtracer`` (:data:`~fogref.study.sweep.sections.UE_PATHTRACER_FIELDS`), each value
    checked by the settings themselves."""
    cf = read_closed_form(path, doc)
    fixed = {k: v for k, v in cf["closed_form"]["fixed"].items() if k != "camera"}
    model = {"name": "ue_pathtracer", "label": "ue_pathtracer", "from_scene": False, "params": fixed}
    design = read_design(path, doc)
    parameters = read_parameters(
        path, doc, [], [{**model, "fields": UE_PATHTRACER_FIELDS}], design, {}, default_model="ue_pathtracer"
    )
    for label, p in parameters.items():
        for v in p.get("values", p.get("range", [])):
            try:
                settings_from(**fixed, **{p["target"]: v * p["scale"]})
            except (FogrefError, TypeError, ValueError) as e:
                raise sweep_error(path, f"parameters.{label}", f"value {v!r} refused: {e}") from None
    return SweepSpec(
        path=path,
        kind="ue_pathtracer",
        name=cf["name"],
        out=cf["out"],
        closed_form=cf["closed_form"],
        scenes=[],
        cache=None,
        spp=0,
        seed=0,
        seed_policy="fixed",
        pixel_filter="centre",
        overrides={},
        parameters=parameters,
        design=design,
        models=[model],
        **read_execution(path, doc),
        **read_outputs(path, doc, cf["out"]),
    )
