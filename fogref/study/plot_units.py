"""Axis labels with units for the study's and the sweep's plots.

A metric ``<part>.<region>.<name>`` of a sweep's table is in its part's units: radiance (the
scene's units) for ``final``, ``inscatter``, ``attenuated_surface`` and ``composite``, 1 for
``transmittance``; relative metrics, ΔE2000 and FLIP are dimensionless.  A swept parameter's unit
is known for the scene's ``$default`` names below and for the built-in models' parameters
(:mod:`fogref.models.terms`, where a name has one unit across the models), else the label says the
value is as written in SWEEP.toml.

Examples
--------
>>> metric_label("final.all.rmse")
'final.all.rmse [radiance, scene units]'
>>> metric_label("transmittance.all.rmse")
'transmittance.all.rmse [1]'
>>> parameter_label("sun_elevation"), parameter_label("something")
('sun_elevation [degrees]', 'something (as in SWEEP.toml)')
>>> parameter_label("ue4.StartDistance")
'ue4.StartDistance [cm]'
"""

from __future__ import annotations

from fogref.models.terms import TERMS

#: Units of the scene ``$default`` names a sweep may vary (a model's parameters: :mod:`fogref.models.terms`).
PARAMETER_UNITS = {
    "sun_elevation": "degrees",
    "sun_azimuth": "degrees",
    "g": "1, Henyey-Greenstein asymmetry",
    "falloff": "1/m",
    "density": "1/m",
    "sigma_t": "1/m",
    "albedo": "1",
    "fov": "degrees",
    "spp": "samples per pixel",
}
DIMENSIONLESS = ("relmse", "rel_", "delta_e2000", "flip")
#: The names of the perceptual metrics (ΔE2000, HDR-FLIP), which a comparison may leave out.
PERCEPTUAL = ("delta_e2000", "flip")
#: The headline metrics of a sweep's table (``<part>.<region>.<name>``): what a sweep plots when its
#: ``[outputs] plot_metrics`` is not given and what a notebook's sweep table shows first.
HEADLINE_METRICS = (
    "final.all.rmse",
    "final.all.rmse_debiased",
    "final.all.relmse",
    "final.all.delta_e2000_mean",
    "final.all.flip_mean",
    "inscatter.all.rmse",
    "transmittance.all.rmse",
)


def metric_label(metric: str) -> str:
    """``metric`` with its unit in brackets (see the module's docstring)."""
    part, _, rest = metric.partition(".")
    name = rest.rsplit(".", 1)[-1]
    if name.startswith("delta_e2000"):
        unit = "ΔE2000"
    elif name.startswith("flip"):
        unit = "HDR-FLIP, 0..1"
    elif any(name.startswith(d) for d in DIMENSIONLESS) or part == "transmittance":
        unit = "1"
    else:
        unit = "radiance, scene units"
    return f"{metric} [{unit}]"


def parameter_label(name: str) -> str:
    """A swept parameter with its unit (a model parameter ``label.name`` by its ``name``)."""
    last = name.rsplit(".", 1)[-1]
    unit = PARAMETER_UNITS.get(name) or PARAMETER_UNITS.get(last)
    if not unit:
        units = {t.unit for m in TERMS.values() if (t := m.get(last)) is not None and t.unit}
        unit = units.pop() if len(units) == 1 else None
    return f"{name} [{unit}]" if unit else f"{name} (as in SWEEP.toml)"


def is_perceptual(metric: str) -> bool:
    """Whether ``metric`` (``<part>.<region>.<name>`` or a bare name) is a perceptual one.

    >>> is_perceptual("final.all.flip_mean"), is_perceptual("final.all.rmse")
    (True, False)
    """
    return metric.rsplit(".", 1)[-1].startswith(PERCEPTUAL)
