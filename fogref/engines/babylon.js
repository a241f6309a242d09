// fogref's Babylon.js page: renders one view of a fogref scene with the real Babylon.js and returns
// its pixels (the page protocol of fogref/engines/__init__.py).  Loaded from file:// by
// fogref/engines/browser.py, with an import map that points "@babylonjs/core/" at the package's
// folder in node_modules.  It imports the modules it uses (the side-effect versions, not the
// ".pure" ones, so that each registers what it adds to Engine and Scene), not the package's index,
// which loads all of its 3,400 modules: 3 s in Chromium from file://, against 0.3 s.
import { Engine } from "@babylonjs/core/Engines/engine.js";
import { Constants } from "@babylonjs/core/Engines/constants.js";
import { Scene } from "@babylonjs/core/scene.js";
import { Color3, Color4 } from "@babylonjs/core/Maths/math.color.js";
import { Vector2, Vector3 } from "@babylonjs/core/Maths/math.vector.js";
import { FreeCamera } from "@babylonjs/core/Cameras/freeCamera.js";
import { DirectionalLight } from "@babylonjs/core/Lights/directionalLight.js";
import { HemisphericLight } from "@babylonjs/core/Lights/hemisphericLight.js";
import { Effect } from "@babylonjs/core/Materials/effect.js";
import { ShaderMaterial } from "@babylonjs/core/Materials/shaderMaterial.js";
import { StandardMaterial } from "@babylonjs/core/Materials/standardMaterial.js";
import { RenderTargetTexture } from "@babylonjs/core/Materials/Textures/renderTargetTexture.js";
import { VertexBuffer } from "@babylonjs/core/Meshes/buffer.js";
import { Mesh } from "@babylonjs/core/Meshes/mesh.js";
import { VertexData } from "@babylonjs/core/Meshes/mesh.vertexData.js";
import { arrayToB64, b64ToArray, triangleCorners, unindexed } from "./page_helpers.js";

const MODES = { LINEAR: Scene.FOGMODE_LINEAR, EXP: Scene.FOGMODE_EXP, EXP2: Scene.FOGMODE_EXP2 };

// The depth pass (as threejs.js's).  G, B: the view position Babylon interpolates across a triangle
// (as its fog's vFogDistance = (view * worldPos).xyz is interpolated): eye depth and distance.
// R: the distance along the camera ray through the pixel's centre to the plane of the triangle's
// three corners (each vertex carries all three).  A: 1 where a surface was drawn.
Effect.ShadersStore.fogrefDepthVertexShader = `
  precision highp float;
  attribute vec3 position;
  attribute vec3 corner0;
  attribute vec3 corner1;
  attribute vec3 corner2;
  uniform mat4 view;
  uniform mat4 projection;
  varying vec3 vView;
  varying vec3 vC0;
  varying vec3 vC1;
  varying vec3 vC2;
  void main() {
    vec4 p = view * vec4(position, 1.0);
    vView = p.xyz;
    vC0 = (view * vec4(corner0, 1.0)).xyz;
    vC1 = (view * vec4(corner1, 1.0)).xyz;
    vC2 = (view * vec4(corner2, 1.0)).xyz;
    gl_Position = projection * p;
  }`;
Effect.ShadersStore.fogrefDepthFragmentShader = `
  precision highp float;
  uniform vec2 size;
  uniform mat4 projection;
  varying vec3 vView;
  varying vec3 vC0;
  varying vec3 vC1;
  varying vec3 vC2;
  void main() {
    vec2 ndc = 2.0 * gl_FragCoord.xy / size - 1.0;
    vec3 ray = vec3((ndc.x + projection[2][0]) / projection[0][0],
                    (ndc.y + projection[2][1]) / projection[1][1], -1.0);
    vec3 n = cross(vC1 - vC0, vC2 - vC0);
    float t = dot(n, vC0) / dot(n, ray);
    gl_FragColor = vec4(t * length(ray), -vView.z, length(vView), 1.0);
  }`;

function colour(rgb) { return new Color3(rgb[0], rgb[1], rgb[2]); }

function lambert(scene, name, rgb) {
  const m = new StandardMaterial(name, scene);
  m.diffuseColor = colour(rgb);
  m.specularColor = new Color3(0, 0, 0);
  m.emissiveColor = new Color3(0, 0, 0);
  m.ambientColor = new Color3(0, 0, 0);
  m.backFaceCulling = false;
  return m;
}

async function ready(scene, rt) {
  await scene.whenReadyAsync();
  await new Promise((ok) => { const t = () => (rt.isReadyForRendering() ? ok() : setTimeout(t, 5)); t(); });
}

