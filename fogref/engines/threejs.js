// fogref's three.js page: renders one view of a fogref scene with the real three.js and returns
// its pixels (the page protocol of fogref/engines/__init__.py).  Loaded from file:// by
// fogref/engines/browser.py, with an import map that points "three" at node_modules/three.
import * as THREE from "three";
import { arrayToB64, b64ToArray, triangleCorners } from "./page_helpers.js";

function linear(rgb) {
  return new THREE.Color().setRGB(rgb[0], rgb[1], rgb[2], THREE.LinearSRGBColorSpace);
}

function buildScene(spec) {
  const scene = new THREE.Scene();
  for (const s of spec.shapes) {
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.BufferAttribute(b64ToArray(s.positions, Float32Array), 3));
    g.setIndex(new THREE.BufferAttribute(b64ToArray(s.indices, Uint32Array), 1));
    if (s.normals) g.setAttribute("normal", new THREE.BufferAttribute(b64ToArray(s.normals, Float32Array), 3));
    else g.computeVertexNormals();
    const m = new THREE.MeshLambertMaterial({ color: linear(s.reflectance), side: THREE.DoubleSide });
    scene.add(new THREE.Mesh(g, m));
  }
  const c = spec.camera;
  if (spec.sun) {
    // irradiance E on a plane facing the sun: three.js's direct diffuse is E cos / pi * albedo
    const sun = new THREE.DirectionalLight(linear(spec.sun.irradiance), 1.0);
    const w = spec.sun.direction;
    sun.position.set(c.origin[0] + w[0], c.origin[1] + w[1], c.origin[2] + w[2]);
    sun.target.position.set(c.origin[0], c.origin[1], c.origin[2]);
    scene.add(sun, sun.target);
  }
  if (spec.sky) {
    // a uniform sky of radiance L above the horizon: irradiance pi L (1 + n.y) / 2, three.js's hemisphere light
    const L = spec.sky;
    const sky = new THREE.HemisphereLight(linear([Math.PI * L[0], Math.PI * L[1], Math.PI * L[2]]), 0x000000, 1.0);
    sky.position.set(0, 1, 0);
    scene.add(sky);
  }
  return scene;
}

function buildCamera(spec) {
  const c = spec.camera;
  const cam = new THREE.PerspectiveCamera(c.fov_y_deg, spec.width / spec.height, c.near, c.far);
  const right = new THREE.Vector3(...c.right);
  const up = new THREE.Vector3(...c.up);
  const back = new THREE.Vector3(...c.forward).negate();
  cam.quaternion.setFromRotationMatrix(new THREE.Matrix4().makeBasis(right, up, back));
  cam.position.set(...c.origin);
  cam.updateMatrixWorld(true);
  return cam;
}

function makeFog(f, colour) {
  if (f.type === "FogExp2") return new THREE.FogExp2(linear(colour), f.density);
  if (f.type === "Fog") return new THREE.Fog(linear(colour), f.near, f.far);
  throw new Error("unknown fog type " + f.type);
}

// The depth pass.  G, B: the view position three.js interpolates across a triangle (as its fog's
// vFogDepth = -mvPosition.z is interpolated): eye depth and distance.  R: the distance along the
// camera ray through the pixel's centre (gl_FragCoord and the projection matrix) to the plane of
// the triangle's three corners (each fragment gets all three): the camera's own depth, free of the
// rasteriser's interpolation.  A: 1 where a surface was drawn.
const DISTANCE = new THREE.ShaderMaterial({
  uniforms: { size: { value: new THREE.Vector2(1, 1) } },
  vertexShader: `
    #include <common>
    #include <logdepthbuf_pars_vertex>
    attribute vec3 corner0;
    attribute vec3 corner1;
    attribute vec3 corner2;
    varying vec3 vView;
    varying vec3 vC0;
    varying vec3 vC1;
    varying vec3 vC2;
    void main() {
      vec4 mvPosition = modelViewMatrix * vec4( position, 1.0 );
      vView = mvPosition.xyz;
      vC0 = ( modelViewMatrix * vec4( corner0, 1.0 ) ).xyz;
      vC1 = ( modelViewMatrix * vec4( corner1, 1.0 ) ).xyz;
      vC2 = ( modelViewMatrix * vec4( corner2, 1.0 ) ).xyz;
      gl_Position = projectionMatrix * mvPosition;
      #include <logdepthbuf_vertex>
    }`,
  fragmentShader: `
    #include <logdepthbuf_pars_fragment>
    uniform vec2 size;
    uniform mat4 projectionMatrix;
    varying vec3 vView;
    varying vec3 vC0;
    varying vec3 vC1;
    varying vec3 vC2;
    void main() {
      #include <logdepthbuf_fragment>
      vec2 ndc = 2.0 * gl_FragCoord.xy / size - 1.0;
      vec3 ray = vec3( ( ndc.x + projectionMatrix[2][0] ) / projectionMatrix[0][0],
                       ( ndc.y + projectionMatrix[2][1] ) / projectionMatrix[1][1], -1.0 );
      vec3 n = cross( vC1 - vC0, vC2 - vC0 );
      float t = dot( n, vC0 ) / dot( n, ray );
      gl_FragColor = vec4( t * length( ray ), - vView.z, length( vView ), 1.0 );
    }`,
  side: THREE.DoubleSide,
});

