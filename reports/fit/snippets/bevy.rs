// fogref export --engine bevy: the bevy fit at sun elevation 8 deg in reports/fit/engines.json
// fogref's units: radiance 1 = 1 cd/m^2, irradiance 1 = 1 lux; exposure 1.
// Bevy 0.15+ (y-up, right-handed, metres, like fogref; -Z forward).  Colours: Color::linear_rgba.
// Exposure 1 (ev100 = -log2 1.2): the light's colour x illuminance is fogref's sun irradiance
// and directional_light_color is the fit's divided by it per channel (Bevy multiplies them).
// Add `.add_systems(Startup, spawn_fogref)` to your App.
use bevy::pbr::{DistanceFog, FogFalloff};
use bevy::prelude::*;
use bevy::render::camera::Exposure;

pub fn spawn_fogref(mut commands: Commands) {
    commands.spawn((
        Camera3d::default(),
        Projection::Perspective(PerspectiveProjection {
            fov: 0.750415856,
            near: 0.1,
            far: 20000.0,
            ..default()
        }),
        Transform::from_translation(Vec3::new(0.0, 2.0, 0.0))
            .looking_at(Vec3::new(0.15, 2.35, 1.0), Vec3::new(0.0, 1.0, 0.0)),
        Exposure { ev100: -0.263034406 },
        DistanceFog {
            color: Color::linear_rgba(0.102061964, 0.142585868, 0.224094462, 1.0),
            directional_light_color: Color::linear_rgba(0.202045006, 0.205763561, 0.215888452, 1.0),
            directional_light_exponent: 8.36158344,
            falloff: FogFalloff::Atmospheric { extinction: Vec3::new(8.41111335e-05, 8.41111335e-05, 8.41111335e-05), inscattering: Vec3::new(0.00206562536, 0.00209898263, 0.00213480954) },
        },
    ));
    commands.spawn((
        DirectionalLight {
            color: Color::linear_rgb(1.0, 0.90625, 0.75),
            illuminance: 3.2,
            ..default()
        },
        Transform::default().looking_to(Vec3::new(-0.39995816, -0.139173101, -0.905905248), Vec3::Y),
    ));
}
