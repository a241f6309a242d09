"""The physical mapping: from one physical scene to each game fog model, and the fits.

Layering: ``fogref.media`` (physics) <- ``fogref.models`` (pure shader ports) <-
``fogref.mapping`` (this package) <- ``fogref.compare``, ``fogref.study``.

* :mod:`~fogref.mapping.physical`  :class:`PhysicalScene`: fog, sun, sky, camera, and its one
  parser (:meth:`PhysicalScene.from_params`, an EXR's ``fogref.params``)
* :mod:`~fogref.mapping.registry`  :func:`from_physical` and the mapping registry
* :mod:`~fogref.mapping.unreal`    Unreal's colour/lobe fit (:func:`fit_unreal`) and its mapping
  (:func:`ue4_from_physical`; the other way is :func:`fogref.models.ue4.ue4_to_medium`)
* :mod:`~fogref.mapping.unreal_basis`  Unreal's inscatter, linear in its two colours, and the colour solve
* :mod:`~fogref.mapping.views`     sample views from the camera and the physical single scattering on them
* :mod:`~fogref.mapping.lobe`      the best cosine lobe for an HG phase (:func:`lobe_fit`, :func:`lobe_table`)
* :mod:`~fogref.mapping.engines`   other engines' mappings, both ways (``X_from_physical``, ``X_to_medium``)
* :mod:`~fogref.mapping.free`      each model's free parameters and bounds (:data:`FIT_SPECS`)
* :mod:`~fogref.mapping.fit`       any model fitted to the physical fog, with uncertainties
* :mod:`~fogref.mapping.translate` one engine's settings to another's through the physical fog
* :mod:`~fogref.mapping.droplet_fog` visibility and droplets -> heightfog parameters (Mie phase)

Examples
--------
>>> import fogref.mapping as fm
>>> ps = fm.PhysicalScene.from_params({"medium": {"profile": "homogeneous", "sigma_t": 0.01}})
>>> type(fm.from_physical("ue4", ps)).__name__
'UE4ExponentialHeightFog'
"""

from fogref.mapping import engines  # noqa: F401  (registers the non-Unreal mappings)
from fogref.mapping.fit import ModelFit, fit_model
from fogref.mapping.free import FIT_SPECS
from fogref.mapping.lobe import lobe_fit, lobe_table
from fogref.mapping.physical import PhysicalScene
from fogref.mapping.registry import MAPPINGS, from_physical, has_mapping, register_mapping
from fogref.mapping.translate import Translation, translate
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
    "FIT_SPECS",
    "MAPPINGS",
    "SKY_DISTANCE",
    "FitResult",
    "ModelFit",
    "Translation",
    "fit_model",
    "translate",
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