// Each triangle on its own, every vertex carrying the triangle's three corners (for DISTANCE).
function cornerScene(scene) {
  const out = new THREE.Scene();
  scene.traverse((o) => {
    if (!o.isMesh) return;
    const g = o.geometry.toNonIndexed();
    const p = g.getAttribute("position").array;
    const c = triangleCorners(p);
    c.forEach((a, k) => g.setAttribute("corner" + k, new THREE.BufferAttribute(a, 3)));
    out.add(new THREE.Mesh(g, DISTANCE));
  });
  return out;
}

window.fogrefRender = function (spec) {
  const W = spec.width, H = spec.height;
  const canvas = document.createElement("canvas");
  canvas.width = W;
  canvas.height = H;
  const renderer = new THREE.WebGLRenderer({
    canvas, antialias: false, preserveDrawingBuffer: true, logarithmicDepthBuffer: true,
  });
  renderer.setPixelRatio(1);
  renderer.setSize(W, H, false);
  const scene = buildScene(spec);
  const camera = buildCamera(spec);
  const rt = new THREE.WebGLRenderTarget(W, H, { type: THREE.FloatType, samples: 0, depthBuffer: true });
  const sky = spec.sky ? linear(spec.sky) : new THREE.Color(0, 0, 0);
  const black = new THREE.MeshBasicMaterial({ color: 0x000000, side: THREE.DoubleSide });
  const fog = spec.fog ? makeFog(spec.fog, spec.fog.color) : null;

  function pass(background, fogObject, override) {
    scene.background = background;
    scene.fog = fogObject;
    scene.overrideMaterial = override;
    renderer.setRenderTarget(rt);
    renderer.setClearColor(0x000000, 0);
    renderer.clear();
    renderer.render(scene, camera);
    const px = new Float32Array(W * H * 4);
    renderer.readRenderTargetPixels(rt, 0, 0, W, H, px);
    return arrayToB64(px);
  }

  const out = { version: THREE.REVISION, target_type: "FloatType" };
  out.final = pass(sky, fog, null);
  out.surface = pass(sky, null, null);
  // the fog factor f with materials black: fog colour white gives f, the fog's own colour C f
  out.fog_factor = spec.fog ? pass(null, makeFog(spec.fog, [1, 1, 1]), black) : null;
  out.inscatter = spec.fog ? pass(null, fog, black) : null;
  DISTANCE.uniforms.size.value.set(W, H);
  const corners = cornerScene(scene);
  renderer.setRenderTarget(rt);
  renderer.setClearColor(0x000000, 0);
  renderer.render(corners, camera);
  const depth = new Float32Array(W * H * 4);
  renderer.readRenderTargetPixels(rt, 0, 0, W, H, depth);
  out.depth = arrayToB64(depth);
  // the canvas as three.js ships it: default output colour space (sRGB), tone mapping, 8 bits
  scene.background = sky;
  scene.fog = fog;
  scene.overrideMaterial = null;
  renderer.setRenderTarget(null);
  renderer.render(scene, camera);
  const gl = renderer.getContext();
  const bytes = new Uint8Array(W * H * 4);
  gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, bytes);
  out.canvas = arrayToB64(bytes);
  out.output_colour_space = renderer.outputColorSpace;
  out.tone_mapping = renderer.toneMapping === THREE.NoToneMapping ? "NoToneMapping" : String(renderer.toneMapping);
  out.renderer = gl.getParameter(gl.RENDERER);
  rt.dispose();
  renderer.dispose();
  return out;
};
document.body.setAttribute("data-ready", "1");
