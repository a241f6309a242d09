// fogref export --engine filament: the filament fit at sun elevation 8 deg in reports/fit/engines.json
// fogref's units: radiance 1 = 1 cd/m^2, irradiance 1 = 1 lux; exposure 1.
// Filament (y-up, right-handed, metres, like fogref).  Colours are linear (LinearColor).
// The fog's sun lobe is the SUN light's colour x intensity: the light is the fitted
// lightColorIntensity; the physical sun's luminance is 2.92768 lux (2.628 x this light).
export function applyFogref(Filament, engine, scene, view, camera) {
  view.setFogOptions({
    enabled: true,
    distance: 0.0,
    cutOffDistance: Infinity,
    maximumOpacity: 1.0,
    height: 0.0,
    heightFalloff: 0.0117390613,
    color: [0.211289948, 0.294623073, 0.462463632],
    density: 0.00114029132,
    inScatteringStart: 1.01482982e-44,
    inScatteringSize: 12.2281925,
    fogColorFromIbl: false,
  });
  const sun = Filament.EntityManager.get().create();
  Filament.LightManager.Builder(Filament.LightManager$Type.SUN)
    .color([1.0, 0.901448107, 0.735847051])
    .intensity(1.22338957)
    .direction([-0.39995816, -0.139173101, -0.905905248])
    .build(engine, sun);
  scene.addEntity(sun);
  camera.lookAt([0.0, 2.0, 0.0], [0.15, 2.35, 1.0], [-0.0485204591, 0.944993704, -0.323469728]);
  camera.setProjectionFov(42.9956614, 1.77777778, 0.1, 20000.0, Filament.Camera$Fov.VERTICAL);
  camera.setExposureDirect(1.0);
  return sun;
}
