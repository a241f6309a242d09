"""``fogpath_knobs``: fogpath with its sun samplers' settings as plugin parameters, for the
benchmarks that measure them (fogpath itself fixes them:
:meth:`fogref_plugins.fogpath.FogPathIntegrator._sun_sampler`).

* ``sun_sampling_layers`` (int in [1, 16], default 1): most layers for which the sun's exact
  sampler is used (more layers: the mixture);
* ``sun_sampling_mixture`` (bool, default true): the closed-form mixture where the exact
  sampler does not apply;
* ``sun_samples`` (int in [1, 64], default ``SUN_SAMPLES``, 2): stratified sun samples per
  camera ray;
* ``sun_guiding`` (float in [0, 0.95], default 0: fogpath's phase sampling): the share of a
  Henyey-Greenstein lobe around the direction toward the sun in the phase sample at medium
  vertices (:class:`SunGuidedPhase`);
* ``sun_guiding_g`` (float in [0, 0.99], default: the fog's ``g``, at least 0.5): that lobe's
  asymmetry.

Importing this module registers the plugin (after ``_common`` set the variant).
"""

from __future__ import annotations

import math

from _common import dr, mi
from fogref_plugins.fogpath import SUN_SAMPLES, FogPathIntegrator

from fogref import params
from fogref.errors import ParameterError
from fogref.media.single_scatter import sun_sampling_mode

SOURCE = "fogpath_knobs"


def hg_lobe_pdf(g: float, cos):
    """Henyey-Greenstein density [1/sr] of a direction at cosine ``cos`` (in [-1, 1]) from
    the lobe's axis, asymmetry ``g`` in [0, 1): ``(1 - g^2) / (4 pi (1 + g^2 - 2 g cos)^1.5)``
    (Henyey & Greenstein, ApJ 93, 1941), in [(1 - g) / (4 pi (1 + g)^2), (1 + g) / (4 pi (1 - g)^2)]."""
    return (1.0 - g * g) / (4.0 * math.pi) * dr.power(1.0 + g * g - 2.0 * g * cos, -1.5)


def hg_lobe_sample(g: float, axis, u):
    """A direction drawn from the Henyey-Greenstein lobe of asymmetry ``g`` in [0, 1) around the
    unit vector ``axis``, from ``u`` in [0, 1)^2 (the inverse CDF of the cosine, Pharr, Jakob &
    Humphreys, *Physically Based Rendering* 3rd ed., section 15.2.3; uniform on the sphere for
    ``g`` below 1e-3)."""
    if g < 1e-3:
        cos = 1.0 - 2.0 * u.x
    else:
        sq = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x)
        cos = dr.clip((1.0 + g * g - sq * sq) / (2.0 * g), -1.0, 1.0)
    sin = dr.safe_sqrt(1.0 - cos * cos)
    s, c = dr.sincos(2.0 * dr.pi * u.y)
    return mi.Frame3f(axis).to_world(mi.Vector3f(c * sin, s * sin, cos))


class SunGuidedPhase(mi.PhaseFunction):
    """The fog's phase function ``phase``, sampled from the one-sample mixture ``(1 - share)
    p_phase + share p_lobe``, ``p_lobe`` the Henyey-Greenstein lobe of asymmetry ``g`` around
    ``to_sun``.  ``sample`` returns the direction, ``f / p_mix`` and ``p_mix``; ``eval_pdf``
    returns ``(f, p_mix)``, so that next-event estimation's MIS weight uses the density the
    phase sample was drawn with (the balance heuristic of the mixture's two techniques inside,
    the power heuristic against light sampling outside; Veach 1997, ch. 9).  Unbiased for any
    ``share`` in [0, 1): ``p_mix > 0`` wherever ``f > 0``."""

    def __init__(self, phase, to_sun, g: float, share: float):
        super().__init__(mi.Properties())
        self.phase, self.to_sun, self.g, self.share = phase, to_sun, g, share

    def _pdf(self, ctx, mei, wo, active):
        f, p = self.phase.eval_pdf(ctx, mei, wo, active)
        lobe = hg_lobe_pdf(self.g, dr.dot(wo, self.to_sun))
        return f, (1.0 - self.share) * p + self.share * lobe

    def sample(self, ctx, mei, sample1, sample2, active=True):
        lobe = sample1 < self.share
        s1 = dr.select(lobe, sample1 / self.share, (sample1 - self.share) / (1.0 - self.share))
        wo_phase, _, _ = self.phase.sample(ctx, mei, s1, sample2, active)
        wo = dr.select(lobe, hg_lobe_sample(self.g, self.to_sun, sample2), wo_phase)
        f, pdf = self._pdf(ctx, mei, wo, active)
        return wo, dr.select(pdf > 0, f / pdf, 0.0), pdf

    def eval_pdf(self, ctx, mei, wo, active=True):
        return self._pdf(ctx, mei, wo, active)


class FogPathKnobs(FogPathIntegrator):
    """fogpath with ``sun_sampling_layers``, ``sun_sampling_mixture``, ``sun_samples``,
    ``sun_guiding`` and ``sun_guiding_g`` read from the plugin's parameters (checked by fogref's
    validator: one line naming the parameter and range)."""

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
        self.sun_guiding = params.number(
            props.get("sun_guiding", 0.0), "sun_guiding", source=SOURCE, lo=0.0, hi=0.95
        )
        g = props.get("sun_guiding_g", None)
        if g is not None:
            g = params.number(g, "sun_guiding_g", source=SOURCE, lo=0.0, hi=0.99)
        self.sun_guiding_g = g

    def _medium_vertex(self, tr, sampler, ray, p, t, med, sun_sampled):
        """fogpath's medium vertex, its phase function sampled by :class:`SunGuidedPhase` when
        ``sun_guiding`` is above 0 and the scene has a sun."""
        sun = self._scene_sun(tr.scene) if self.sun_guiding > 0 else None
        if sun is None:
            return super()._medium_vertex(tr, sampler, ray, p, t, med, sun_sampled)
        g = self.sun_guiding_g if self.sun_guiding_g is not None else max(float(tr.fog.g), 0.5)
        phase = tr.phase
        tr.phase = SunGuidedPhase(phase, mi.Vector3f(*tr.ops.params(sun[0])), g, self.sun_guiding)
        try:
            return super()._medium_vertex(tr, sampler, ray, p, t, med, sun_sampled)
        finally:
            tr.phase = phase

    def _sun_sampler(self, fog, w_sun):
        mode = sun_sampling_mode(fog, w_sun, self.sun_sampling_layers, self.sun_sampling_mixture)
        return mode, self.sun_samples


mi.register_integrator("fogpath_knobs", lambda props: FogPathKnobs(props))
