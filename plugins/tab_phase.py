"""Mitsuba phase plugin ``fogtabphase``: a phase function tabulated at irregular cosines.

Mitsuba 3.9.1 ships ``tabphase``, whose table is regular in ``cos theta``: a water
droplet's diffraction peak (about 1/x rad wide, x = 2 pi r / lambda, in the hundreds for
fog) would need some 1e5 nodes there.  This plugin takes the nodes where they are needed
(:func:`fogref.media.phase.phase_cosines`: 915 for fog) and is otherwise the same model:
the phase is linear in ``cos theta`` between the nodes, normalised over the sphere, and
sampled exactly by inverting its piecewise-quadratic CDF (Mitsuba's
``IrregularContinuousDistribution``), so ``eval`` and ``sample`` agree to rounding.  Its
density is :class:`fogref.media.phase.TabulatedPhase`'s, which fogref's closed forms use.

.. pluginparameters::

 * - cosines
   - string
   - Comma-separated cosines of the scattering angle, strictly increasing from -1 to 1
     (1: forward scattering).
 * - values
   - string
   - Comma-separated phase values at those cosines (>= 0; normalised here).
 * - label
   - string
   - The phase's name in reports (e.g. ``mie radiation``). Default: ``tabulated``.

Convention: ``cos theta = dot(wo, -wi)`` (``wi`` points back along the incoming ray, as
in Mitsuba's ``hg``), so the forward direction continues the ray.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from fogref.errors import ParameterError
from fogref.media.phase import TabulatedPhase


def _floats(props, name: str, src: str) -> tuple:
    if name not in props:
        raise ParameterError(src, name, "required (comma-separated numbers)")
    try:
        return tuple(float(x) for x in str(props[name]).replace(",", " ").split())
    except ValueError:
        raise ParameterError(src, name, "must be comma-separated numbers") from None


class TabulatedPhaseFunction(mi.PhaseFunction):
    """``fogtabphase`` (see module); ``self.table`` is the physics."""

    def __init__(self, props):
        mi.PhaseFunction.__init__(self, props)
        src = f"fogtabphase '{props.id()}'" if props.id() else "fogtabphase"
        label = str(props["label"]) if "label" in props else "tabulated"
        self.table = TabulatedPhase(
            _floats(props, "cosines", src), _floats(props, "values", src), label=label, source=src
        )
        self.distr = mi.IrregularContinuousDistribution(
            mi.Float(self.table.cosines), mi.Float(self.table.values)
        )
        self.m_flags = mi.PhaseFunctionFlags.Anisotropic

    def _value(self, cos_theta, active):
        return self.distr.eval_pdf_normalized(dr.clip(cos_theta, -1.0, 1.0), active) * dr.inv_two_pi

    def sample(self, ctx, mei, sample1, sample2, active=True):
        cos_theta = dr.clip(self.distr.sample(sample1, active), -1.0, 1.0)
        sin_theta = dr.safe_sqrt(1.0 - cos_theta * cos_theta)
        s, c = dr.sincos(dr.two_pi * sample2.x)
        wo = mi.Frame3f(-mei.wi).to_world(mi.Vector3f(c * sin_theta, s * sin_theta, cos_theta))
        pdf = self._value(cos_theta, active)
        return wo, mi.Spectrum(dr.select(pdf > 0, 1.0, 0.0)), pdf

    def eval_pdf(self, ctx, mei, wo, active=True):
        pdf = self._value(dr.dot(wo, -mei.wi), active)
        return mi.Spectrum(pdf), pdf

    def to_string(self):
        return f"TabulatedPhaseFunction[{self.table.label}, {len(self.table.cosines)} nodes]"


def register() -> None:
    mi.register_phase("fogtabphase", lambda props: TabulatedPhaseFunction(props))


__all__ = ["TabulatedPhaseFunction", "register"]