window.fogrefRender = async function (spec) {
  const W = spec.width, H = spec.height;
  const canvas = document.createElement("canvas");
  canvas.width = W;
  canvas.height = H;
  const engine = new Engine(canvas, false, { preserveDrawingBuffer: true, antialias: false }, false);
  engine.setHardwareScalingLevel(1);
  const scene = new Scene(engine);
  scene.useRightHandedSystem = true;
  scene.ambientColor = new Color3(0, 0, 0);
  const c = spec.camera;
  const camera = new FreeCamera("camera", new Vector3(...c.origin), scene);
  camera.upVector = new Vector3(...c.up);
  camera.setTarget(new Vector3(c.origin[0] + c.forward[0], c.origin[1] + c.forward[1],
                               c.origin[2] + c.forward[2]));
  camera.fov = c.fov_y_deg * Math.PI / 180;  // vertical (FOVMODE_VERTICAL_FIXED, the default)
  camera.minZ = c.near;
  camera.maxZ = c.far;
  scene.activeCamera = camera;

  const meshes = [], corners = [], materials = [];
  spec.shapes.forEach((s, i) => {
    const positions = b64ToArray(s.positions, Float32Array);
    const indices = b64ToArray(s.indices, Uint32Array);
    const mesh = new Mesh(`shape${i}`, scene);
    const vd = new VertexData();
    vd.positions = positions;
    vd.indices = indices;
    if (s.normals) vd.normals = b64ToArray(s.normals, Float32Array);
    else { vd.normals = []; VertexData.ComputeNormals(positions, indices, vd.normals); }
    vd.applyToMesh(mesh);
    const m = lambert(scene, `mat${i}`, s.reflectance);
    mesh.material = m;
    materials.push(m);
    meshes.push(mesh);
    // each triangle on its own, every vertex carrying the triangle's three corners (the depth pass)
    const n = indices.length;
    const p = unindexed(positions, indices);
    const cs = triangleCorners(p);
    const cm = new Mesh(`corners${i}`, scene);
    cm.setVerticesData(VertexBuffer.PositionKind, p, false, 3);
    cs.forEach((a, k) => cm.setVerticesData(`corner${k}`, a, false, 3));
    cm.setIndices(Array.from({ length: n }, (_, k) => k));
    cm.setEnabled(false);
    corners.push(cm);
  });
  if (spec.sun) {
    // irradiance E on a plane facing the sun: Babylon's diffuse is max(n.l, 0) * light colour * albedo
    const w = spec.sun.direction;
    const sun = new DirectionalLight("sun", new Vector3(-w[0], -w[1], -w[2]), scene);
    sun.diffuse = colour(spec.sun.irradiance.map((e) => e / Math.PI));
    sun.specular = new Color3(0, 0, 0);
    sun.intensity = 1.0;
  }
  if (spec.sky) {
    // a uniform sky of radiance L above the horizon: albedo L (1 + n.y) / 2, a hemispheric light
    const sky = new HemisphericLight("sky", new Vector3(0, 1, 0), scene);
    sky.diffuse = colour(spec.sky);
    sky.groundColor = new Color3(0, 0, 0);
    sky.specular = new Color3(0, 0, 0);
    sky.intensity = 1.0;
  }
  const skyColour = spec.sky ? new Color4(...spec.sky, 1.0) : new Color4(0, 0, 0, 1.0);
  const black = new Color4(0, 0, 0, 1.0);
  const blackMaterial = lambert(scene, "black", [0, 0, 0]);
  blackMaterial.disableLighting = true;
  const depthMaterial = new ShaderMaterial("depth", scene, { vertex: "fogrefDepth", fragment: "fogrefDepth" },
    { attributes: ["position", "corner0", "corner1", "corner2"], uniforms: ["view", "projection", "size"] });
  depthMaterial.backFaceCulling = false;
  depthMaterial.setVector2("size", new Vector2(W, H));
  corners.forEach((m) => { m.material = depthMaterial; });

  const rt = new RenderTargetTexture("rt", { width: W, height: H }, scene, false, true,
    Constants.TEXTURETYPE_FLOAT, false, Constants.TEXTURE_NEAREST_SAMPLINGMODE, true);
  rt.activeCamera = camera;

  function setFog(f, rgb) {
    if (!f) { scene.fogMode = Scene.FOGMODE_NONE; return; }
    scene.fogMode = MODES[f.mode];
    scene.fogColor = colour(rgb);
    scene.fogDensity = f.density;
    scene.fogStart = f.start;
    scene.fogEnd = f.end;
  }

  async function pass(clear, fog, fogColour, material, list) {
    setFog(fog, fogColour);
    meshes.forEach((m, i) => { m.material = material || materials[i]; });
    list.forEach((m) => m.setEnabled(true));
    rt.renderList = list;
    rt.clearColor = clear;
    await ready(scene, rt);
    rt.render();
    const px = await rt.readPixels();
    return arrayToB64(new Float32Array(px.buffer, px.byteOffset, W * H * 4));
  }

  const f = spec.fog;
  const out = { version: Engine.Version, target_type: "TEXTURETYPE_FLOAT" };
  out.final = await pass(skyColour, f, f && f.color, null, meshes);
  out.surface = await pass(skyColour, null, null, null, meshes);
  out.fog_factor = f ? await pass(black, f, [1, 1, 1], blackMaterial, meshes) : null;
  out.inscatter = f ? await pass(black, f, f.color, blackMaterial, meshes) : null;
  meshes.forEach((m) => m.setEnabled(false));
  out.depth = await pass(new Color4(0, 0, 0, 0), null, null, null, corners);
  corners.forEach((m) => m.setEnabled(false));
  meshes.forEach((m) => m.setEnabled(true));
  // the canvas as Babylon ships it: its default image processing, 8 bits
  setFog(f, f && f.color);
  meshes.forEach((m, i) => { m.material = materials[i]; });
  scene.clearColor = skyColour;
  await scene.whenReadyAsync();
  scene.render();
  out.canvas = arrayToB64(new Uint8Array(await engine.readPixels(0, 0, W, H, true, false)));
  const ip = scene.imageProcessingConfiguration;
  out.output_colour_space = "none (StandardMaterial writes its values unconverted)";
  out.tone_mapping = ip.toneMappingEnabled ? String(ip.toneMappingType) : "none";
  const gl = engine._gl;
  out.renderer = gl ? gl.getParameter(gl.RENDERER) : "";
  rt.dispose();
  engine.dispose();
  return out;
};
document.body.setAttribute("data-ready", "1");
