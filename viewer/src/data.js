// The page's embedded scene and geometry buffer (viewer/README.md: SCENE, DATA, ARRAY), decoded
// without any request: the buffer is base64 text in the page, inflated by DecompressionStream.

/** The SCENE object of #corrlap-scene; throws a readable Error when it is missing or malformed. */
export function readScene() {
  const element = document.getElementById('corrlap-scene');
  if (!element) throw new Error('the page has no scene (#corrlap-scene)');
  let scene;
  try {
    scene = JSON.parse(element.textContent);
  } catch (error) {
    throw new Error(`the scene is not valid JSON: ${error.message}`);
  }
  if (!scene || scene.format !== 'corrlap-view 1')
    throw new Error(`unknown scene format ${JSON.stringify(scene && scene.format)} (expected "corrlap-view 1")`);
  if (!Array.isArray(scene.meshes) || scene.meshes.length === 0) throw new Error('the scene has no mesh');
  if (!Array.isArray(scene.fields)) scene.fields = [];
  return scene;
}

/** The decoded buffer of #corrlap-data, of exactly scene.data.bytes bytes. */
export async function readData(scene) {
  const element = document.getElementById('corrlap-data');
  if (!element) throw new Error('the page has no geometry data (#corrlap-data)');
  const { encoding, bytes } = scene.data || {};
  let buffer = decodeBase64(element.textContent.trim());
  if (encoding === 'deflate+base64') buffer = await inflate(buffer);
  else if (encoding !== 'base64') throw new Error(`unknown data encoding ${JSON.stringify(encoding)}`);
  if (buffer.length !== bytes)
    throw new Error(`the geometry data has ${buffer.length} bytes once decoded, the scene says ${bytes}`);
  return buffer;
}

function decodeBase64(text) {
  try {
    // Uint8Array.fromBase64 is native and several times faster than atob on tens of megabytes.
    if (typeof Uint8Array.fromBase64 === 'function') return Uint8Array.fromBase64(text);
    const binary = atob(text);
    const out = new Uint8Array(binary.length);
    for (let i = 0; i < binary.length; ++i) out[i] = binary.charCodeAt(i);
    return out;
  } catch (error) {
    throw new Error(`the geometry data is not valid base64: ${error.message}`);
  }
}

async function inflate(compressed) {
  if (typeof DecompressionStream !== 'function')
    throw new Error('this browser cannot decompress the geometry (no DecompressionStream); try a recent one');
  try {
    // A Blob's stream and a Response's body are local: no request is made.
    const stream = new Blob([compressed]).stream().pipeThrough(new DecompressionStream('deflate'));
    return new Uint8Array(await new Response(stream).arrayBuffer());
  } catch (error) {
    // The browser's message ("Failed to fetch" in Chromium) says nothing useful here.
    throw new Error('the geometry data cannot be decompressed: it is not a valid zlib stream');
  }
}

const TYPES = { float32: Float32Array, uint32: Uint32Array, uint8: Uint8Array };

/**
 * The typed array an ARRAY descriptor stands for, un-filtered. `type` and `count` are what the
 * caller expects; `what` names the array in errors.
 */
export function readArray(buffer, desc, type, count, what) {
  if (!desc || typeof desc !== 'object') throw new Error(`${what}: missing array`);
  const { offset, filter } = desc;
  if (desc.type !== type) throw new Error(`${what}: type ${desc.type}, expected ${type}`);
  if (desc.count !== count) throw new Error(`${what}: ${desc.count} elements, expected ${count}`);
  const Type = TYPES[type];
  const size = count * Type.BYTES_PER_ELEMENT;
  if (!Number.isInteger(offset) || offset < 0 || offset % 4 !== 0 || offset + size > buffer.length)
    throw new Error(`${what}: bytes ${offset} to ${offset + size} are not in the buffer of ${buffer.length}`);
  if (filter === 'none' || (type === 'uint8' && filter === 'shuffle')) {
    // Views, not copies (the buffer is ours, little-endian like every browser's platform).
    return new Type(buffer.buffer, buffer.byteOffset + offset, count);
  }
  if (type === 'uint8' || (filter !== 'shuffle' && !(filter === 'delta+shuffle' && type === 'uint32')))
    throw new Error(`${what}: filter ${JSON.stringify(filter)} does not apply to ${type}`);
  const out = unshuffle(buffer, offset, count, filter === 'delta+shuffle');
  return type === 'float32' ? new Float32Array(out.buffer) : out;
}

// Gathers the 4 byte planes back into 32-bit words, summing the deltas on the way when asked.
function unshuffle(buffer, offset, count, delta) {
  const out = new Uint32Array(count);
  const b0 = offset, b1 = offset + count, b2 = offset + 2 * count, b3 = offset + 3 * count;
  let sum = 0;
  for (let i = 0; i < count; ++i) {
    const word = (buffer[b0 + i] | (buffer[b1 + i] << 8) | (buffer[b2 + i] << 16) | (buffer[b3 + i] << 24)) >>> 0;
    sum = delta ? (sum + word) >>> 0 : word;
    out[i] = sum;
  }
  return out;
}
