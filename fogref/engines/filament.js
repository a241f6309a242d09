// fogref's Filament page: renders one view of a fogref scene with the real Filament (npm "filament",
// WebAssembly) and returns its pixels (the page protocol of fogref/engines/__init__.py).  filament.js
// is a classic script: it is loaded from the URL the import map gives "filament".
//
// The npm build ships no compiled materials but gltfio's ubershaders, so the scene is a glTF built
// here: unlit (KHR_materials_unlit) triangles whose vertex colours (COLOR_0, times a white base
// colour) are, by pass, fogref's Lambert shading of the vertex, black, or the vertex's position
// relative to the camera (the depth pass).  Float pixels: the view draws into a RenderTarget with an
// RGBA32F colour texture (post-processing off, so the colour pass writes it directly); Filament's
// JS has no readPixels, so the page notes which GL texture Filament allocates as RGBA32F
// (texStorage2D on its WebGL 2 context, engine.context) and reads it back with gl.readPixels.
import { arrayToB64, b64ToArray, unindexed, withoutDithering } from "./page_helpers.js";

const loaded = new Promise((ok, fail) => {
  const s = document.createElement("script");
  s.src = import.meta.resolve("filament");
  s.onload = () => Filament.init([], ok);
  s.onerror = () => fail(new Error("filament.js did not load from " + s.src));
  document.head.appendChild(s);
});

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];

// Per corner of flat triangles p: the shaded colour (shade(n, p) with n the vertex normal, or the
// face normal without normals, turned toward the camera), black, the position minus the camera and
// the triangle's face normal.
function corners(spec) {
  const o = spec.camera.origin;
  const out = { shaded: [], black: [], position: [], face: [], positions: [] };
  for (const s of spec.shapes) {
    const idx = b64ToArray(s.indices, Uint32Array);
    const p = unindexed(b64ToArray(s.positions, Float32Array), idx);
    const nrm = s.normals ? unindexed(b64ToArray(s.normals, Float32Array), idx) : null;
    const shaded = new Float32Array((p.length / 3) * 4), black = new Float32Array(shaded.length);
    const position = new Float32Array(shaded.length), faces = new Float32Array(shaded.length);
    for (let t = 0; t < p.length; t += 9) {
      const c = [0, 1, 2].map((k) => Array.from(p.subarray(t + 3 * k, t + 3 * k + 3)));
      const face = cross(sub(c[1], c[0]), sub(c[2], c[0]));
      for (let k = 0; k < 3; k++) {
        const v = t / 3 + k;
        let n = nrm ? Array.from(nrm.subarray(3 * v, 3 * v + 3)) : face;
        const len = Math.hypot(...n) || 1;
        n = n.map((x) => x / len);
        if (dot(n, sub(o, c[k])) < 0) n = n.map((x) => -x);
        shaded.set([...shade(spec, s.reflectance, n), 1], 4 * v);
        black.set([0, 0, 0, 1], 4 * v);
        position.set([...sub(c[k], o), 1], 4 * v);
        faces.set([...face, 1], 4 * v);
      }
    }
    out.positions.push(p);
    out.shaded.push(shaded);
    out.black.push(black);
    out.position.push(position);
    out.face.push(faces);
  }
  return out;
}

// Lambert radiance of reflectance rho with unit normal n: rho / pi (E max(n.w, 0) + pi L (1 + n_y) / 2).
function shade(spec, rho, n) {
  const cosSun = spec.sun ? Math.max(dot(n, spec.sun.direction), 0) : 0;
  return [0, 1, 2].map((i) => {
    const E = (spec.sun ? spec.sun.irradiance[i] * cosSun : 0) + (spec.sky ? (Math.PI * spec.sky[i] * (1 + n[1])) / 2 : 0);
    return (rho[i] * E) / Math.PI;
  });
}

