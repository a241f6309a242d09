// The pixel transport shared by fogref's engine pages: typed arrays to and from base64 (selenium
// passes strings between Python and the page).  Imported by threejs.js, babylon.js and
// playcanvas.js as "./pixels.js".

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
