"""Game-engine fog models, one module each (numpy only, no Mitsuba).

==============  =============================================  ==========================
registry name   class                                          source
==============  =============================================  ==========================
``ue4``         :class:`~fogref.models.ue4.UE4ExponentialHeightFog`   HeightFogCommon.ush, FogRendering.cpp
``unity``       :class:`~fogref.models.unity_builtin.UnityBuiltinFog`  UnityCG.cginc
``altitude``    :class:`~fogref.models.altitude.AltitudeFog`           power-law altitude fog (Unity)
``box``         :class:`~fogref.models.box.BoxFog`                     box volume fog (Unity)
``hdrp``        :class:`~fogref.models.hdrp.HDRPFog`                   HDRP AtmosphericScattering.hlsl
``filament``    :class:`~fogref.models.filament.FilamentFog`           Filament fog.fs
``godot``       :class:`~fogref.models.godot.GodotFog`                 Godot scene_forward_clustered.glsl
``bevy``        :class:`~fogref.models.bevy.BevyDistanceFog`           Bevy fog.wgsl
``threejs``     :class:`~fogref.models.threejs.ThreeJSFog`             three.js fog_fragment.glsl.js
``babylon``     :class:`~fogref.models.babylon.BabylonFog`             Babylon.js fogFragmentDeclaration.fx
``playcanvas``  :class:`~fogref.models.playcanvas.PlayCanvasFog`       PlayCanvas fog chunk (fogPS)
``ue5_lfv``     :class:`~fogref.models.ue_local_fog_volume.UELocalFogVolume`  LocalFogVolumeCommon.ush
==============  =============================================  ==========================

Every model follows :class:`~fogref.models.base.FogModel`:
``Model(params).evaluate(camera (3,), positions (..., 3), precision="float32" |
"float64") -> FogResult`` in fogref's y-up metre frame.  Models depend on numpy
and :mod:`fogref.media` only; :mod:`fogref.mapping` builds them from a physical
scene (``fogref.mapping.from_physical("ue4", scene)``).

Names are resolved by one function, :func:`~fogref.models.resolve.resolve_model`
(also ``get``): a registry name, ``module.path:Class`` or an entry point of the
group ``fogref.models``; an unknown name gets a FogrefError with a "did you mean".
"""

from fogref.models import (  # noqa: F401  (registration)
    altitude,
    babylon,
    bevy,
    box,
    filament,
    godot,
    hdrp,
    playcanvas,
    threejs,
    ue4,
    ue_local_fog_volume,
    unity_builtin,
)
from fogref.models.altitude import AltitudeFog, AltitudeFogParams
from fogref.models.base import SKY_DISTANCE, FogModel, FogResult, as_points, register
from fogref.models.box import BoxFog, BoxFogParams
from fogref.models.filament import FilamentFog, FilamentFogParams
from fogref.models.hdrp import HDRPFog, HDRPFogParams
from fogref.models.resolve import available_models, get, resolve_model
from fogref.models.ue4 import SecondFogData, UE4ExponentialHeightFog, UE4FogParams
from fogref.models.unity_builtin import UnityBuiltinFog, UnityFogParams

__all__ = [
    "SKY_DISTANCE",
    "FogModel",
    "FogResult",
    "as_points",
    "available_models",
    "get",
    "register",
    "resolve_model",
    "AltitudeFog",
    "AltitudeFogParams",
    "BoxFog",
    "BoxFogParams",
    "FilamentFog",
    "FilamentFogParams",
    "HDRPFog",
    "HDRPFogParams",
    "SecondFogData",
    "UE4ExponentialHeightFog",
    "UE4FogParams",
    "UnityBuiltinFog",
    "UnityFogParams",
]