// A binary glTF of unlit, double-sided, vertex-coloured triangle lists (positions p, RGBA colours).
function glb(positions, colours) {
  const json = { asset: { version: "2.0" }, extensionsUsed: ["KHR_materials_unlit"], scene: 0,
    scenes: [{ nodes: [0] }], nodes: [{ mesh: 0 }], meshes: [{ primitives: [] }],
    materials: [{ pbrMetallicRoughness: { baseColorFactor: [1, 1, 1, 1] }, doubleSided: true,
                  extensions: { KHR_materials_unlit: {} } }],
    buffers: [{ byteLength: 0 }], bufferViews: [], accessors: [] };
  const parts = [];
  let offset = 0;
  positions.forEach((p, i) => {
    const n = p.length / 3, idx = new Uint32Array(n).map((_, k) => k);
    const min = [Infinity, Infinity, Infinity], max = [-Infinity, -Infinity, -Infinity];
    p.forEach((x, k) => { min[k % 3] = Math.min(min[k % 3], x); max[k % 3] = Math.max(max[k % 3], x); });
    for (const [data, target] of [[p, 34962], [colours[i], 34962], [idx, 34963]]) {
      json.bufferViews.push({ buffer: 0, byteOffset: offset, byteLength: data.byteLength, target });
      parts.push([offset, data]);
      offset += data.byteLength;
    }
    json.accessors.push({ bufferView: 3 * i, componentType: 5126, count: n, type: "VEC3", min, max },
                        { bufferView: 3 * i + 1, componentType: 5126, count: n, type: "VEC4" },
                        { bufferView: 3 * i + 2, componentType: 5125, count: n, type: "SCALAR" });
    json.meshes[0].primitives.push({ attributes: { POSITION: 3 * i, COLOR_0: 3 * i + 1 }, indices: 3 * i + 2, material: 0 });
  });
  json.buffers[0].byteLength = offset;
  const text = new TextEncoder().encode(JSON.stringify(json));
  const jlen = (text.length + 3) & ~3, blen = (offset + 3) & ~3;
  const out = new Uint8Array(28 + jlen + blen);
  const dv = new DataView(out.buffer);
  dv.setUint32(0, 0x46546c67, true); dv.setUint32(4, 2, true); dv.setUint32(8, out.length, true);
  dv.setUint32(12, jlen, true); dv.setUint32(16, 0x4e4f534a, true);
  out.fill(0x20, 20, 20 + jlen); out.set(text, 20);
  dv.setUint32(20 + jlen, blen, true); dv.setUint32(24 + jlen, 0x004e4942, true);
  for (const [o, data] of parts) out.set(new Uint8Array(data.buffer, data.byteOffset, data.byteLength), 28 + jlen + o);
  return out;
}

