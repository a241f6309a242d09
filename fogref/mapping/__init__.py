"""The physical mapping: from one physical scene to each game fog model, and the fits.

Layering: ``fogref.media`` (physics) <- ``fogref.models`` (pure shader ports) <-
``fogref.mapping`` (this package) <- ``fogref.compare``, ``fogref.study``.

* :mod:`~fogref.mapping.physical`  :class:`PhysicalScene`: fog, sun, sky, camera, and its one
  parser (:meth:`PhysicalScene.from_params`, an EXR's ``fogref.params``)
* :mod:`~fogref.mapping.registry`  :func:`from_physical` and the mapping registry
* :mod:`~fogref.mapping.unreal`    Unreal's colour/lobe fit (:func:`fit_unreal`) and its mapping
* :mod:`~fogref.mapping.unreal_basis`  Unreal's inscatter, linear in its two colours, and the colour solve
* :mod:`~fogref.mapping.views`     sample views from the camera and the physical single scattering on them
* :mod:`~fogref.mapping.lobe`      the best cosine lobe for an HG phase (:func:`lobe_fit`, :func:`lobe_table`)
* :mod:`~fogref.mapping.engines`   Unity, altitude, box, HDRP and Filament mappings

Examples
--------
>>> import fogref.mapping as fm
>>> ps = fm.PhysicalScene.from_params({"medium": {"profile": "homogeneous", "sigma_t": 0.01}})
>>> type(fm.from_physical("ue4", ps)).__name__
'UE4ExponentialHeightFog'
"""

from fogref.mapping import engines  # noqa: F401  (registers the non-Unreal mappings)
from fogref.mapping.lobe import lobe_fit, lobe_table
from fogref.mapping.physical import PhysicalScene
from fogref.mapping.registry import MAPPINGS, from_physical, has_mapping, register_mapping
from fogref.mapping.unreal import (
    FIT_DIRECTIONS_MAX,
    FIT_DIRECTIONS_START,
    FIT_RTOL,
    FitResult,
    Views,
    base_params,
    fit_unreal,
    physical_single_scattering,
    sample_views,
    ue4_from_physical,
    unreal_inscatter,
)
from fogref.models.base import SKY_DISTANCE

__all__ = [
    "FIT_DIRECTIONS_MAX",
    "FIT_DIRECTIONS_START",
    "FIT_RTOL",
    "MAPPINGS",
    "SKY_DISTANCE",
    "FitResult",
    "PhysicalScene",
    "Views",
    "base_params",
    "fit_unreal",
    "from_physical",
    "has_mapping",
    "lobe_fit",
    "lobe_table",
    "physical_single_scattering",
    "register_mapping",
    "sample_views",
    "ue4_from_physical",
    "unreal_inscatter",
]
