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

from fogref.errors import FogrefError
from fogref.study.sweep.parameters import design_size, read_parameters
from fogref.study.sweep.sections import (
    DESIGN_KINDS,
    MAX_CONFIGS,
    SEED_POLICIES,
    read_design,
    read_execution,
    read_models,
    read_outputs,
    read_render,
    read_sweep,
)
from fogref.study.sweep.values import as_str, toml_error

try:
    import tomllib  # Python >= 3.11
except ImportError:  # pragma: no cover
    import tomli as tomllib  # type: ignore[no-redef]

__all__ = ["DESIGN_KINDS", "MAX_CONFIGS", "SEED_POLICIES", "SweepSpec", "as_str", "design_size", "load_sweep"]

_TOP_KEYS = {"sweep", "render", "design", "parameters", "models", "execution", "outputs"}


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
    unknown = set(doc) - _TOP_KEYS
    if unknown:
        raise toml_error(path, None, f"unknown table(s) {sorted(unknown)}; allowed: {sorted(_TOP_KEYS)}")
    return doc


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
    sweep = read_sweep(path, doc)
    render = read_render(path, doc)
    models = read_models(path, doc)
    design = read_design(path, doc)
    parameters = read_parameters(path, doc, sweep["scenes"], models, design, render["overrides"])
    for m in models:
        del m["fields"]
    return SweepSpec(
        path=path,
        **sweep,
        **render,
        parameters=parameters,
        design=design,
        models=models,
        **read_execution(path, doc),
        **read_outputs(path, doc, sweep["out"]),
    )
