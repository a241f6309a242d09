// fogref's PlayCanvas page: renders one view of a fogref scene with the real PlayCanvas engine and
// returns its pixels (the page protocol of fogref/engines/__init__.py).  Loaded from file:// by
// fogref/engines/browser.py, with an import map that points "playcanvas" at node_modules.
// PlayCanvas takes material, light, ambient and fog colours gamma-encoded (it raises them to 2.2
// on the CPU): the page hands it c^(1/2.2) for a linear c.
import * as pc from "playcanvas";
import { arrayToB64, b64ToArray, triangleCorners, unindexed } from "./page_helpers.js";

function gamma(c) { return new pc.Color(...c.map((x) => Math.pow(x, 1 / 2.2))); }

// The depth pass (as threejs.js's): R the camera's ray-plane distance through the pixel centre,
// G, B the interpolated view position's eye depth and distance, A 1 where a surface was drawn.
const DEPTH_VS = `
  attribute vec3 vertex_position;
  attribute vec3 corner0;
  attribute vec3 corner1;
  attribute vec3 corner2;
  uniform mat4 matrix_view;
  uniform mat4 matrix_projection;
  varying vec3 vView;
  varying vec3 vC0;
  varying vec3 vC1;
  varying vec3 vC2;
  void main(void) {
    vec4 p = matrix_view * vec4(vertex_position, 1.0);
    vView = p.xyz;
    vC0 = (matrix_view * vec4(corner0, 1.0)).xyz;
    vC1 = (matrix_view * vec4(corner1, 1.0)).xyz;
    vC2 = (matrix_view * vec4(corner2, 1.0)).xyz;
    gl_Position = matrix_projection * p;
  }`;
const DEPTH_FS = `
  precision highp float;
  uniform vec2 size;
  uniform mat4 matrix_projection;
  varying vec3 vView;
  varying vec3 vC0;
  varying vec3 vC1;
  varying vec3 vC2;
  void main(void) {
    vec2 ndc = 2.0 * gl_FragCoord.xy / size - 1.0;
    vec3 ray = vec3((ndc.x + matrix_projection[2][0]) / matrix_projection[0][0],
                    (ndc.y + matrix_projection[2][1]) / matrix_projection[1][1], -1.0);
    vec3 n = cross(vC1 - vC0, vC2 - vC0);
    float t = dot(n, vC0) / dot(n, ray);
    gl_FragColor = vec4(t * length(ray), -vView.z, length(vView), 1.0);
  }`;

function material(rgb, lit) {
  const m = new pc.StandardMaterial();
  m.diffuse = gamma(rgb);
  m.specular = new pc.Color(0, 0, 0);
  m.emissive = new pc.Color(0, 0, 0);
  m.useLighting = lit;
  m.useSkybox = false;
  m.cull = pc.CULLFACE_NONE;
  m.update();
  return m;
}

