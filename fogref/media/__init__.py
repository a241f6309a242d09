"""Physics of fog media: density profiles and their closed forms (no Mitsuba)."""

from fogref.media.closed_form import TAU_MAX, hg_phase, phi, psi
from fogref.media.medium import Box, ExpLayer, FogMedium
from fogref.media.ops import NP, drjit_ops
from fogref.media.profiles import HDRPLayer, PowerLawLayer
from fogref.media.single_scatter import single_scatter_sun

__all__ = ["TAU_MAX", "NP", "Box", "ExpLayer", "FogMedium", "HDRPLayer", "PowerLawLayer", "drjit_ops", "hg_phase",
           "phi", "psi", "single_scatter_sun"]
