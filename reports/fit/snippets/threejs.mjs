// fogref export --engine threejs: the threejs fit at sun elevation 8 deg in reports/fit/engines.json
// fogref's units: radiance 1 = 1 cd/m^2, irradiance 1 = 1 lux; exposure 1.
// three.js r155+ (y-up, right-handed, metres, like fogref; the camera looks along -Z).
// Colours: setRGB(..., THREE.LinearSRGBColorSpace) takes linear values (a hex would be sRGB).
// The light's colour x intensity is fogref's sun irradiance; no tone mapping, exposure 1.
import * as THREE from 'three';

export function applyFogref(scene) {
  const fogColor = new THREE.Color().setRGB(0.152118391, 0.188222197, 0.262532724, THREE.LinearSRGBColorSpace);
  scene.fog = new THREE.FogExp2(fogColor, 0.00259463727);

  const sun = new THREE.DirectionalLight(new THREE.Color().setRGB(1.0, 0.90625, 0.75, THREE.LinearSRGBColorSpace), 3.2);
  sun.position.set(399.95816, 139.173101, 905.905248);  // toward the sun; the target stays at the origin
  scene.add(sun);
  scene.add(sun.target);

  const camera = new THREE.PerspectiveCamera(42.9956614, 1.77777778, 0.1, 20000.0);
  camera.position.set(0.0, 2.0, 0.0);
  camera.up.set(0.0, 1.0, 0.0);
  camera.lookAt(0.15, 2.35, 1.0);
  return { camera, sun };
}