window.fogrefRender = async function (spec) {
  const W = spec.width, H = spec.height;
  const canvas = document.createElement("canvas");
  canvas.width = W;
  canvas.height = H;
  const app = new pc.Application(canvas, {
    graphicsDeviceOptions: { preserveDrawingBuffer: true, antialias: false, alpha: false, deviceTypes: ["webgl2"] },
  });
  const device = app.graphicsDevice;
  device.maxPixelRatio = 1;
  app.setCanvasFillMode(pc.FILLMODE_NONE);
  app.setCanvasResolution(pc.RESOLUTION_FIXED, W, H);
  const c = spec.camera;
  const f = spec.fog;
  const camera = new pc.Entity("camera");
  camera.addComponent("camera", {
    fov: c.fov_y_deg,
    nearClip: f ? f.nearClip : c.near,
    farClip: f ? f.farClip : c.far,
  });
  camera.setPosition(...c.origin);
  camera.lookAt(new pc.Vec3(c.origin[0] + c.forward[0], c.origin[1] + c.forward[1], c.origin[2] + c.forward[2]),
    new pc.Vec3(...c.up));
  app.root.addChild(camera);

  const depthMaterial = new pc.ShaderMaterial({
    uniqueName: "fogrefDepth",
    vertexGLSL: DEPTH_VS,
    fragmentGLSL: DEPTH_FS,
    attributes: { vertex_position: pc.SEMANTIC_POSITION, corner0: pc.SEMANTIC_ATTR12,
                  corner1: pc.SEMANTIC_ATTR13, corner2: pc.SEMANTIC_ATTR14 },
  });
  depthMaterial.cull = pc.CULLFACE_NONE;
  depthMaterial.setParameter("size", [W, H]);
  depthMaterial.update();
  const entities = [], corners = [], materials = [];
  spec.shapes.forEach((s, i) => {
    const positions = b64ToArray(s.positions, Float32Array);
    const indices = b64ToArray(s.indices, Uint32Array);
    const mesh = new pc.Mesh(device);
    mesh.setPositions(positions);
    mesh.setNormals(s.normals ? b64ToArray(s.normals, Float32Array) : pc.calculateNormals(positions, indices));
    mesh.setIndices(indices);
    mesh.update();
    const m = material(s.reflectance, true);
    materials.push(m);
    const e = new pc.Entity(`shape${i}`);
    e.addComponent("render", { meshInstances: [new pc.MeshInstance(mesh, m)] });
    app.root.addChild(e);
    entities.push(e);
    // each triangle on its own, every vertex carrying the triangle's three corners (the depth pass)
    const p = unindexed(positions, indices);
    const cs = triangleCorners(p);
    const cm = new pc.Mesh(device);
    cm.setPositions(p);
    const semantics = [pc.SEMANTIC_ATTR12, pc.SEMANTIC_ATTR13, pc.SEMANTIC_ATTR14];
    cs.forEach((a, k) => cm.setVertexStream(semantics[k], a, 3));
    cm.update();
    const ce = new pc.Entity(`corners${i}`);
    ce.addComponent("render", { meshInstances: [new pc.MeshInstance(cm, depthMaterial)] });
    ce.enabled = false;
    app.root.addChild(ce);
    corners.push(ce);
  });

  if (spec.sun) {
    // irradiance E on a plane facing the sun: PlayCanvas's diffuse is max(n.l, 0) * light colour * albedo
    const w = spec.sun.direction;
    const e = spec.sun.irradiance.map((x) => x / Math.PI);
    const k = Math.max(1, ...e);  // intensity >= 1 multiplies the linear colour
    const sun = new pc.Entity("sun");
    sun.addComponent("light", { type: "directional", color: gamma(e.map((x) => x / k)), intensity: k,
                                castShadows: false });
    // a directional light shines down its entity's -y axis: turn +y onto w (toward the sun)
    const axis = new pc.Vec3().cross(pc.Vec3.UP, new pc.Vec3(...w));
    const s = axis.length();
    if (s > 1e-12) {
      const angle = Math.atan2(s, w[1]) * 180 / Math.PI;
      sun.setRotation(new pc.Quat().setFromAxisAngle(axis.mulScalar(1 / s), angle));
    } else if (w[1] < 0) sun.setRotation(new pc.Quat().setFromAxisAngle(pc.Vec3.RIGHT, 180));
    app.root.addChild(sun);
  }
  // a uniform sky of radiance L: PlayCanvas has no hemisphere light; its ambient light (uniform
  // irradiance, albedo L whatever the normal) is the sky's on a horizontal surface
  app.scene.ambientLight = spec.sky ? gamma(spec.sky) : new pc.Color(0, 0, 0);

  const tex = new pc.Texture(device, { width: W, height: H, format: pc.PIXELFORMAT_RGBA32F, mipmaps: false,
    minFilter: pc.FILTER_NEAREST, magFilter: pc.FILTER_NEAREST });
  const rt = new pc.RenderTarget({ colorBuffer: tex, depth: true });
  const cam = camera.camera;
  const black = material([0, 0, 0], false);

  function setFog(fog, rgb) {
    app.scene.fog.type = fog ? fog.type : pc.FOG_NONE;
    if (!fog) return;
    app.scene.fog.color = gamma(rgb);
    app.scene.fog.density = fog.density;
    app.scene.fog.start = fog.start;
    app.scene.fog.end = fog.end;
  }

  async function pass(clear, fog, fogColour, mat, list, others) {
    setFog(fog, fogColour);
    entities.forEach((e, i) => { e.render.meshInstances[0].material = mat || materials[i]; });
    others.forEach((e) => { e.enabled = false; });
    list.forEach((e) => { e.enabled = true; });
    cam.renderTarget = rt;
    cam.gammaCorrection = pc.GAMMA_NONE;
    cam.clearColor = clear;
    app.render();
    const px = await tex.read(0, 0, W, H, { renderTarget: rt, immediate: true });
    return arrayToB64(new Float32Array(px.buffer, px.byteOffset, W * H * 4));
  }

  const sky = spec.sky ? new pc.Color(...spec.sky) : new pc.Color(0, 0, 0);
  const out = { version: pc.version, target_type: "PIXELFORMAT_RGBA32F" };
  out.final = await pass(sky, f, f && f.color, null, entities, corners);
  out.surface = await pass(sky, null, null, null, entities, corners);
  out.fog_factor = f ? await pass(new pc.Color(0, 0, 0), f, [1, 1, 1], black, entities, corners) : null;
  out.inscatter = f ? await pass(new pc.Color(0, 0, 0), f, f.color, black, entities, corners) : null;
  out.depth = await pass(new pc.Color(0, 0, 0, 0), null, null, null, corners, entities);
  // the canvas as PlayCanvas ships it: the camera's defaults (GAMMA_SRGB, TONEMAP_LINEAR), 8 bits;
  // the clear colour is written unconverted, so it is given gamma-encoded as the other colours
  entities.forEach((e, i) => { e.enabled = true; e.render.meshInstances[0].material = materials[i]; });
  corners.forEach((e) => { e.enabled = false; });
  setFog(f, f && f.color);
  cam.renderTarget = null;
  cam.gammaCorrection = pc.GAMMA_SRGB;
  cam.clearColor = spec.sky ? gamma(spec.sky) : new pc.Color(0, 0, 0);
  app.render();
  const gl = device.gl;
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  const bytes = new Uint8Array(W * H * 4);
  gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, bytes);
  out.canvas = arrayToB64(bytes);
  out.output_colour_space = cam.gammaCorrection === pc.GAMMA_SRGB ? "GAMMA_SRGB (pow 1/2.2)" : String(cam.gammaCorrection);
  out.tone_mapping = cam.toneMapping === pc.TONEMAP_LINEAR ? "TONEMAP_LINEAR" : String(cam.toneMapping);
  out.renderer = gl.getParameter(gl.RENDERER);
  app.destroy();
  return out;
};
document.body.setAttribute("data-ready", "1");
