// Loading glTF/VRM bytes with three.js's GLTFLoader and three-vrm's plugins, in Node or a
// browser: what the parity tests, the benchmark and the example share. Textures are
// stubbed (the tests draw nothing).
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { VRMLoaderPlugin } from '@pixiv/three-vrm';
import { VRMSpringBoneLoaderPlugin } from '@pixiv/three-vrm-springbone';

class StubTexturePlugin {
  constructor(parser) {
    this.parser = parser;
    this.name = 'STUB_TEXTURES';
  }
  loadTexture() {
    return Promise.resolve(new THREE.Texture());
  }
}

/** A GLB's JSON chunk and the rest of the file after it. */
function splitGlb(bytes) {
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const jsonLength = dv.getUint32(12, true);
  const json = JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + jsonLength)));
  return { json, rest: bytes.subarray(20 + jsonLength) };
}

/** A GLB with `json` as its JSON chunk and `rest` (the BIN chunk, with its header) after. */
function joinGlb(json, rest) {
  let text = new TextEncoder().encode(JSON.stringify(json));
  const padded = new Uint8Array((text.length + 3) & ~3).fill(0x20);
  padded.set(text);
  text = padded;
  const out = new Uint8Array(20 + text.length + rest.length);
  const dv = new DataView(out.buffer);
  out.set(new TextEncoder().encode('glTF'), 0);
  dv.setUint32(4, 2, true);
  dv.setUint32(8, out.length, true);
  dv.setUint32(12, text.length, true);
  dv.setUint32(16, 0x4e4f534a, true);
  out.set(text, 20);
  out.set(rest, 20 + text.length);
  return out;
}

/** three-vrm ignores VRMC_springBone_extended_collider objects without a specVersion
 *  (and crashes on some): the one the test files lack is added, as the oracle's
 *  --fix-ext-spec does, so that both runtimes read the same colliders. */
function withExtendedColliderSpec(bytes) {
  const { json, rest } = splitGlb(bytes);
  let changed = false;
  for (const c of json.extensions?.VRMC_springBone?.colliders ?? []) {
    const e = c.extensions?.VRMC_springBone_extended_collider;
    if (e && e.specVersion === undefined) {
      e.specVersion = '1.0';
      changed = true;
    }
  }
  return changed ? joinGlb(json, rest) : bytes;
}

/** The file's bytes (an ArrayBuffer) and its GLTFLoader result, with three-vrm's plugin
 *  (VRMLoaderPlugin for a VRM, VRMSpringBoneLoaderPlugin for a plain glTF with springs). */
export async function loadGltfBytes(raw) {
  const buf = withExtendedColliderSpec(new Uint8Array(raw.buffer, raw.byteOffset, raw.byteLength));
  const data = buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);
  const { json } = splitGlb(buf);
  const used = json.extensionsUsed ?? [];
  const isVrm = used.includes('VRM') || used.includes('VRMC_vrm');
  const loader = new GLTFLoader();
  loader.register((parser) => new StubTexturePlugin(parser));
  if (isVrm) loader.register((parser) => new VRMLoaderPlugin(parser));
  else loader.register((parser) => new VRMSpringBoneLoaderPlugin(parser));
  const warn = console.warn;
  console.warn = () => {};
  try {
    const gltf = await new Promise((resolve, reject) => loader.parse(data, '', resolve, reject));
    const manager = isVrm ? gltf.userData.vrm?.springBoneManager : gltf.userData.vrmSpringBoneManager;
    return { gltf, data, manager };
  } finally {
    console.warn = warn;
  }
}

export { THREE };