window.fogrefRender = async function (spec) {
  await loaded;
  const W = spec.width, H = spec.height, c = spec.camera;
  const canvas = document.createElement("canvas");
  canvas.width = W;
  canvas.height = H;
  const engine = Filament.Engine.create(canvas, { preserveDrawingBuffer: true });
  const gl = engine.context;
  gl.getExtension("EXT_color_buffer_float");
  const ditheringRemoved = withoutDithering(gl);
  const floatTextures = [];
  const texStorage2D = gl.texStorage2D.bind(gl);
  gl.texStorage2D = (target, levels, format, w, h) => {
    texStorage2D(target, levels, format, w, h);
    if (format === gl.RGBA32F) floatTextures.push(gl.getParameter(gl.TEXTURE_BINDING_2D));
  };
  const scene = engine.createScene();
  const cam = engine.createCamera(Filament.EntityManager.get().create());
  cam.setProjectionFov(c.fov_y_deg, W / H, c.near, c.far, Filament.Camera$Fov.VERTICAL);
  cam.lookAt(c.origin, sub(c.origin, c.forward.map((x) => -x)), c.up);
  cam.setExposureDirect(1.0);  // the fog colour is scaled by iblLuminance = IBL intensity * exposure = 1
  scene.setIndirectLight(Filament.IndirectLight.Builder().irradianceSh(1, [0, 0, 0]).intensity(1.0).build(engine));
  const fog = spec.fog;
  if (fog && fog.inScatteringSize > 0) {  // the fog's sun term reads the directional light (unlit surfaces ignore it)
    const e = Filament.EntityManager.get().create();
    Filament.LightManager.Builder(Filament.LightManager$Type.DIRECTIONAL).color(fog.lightColor)
      .intensity(fog.lightIntensity).direction(fog.lightDirection.map((x) => -x)).castShadows(false).build(engine, e);
    scene.addEntity(e);
  }
  const tex = (format, usage) => Filament.Texture.Builder().width(W).height(H).levels(1)
    .sampler(Filament.Texture$Sampler.SAMPLER_2D).format(format).usage(usage).build(engine);
  const rt = Filament.RenderTarget.Builder()
    .texture(Filament.RenderTarget$AttachmentPoint.COLOR, tex(Filament.Texture$InternalFormat.RGBA32F, 17))
    .texture(Filament.RenderTarget$AttachmentPoint.DEPTH, tex(Filament.Texture$InternalFormat.DEPTH32F, 2))
    .build(engine);
  const views = [true, false].map((toTarget) => {
    const v = engine.createView();
    v.setCamera(cam);
    v.setScene(scene);
    v.setViewport([0, 0, W, H]);
    // the float target: post-processing off (the colour pass writes it).  The canvas: Filament's
    // defaults (post-processing on: its default ColorGrading, ACES-legacy tone mapping and sRGB
    // output) but FXAA and temporal dithering, turned off (withoutDithering)
    if (toTarget) {
      v.setPostProcessingEnabled(false);
      v.setRenderTarget(rt);
    } else {
      v.setAntiAliasing(Filament.View$AntiAliasing.NONE);
    }
    return v;
  });
  const renderer = engine.createRenderer();
  const swapChain = engine.createSwapChain();
  const loader = engine.createAssetLoader();
  const geo = corners(spec);
  const assets = {};
  for (const k of ["shaded", "black", "position", "face"]) {
    assets[k] = loader.createAsset(glb(geo.positions, geo[k]));
    await new Promise((ok) => assets[k].loadResources(ok, () => {}, "", 1));
  }
  const { lightColor, lightIntensity, lightDirection, ...fogOptions } = fog || {};
  const sky = spec.sky || [0, 0, 0];

  async function draw(toTarget, asset, fogSettings, clear) {
    for (const k in assets) scene.removeEntities(assets[k].getRenderableEntities());
    scene.addEntities(assets[asset].getRenderableEntities());
    const view = views[toTarget ? 0 : 1];
    view.setFogOptions(fogSettings ? Object.assign({ enabled: true }, fogSettings) : { enabled: false });
    renderer.setClearOptions({ clearColor: clear, clear: true });
    // Renderer.beginFrame skips a frame while the previous one's fence is pending, and a WebGL
    // fence signals only once the page yields: wait for a frame that is drawn
    for (let tries = 0; !renderer.beginFrame(swapChain); tries++) {
      if (tries > 200) throw new Error("Filament skipped 200 frames in a row");
      engine.execute();
      await new Promise((ok) => setTimeout(ok, 5));
    }
    renderer.renderView(view);
    renderer.endFrame();
    engine.execute();  // run the queued commands before reading (single-threaded wasm)
    const out = new (toTarget ? Float32Array : Uint8Array)(W * H * 4);
    const fb = gl.createFramebuffer();
    const read = gl.getParameter(gl.READ_FRAMEBUFFER_BINDING), pack = gl.getParameter(gl.PIXEL_PACK_BUFFER_BINDING);
    gl.bindBuffer(gl.PIXEL_PACK_BUFFER, null);
    gl.bindFramebuffer(gl.READ_FRAMEBUFFER, toTarget ? fb : null);
    if (toTarget) gl.framebufferTexture2D(gl.READ_FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, floatTextures[0], 0);
    gl.readPixels(0, 0, W, H, gl.RGBA, toTarget ? gl.FLOAT : gl.UNSIGNED_BYTE, out);
    gl.bindFramebuffer(gl.READ_FRAMEBUFFER, read);
    gl.bindBuffer(gl.PIXEL_PACK_BUFFER, pack);
    gl.deleteFramebuffer(fb);
    return out;
  }

  const out = { version: "", target_type: "RGBA32F RenderTarget", output_colour_space: "sRGB (Rec709-sRGB-D65)",
                tone_mapping: "ACES_LEGACY (the default ColorGrading)" };
  out.final = arrayToB64(await draw(true, "shaded", fog && fogOptions, [...sky, 1]));
  if (floatTextures.length !== 1) throw new Error(`expected one RGBA32F texture, Filament made ${floatTextures.length}`);
  out.surface = arrayToB64(await draw(true, "shaded", null, [...sky, 1]));
  if (fog) {
    // the fog factor with materials black, white fog and no sun term; then the fog's own colour
    const white = Object.assign({}, fogOptions, { color: [1, 1, 1], inScatteringSize: -1 });
    out.fog_factor = arrayToB64(await draw(true, "black", white, [0, 0, 0, 0]));
    out.inscatter = arrayToB64(await draw(true, "black", fogOptions, [0, 0, 0, 0]));
  }
  // The depth pass.  G, B: from the interpolated position minus the camera v (what the fog reads):
  // eye depth and distance.  R: the distance along the ray through the pixel's centre (Filament's
  // projection and camera matrices) to the plane of the triangle (its face normal n, from a pass
  // of flat colours): the camera's own depth, free of the rasteriser's interpolation.  A: hit.
  const p = await draw(true, "position", null, [0, 0, 0, 0]);
  const nrm = await draw(true, "face", null, [0, 0, 0, 0]);
  const P = cam.getProjectionMatrix(), M = cam.getModelMatrix();
  const depth = new Float32Array(W * H * 4);
  for (let i = 0; i < W * H; i++) {
    const v = [p[4 * i], p[4 * i + 1], p[4 * i + 2]], n = [nrm[4 * i], nrm[4 * i + 1], nrm[4 * i + 2]];
    if (!(p[4 * i + 3] > 0.5)) continue;
    const x = (2 * ((i % W) + 0.5)) / W - 1, y = (2 * (Math.floor(i / W) + 0.5)) / H - 1;
    const rv = [(x + P[8]) / P[0], (y + P[9]) / P[5], -1];
    const ray = [0, 1, 2].map((a) => M[a] * rv[0] + M[4 + a] * rv[1] + M[8 + a] * rv[2]);
    depth.set([(dot(n, v) / dot(n, ray)) * Math.hypot(...ray), dot(v, c.forward), Math.hypot(...v), 1], 4 * i);
  }
  out.depth = arrayToB64(depth);
  out.position = arrayToB64(p);
  out.canvas = arrayToB64(await draw(false, "shaded", fog && fogOptions, [...sky, 1]));
  if (ditheringRemoved() !== 1) throw new Error(`dithering: expected one shader to change, ${ditheringRemoved()} did`);
  out.renderer = gl.getParameter(gl.RENDERER);
  Filament.Engine.destroy(engine);
  return out;
};
document.body.setAttribute("data-ready", "1");
