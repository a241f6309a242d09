"""``fogpath_knobs``: fogpath with its sun samplers' settings as plugin parameters, for the
benchmarks that measure them (fogpath itself fixes them:
:meth:`fogref_plugins.fogpath.FogPathIntegrator._sun_sampler`).

* ``sun_sampling_layers`` (int in [1, 16], default 1): most layers for which the sun's exact
  sampler is used (more layers: the mixture);
* ``sun_sampling_mixture`` (bool, default true): the closed-form mixture where the exact
  sampler does not apply;
* ``sun_samples`` (int in [1, 64], default ``SUN_SAMPLES``, 2): stratified sun samples per
  camera ray.

Importing this module registers the plugin (after ``_common`` set the variant).
"""

from __future__ import annotations

from _common import mi
from fogref_plugins.fogpath import SUN_SAMPLES, FogPathIntegrator

from fogref import params
from fogref.errors import ParameterError
from fogref.media.single_scatter import sun_sampling_mode

SOURCE = "fogpath_knobs"


class FogPathKnobs(FogPathIntegrator):
    """fogpath with ``sun_sampling_layers``, ``sun_sampling_mixture`` and ``sun_samples`` read from
    the plugin's parameters (checked by fogref's validator: one line naming the parameter and range)."""

    def __init__(self, props):
        super().__init__(props)
        layers = props.get("sun_sampling_layers", 1)
        self.sun_sampling_layers = params.integer(layers, "sun_sampling_layers", source=SOURCE, lo=1, hi=16)
        mixture = props.get("sun_sampling_mixture", True)
        if not isinstance(mixture, bool):
            raise ParameterError(SOURCE, "sun_sampling_mixture", f"expected true or false, got {mixture!r}")
        self.sun_sampling_mixture = mixture
        self.sun_samples = params.integer(
            props.get("sun_samples", SUN_SAMPLES), "sun_samples", source=SOURCE, lo=1, hi=64
        )

    def _sun_sampler(self, fog, w_sun):
        mode = sun_sampling_mode(fog, w_sun, self.sun_sampling_layers, self.sun_sampling_mixture)
        return mode, self.sun_samples


mi.register_integrator("fogpath_knobs", lambda props: FogPathKnobs(props))
