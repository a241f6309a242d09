// What fogref's engine pages share: the pixel transport (typed arrays to and from base64: selenium
// passes strings between Python and the page), the depth pass's triangle corners and Filament's
// dithering switch.  Imported by the engine pages as "./page_helpers.js" (and by Filament's probe
// page, tests/web/filament.html).

export function b64ToArray(text, Type) {
  const bin = atob(text);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return new Type(bytes.buffer);
}

export function arrayToB64(array) {
  const bytes = new Uint8Array(array.buffer, array.byteOffset, array.byteLength);
  let out = "";
  for (let i = 0; i < bytes.length; i += 0x8000) {
    out += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  }
  return btoa(out);
}

// Indexed triangles as a flat list: 3 floats per corner, 9 per triangle.
export function unindexed(positions, indices) {
  const p = new Float32Array(3 * indices.length);
  for (let k = 0; k < indices.length; k++) p.set(positions.subarray(3 * indices[k], 3 * indices[k] + 3), 3 * k);
  return p;
}

// For flat triangles p (9 floats each): three arrays like p in which every vertex of a triangle
// carries that triangle's corner 0, 1 and 2 (the depth pass intersects the pixel's ray with them).
export function triangleCorners(p) {
  const c = [new Float32Array(p.length), new Float32Array(p.length), new Float32Array(p.length)];
  for (let t = 0; t < p.length; t += 9) {
    for (let k = 0; k < 3; k++) {
      for (let v = 0; v < 3; v++) c[k].set(p.subarray(t + 3 * k, t + 3 * k + 3), t + 3 * v);
    }
  }
  return c;
}

// Filament (npm "filament" 1.53.4): its colour-grading pass adds temporal dithering, triangular
// noise under one 8-bit step (shaders/src/dithering.fs), and its JS API has no View.setDithering.
// This turns the dithering off as View::setDithering(Dithering::NONE) does: the noise term of the
// GLSL that Filament gives WebGL context gl is replaced by 0.  Returns how many shaders it changed.
export function withoutDithering(gl) {
  const noise = /\(\(fract\((\w+) \* 95\.4307\) \+ fract\(\1 \* 75\.04961\)\) - 1\.0\) \/ 255\.0/;
  const shaderSource = gl.shaderSource.bind(gl);
  let changed = 0;
  gl.shaderSource = (shader, source) => {
    if (noise.test(source)) changed++;
    shaderSource(shader, source.replace(noise, "0.0"));
  };
  return () => changed;
}
