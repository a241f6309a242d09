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
            color: Color::linear_rgba(0.0964907964, 0.13400782, 0.209361735, 1.0),
            directional_light_color: Color::linear_rgba(0.20376788, 0.207380378, 0.217729562, 1.0),
            directional_light_exponent: 8.67749008,
            falloff: FogFalloff::Atmospheric { extinction: Vec3::new(8.36077792e-05, 8.36077792e-05, 8.36077792e-05), inscattering: Vec3::new(0.00218913914, 0.00226905809, 0.0023656387) },
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
