"""Physics of fog media: density profiles and their closed forms (numpy and Dr.Jit, no Mitsuba).

* :mod:`~fogref.media.protocol`      the height-profile protocol, the profile registry, parameter parsers
* :mod:`~fogref.media.medium`        :class:`FogMedium`, :class:`ExpLayer` (exponential, homogeneous, box)
* :mod:`~fogref.media.profiles`      :class:`HDRPLayer`, :class:`PowerLawLayer`
* :mod:`~fogref.media.ue_pathtracer` :class:`UEPathTracerLayer`, :class:`Cylinder` (Unreal's path-traced fog)
* :mod:`~fogref.media.local_fog_volume` :class:`LocalFogVolume` (a sphere of fog, closed form)
* :mod:`~fogref.media.params`        :func:`medium_from_params` (the ``heightfog`` XML parameters)
* :mod:`~fogref.media.closed_form`   optical depth, free flight, ``phi``/``psi``, HG phase
* :mod:`~fogref.media.single_scatter` single scattering of the sun and the sky, closed form and sampled
* :mod:`~fogref.media.phase`         tabulated, Draine and approximate-Mie phase functions
* :mod:`~fogref.media.visibility`    visibility (meteorological optical range) <-> extinction
* :mod:`~fogref.media.droplets`      fog droplet size distributions (gamma; radiation, advection fog)
* :mod:`~fogref.media.mie`           the droplets' Mie optics per RGB channel (miepython)
"""

from fogref.media.closed_form import TAU_MAX, hg_phase, phi, psi
from fogref.media.local_fog_volume import LocalFogVolume
from fogref.media.medium import Box, ExpLayer, FogMedium
from fogref.media.ops import NP, drjit_ops
from fogref.media.params import medium_from_params
from fogref.media.profiles import HDRPLayer, PowerLawLayer
from fogref.media.protocol import PROFILES, HeightProfile, register_profile, rgb
from fogref.media.single_scatter import single_scatter_sun
from fogref.media.ue_pathtracer import Cylinder, UEPathTracerLayer

__all__ = [
    "TAU_MAX",
    "NP",
    "PROFILES",
    "Box",
    "Cylinder",
    "ExpLayer",
    "FogMedium",
    "HDRPLayer",
    "HeightProfile",
    "LocalFogVolume",
    "PowerLawLayer",
    "drjit_ops",
    "hg_phase",
    "medium_from_params",
    "phi",
    "psi",
    "register_profile",
    "rgb",
    "single_scatter_sun",
    "UEPathTracerLayer",
]
