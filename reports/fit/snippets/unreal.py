# fogref export --engine unreal: the ue4 fit at sun elevation 8 deg in reports/fit/engines.json
# fogref's units: radiance 1 = 1 cd/m^2, irradiance 1 = 1 lux; exposure 1.
# Run in the Unreal Editor (Python Editor Script Plugin): Tools > Execute Python Script.
# Unreal is z-up, left-handed, cm: (x, y, z)_ue = 100 (x, z, y)_fogref.
# Colours: FLinearColor values are linear (as the details panel shows them); the light's
# FColor is sRGB.  DirectionalInscatteringColor is the fit's, divided by the sun light's
# luminance 2.93304 (Unreal multiplies it back on the CPU).
# UE 5.1+ names the colours ...Luminance: set_first() takes either name.

import unreal


def set_first(obj, names, value, required=True):
    """Set the first of ``names`` that ``obj`` has (property names differ between versions)."""
    for name in names:
        try:
            obj.set_editor_property(name, value)
            return name
        except Exception:
            pass
    if required:
        raise RuntimeError(f"{obj.get_name()} has none of {names}")
    return None


try:  # UE 5
    spawn = unreal.get_editor_subsystem(unreal.EditorActorSubsystem).spawn_actor_from_class
except AttributeError:  # UE 4.26-4.27
    spawn = unreal.EditorLevelLibrary.spawn_actor_from_class

fog_actor = spawn(
    unreal.ExponentialHeightFog, unreal.Vector(0.0, 0.0, 0.0)
)
fog = fog_actor.get_component_by_class(unreal.ExponentialHeightFogComponent)
set_first(fog, ["fog_density"], 0.0237336704)
set_first(fog, ["fog_height_falloff"], 0.169358862)
set_first(fog, ["fog_max_opacity"], 1.0)
set_first(fog, ["start_distance"], 0.0)
set_first(fog, ["fog_cutoff_distance"], 0.0)
set_first(fog, ["directional_inscattering_exponent"], 12.2281926)
set_first(fog, ["directional_inscattering_start_distance"], 8.22242976e-44)
set_first(fog, ['fog_inscattering_color', 'fog_inscattering_luminance'], unreal.LinearColor(0.211289948, 0.294623073, 0.462463632, 1.0))
set_first(fog, ['directional_inscattering_color', 'directional_inscattering_luminance'], unreal.LinearColor(0.417106913, 0.376000237, 0.306926892, 1.0))

# the sun: its X axis is the direction the light travels; intensity in lux
sun_actor = spawn(
    unreal.DirectionalLight, unreal.Vector(0.0, 0.0, 0.0), unreal.Rotator(roll=0.0, pitch=-8.0, yaw=-113.821511)
)
sun = sun_actor.get_component_by_class(unreal.DirectionalLightComponent)
sun.set_editor_property('intensity', 3.2)
sun.set_editor_property('light_color', unreal.Color(r=255, g=244, b=225, a=255))
set_first(sun, ['atmosphere_sun_light', 'used_as_atmosphere_sun_light'], True, required=False)

# the camera: horizontal field of view [deg]
camera_actor = spawn(
    unreal.CameraActor, unreal.Vector(0.0, 0.0, 200.0), unreal.Rotator(roll=7.1396776e-16, pitch=19.0921554, yaw=81.4692344)
)
camera = camera_actor.get_component_by_class(unreal.CameraComponent)
camera.set_editor_property('field_of_view', 70.0)
camera.set_editor_property('aspect_ratio', 1.77777778)
