"""Game-engine fog models, one module each (numpy only, no Mitsuba).

==============  =============================================  ==========================
registry name   class                                          source
==============  =============================================  ==========================
``ue4``         :class:`~fogref.models.ue4.UE4ExponentialHeightFog`   HeightFogCommon.ush (seeds 000, 002)
``unity``       :class:`~fogref.models.unity_builtin.UnityBuiltinFog`  UnityCG.cginc (seed 003)
``altitude``    :class:`~fogref.models.altitude.AltitudeFog`           seed 001
``box``         :class:`~fogref.models.box.BoxFog`                     seed 004
``hdrp``        :class:`~fogref.models.hdrp.HDRPFog`                   HDRP AtmosphericScattering.hlsl
``filament``    :class:`~fogref.models.filament.FilamentFog`           Filament fog.fs
==============  =============================================  ==========================

Every model: ``Model(params).evaluate(camera (3,), world_pos (..., 3),
precision="float32" | "float64") -> FogResult`` in fogref's y-up metre frame.
"""

from fogref.models import altitude, box, filament, hdrp, ue4, unity_builtin  # noqa: F401  (registration)
from fogref.models.altitude import AltitudeFog, AltitudeFogParams
from fogref.models.base import FogResult, as_points, available, get, register
from fogref.models.box import BoxFog, BoxFogParams
from fogref.models.filament import FilamentFog, FilamentFogParams
from fogref.models.hdrp import HDRPFog, HDRPFogParams
from fogref.models.ue4 import (
           SecondFogData,
           UE4ExponentialHeightFog,
           UE4FogParams,
           medium_to_ue4,
           ue4_to_medium,
)
from fogref.models.unity_builtin import UnityBuiltinFog, UnityFogParams

__all__ = ["FogResult", "as_points", "available", "get", "register",
           "AltitudeFog", "AltitudeFogParams", "BoxFog", "BoxFogParams",
           "FilamentFog", "FilamentFogParams", "HDRPFog", "HDRPFogParams",
           "SecondFogData", "UE4ExponentialHeightFog", "UE4FogParams", "medium_to_ue4", "ue4_to_medium",
           "UnityBuiltinFog", "UnityFogParams"]
