// tassel-three: Tassel's secondary motion for three.js, in WebAssembly.
//
// The solvers are Tassel's own Rust code (crates/tassel-ffi's C ABI, compiled to
// wasm32-unknown-unknown): no second implementation here. This layer maps three.js objects
// to the file's nodes, moves transforms through one Float32Array view of the module's
// memory, and writes the simulated bones back.
//
//   import { TasselSpringBoneManager, TasselCharacter } from 'tassel-three';
//   const springs = await TasselSpringBoneManager.fromGLTF(gltf, bytes, { mode: 'fixed' });
//   vrm.springBoneManager = springs;   // vrm.update(delta) now steps Tassel
//   const character = await TasselCharacter.fromGLTF(gltf, bytes, rigToml, { mode: 'fixed' });
//   character.update(delta);           // after AnimationMixer.update(delta)

const FLOATS = 10; // tx ty tz qx qy qz qw sx sy sz

let modulePromise = null;

/** The WebAssembly module, loaded once (in browsers by fetch beside this file, in Node
 *  from the file system). `source` may be given once to load it from elsewhere: a URL,
 *  bytes, or a compiled `WebAssembly.Module`. */
export function loadTassel(source) {
  if (!modulePromise) {
    modulePromise = instantiate(source).catch((e) => {
      modulePromise = null;
      throw e;
    });
  }
  return modulePromise;
}

async function instantiate(source) {
  let module;
  if (source instanceof WebAssembly.Module) {
    module = source;
  } else if (source instanceof ArrayBuffer || ArrayBuffer.isView(source)) {
    module = await WebAssembly.compile(source);
  } else {
    const url = source ? new URL(source, import.meta.url) : new URL('./tassel.wasm', import.meta.url);
    if (url.protocol === 'file:') {
      const { readFile } = await import('node:fs/promises');
      module = await WebAssembly.compile(await readFile(url));
    } else {
      const response = await fetch(url);
      if (!response.ok) throw new Error(`tassel-three: ${url}: ${response.status} ${response.statusText}`);
      module = await WebAssembly.compile(await response.arrayBuffer());
    }
  }
  const instance = await WebAssembly.instantiate(module, {});
  return new Tassel(instance.exports);
}

/** The module's exports, with strings and buffers across its memory. */
class Tassel {
  constructor(exports) {
    this.x = exports;
    this.memory = exports.memory;
    this.version = this.string(exports.tassel_version());
  }

  /** A NUL-terminated UTF-8 string at `ptr` (null for 0). */
  string(ptr) {
    if (!ptr) return null;
    const bytes = new Uint8Array(this.memory.buffer);
    let end = ptr;
    while (bytes[end] !== 0) end++;
    return new TextDecoder().decode(bytes.subarray(ptr, end));
  }

  /** `bytes` copied into the module's memory: [pointer, length]. Free with `free`. */
  copyIn(bytes) {
    const ptr = this.x.tassel_alloc(Math.max(bytes.length, 1));
    if (!ptr) throw new Error(`tassel-three: out of memory for ${bytes.length} bytes`);
    new Uint8Array(this.memory.buffer, ptr, bytes.length).set(bytes);
    return [ptr, Math.max(bytes.length, 1)];
  }

  cstring(text) {
    if (text == null) return [0, 0];
    return this.copyIn(new TextEncoder().encode(text + '\0'));
  }

  free([ptr, size]) {
    if (ptr) this.x.tassel_free(ptr, size);
  }

  error(what) {
    return new Error(`tassel-three: ${this.string(this.x.tassel_last_error()) ?? what}`);
  }

  /** A character from the file's bytes: [pointer to the character]. */
  load(bytes, rigToml, mode) {
    const data = bytes instanceof Uint8Array ? bytes : new Uint8Array(bytes);
    const file = this.copyIn(data);
    const rig = this.cstring(rigToml);
    const m = this.cstring(mode);
    try {
      const c = this.x.tassel_character_load(file[0], data.length, rig[0], m[0]);
      if (!c) throw this.error('the character did not load');
      return c;
    } finally {
      this.free(file);
      this.free(rig);
      this.free(m);
    }
  }
}

/** The three.js object of each glTF node index, from the loader's associations. */
function nodeObjects(gltf, count) {
  const objects = new Array(count).fill(null);
  const associations = gltf.parser?.associations;
  if (!associations) throw new Error('tassel-three: gltf.parser.associations is missing: pass the GLTFLoader result');
  const visit = (object) => {
    const a = associations.get(object);
    if (a && a.nodes !== undefined && a.nodes < count && objects[a.nodes] === null) objects[a.nodes] = object;
    for (const child of object.children) visit(child);
  };
  visit(gltf.scene);
  return objects;
}

/** One character stepped by Tassel: what both public classes drive. */
class Driver {
  constructor(tassel, ptr, gltf, options) {
    const x = tassel.x;
    this.tassel = tassel;
    this.ptr = ptr;
    this.scene = gltf.scene;
    this.onError = options.onError ?? null;
    this.syncRotation = options.syncRotation ?? false;
    this.lastError = null;
    this.mode = tassel.string(x.tassel_mode(ptr));
    const n = x.tassel_joint_count(ptr);
    this.count = n;
    this.names = [];
    this.parents = new Int32Array(n);
    for (let j = 0; j < n; j++) {
      this.names.push(tassel.string(x.tassel_joint_name(ptr, j)));
      this.parents[j] = x.tassel_joint_parent(ptr, j);
    }
    this.objects = nodeObjects(gltf, n);
    // The joints Tassel writes (size_t is 32 bits in wasm32), parents before children.
    const simCount = x.tassel_simulated_joint_count(ptr);
    const sim = tassel.copyIn(new Uint8Array(Math.max(simCount, 1) * 4));
    if (x.tassel_simulated_joints(ptr, sim[0], simCount) !== 0) throw tassel.error('simulated joints');
    const written = Array.from(new Uint32Array(tassel.memory.buffer, sim[0], simCount));
    tassel.free(sim);
    const depth = (j) => (this.parents[j] < 0 ? 0 : 1 + depth(this.parents[j]));
    written.sort((a, b) => depth(a) - depth(b) || a - b);
    this.written = Int32Array.from(written.filter((j) => this.objects[j] !== null));
    this.isWritten = new Uint8Array(n);
    for (const j of this.written) this.isWritten[j] = 1;
    // Transforms cross in one buffer of the module's memory: the root, then every joint.
    this.floats = n * FLOATS;
    this.buffer = tassel.copyIn(new Uint8Array((this.floats + FLOATS) * 4));
    this.rootPtr = this.buffer[0];
    this.localsPtr = this.buffer[0] + FLOATS * 4;
    this.view = null;
    // Each joint's last animated pose (what the app or its mixer set), and what this layer
    // wrote last: a written bone that still holds it was not animated since.
    this.animated = new Float32Array(this.floats);
    this.wrote = new Float32Array(this.floats);
    this.hasWritten = false;
    const rest = this.locals();
    if (x.tassel_rest_locals(ptr, this.localsPtr, this.floats) !== 0) throw tassel.error('rest pose');
    this.animated.set(rest);
    this.capture();
  }

  /** The bones' current local transforms become their animated pose. */
  capture() {
    const a = this.animated;
    for (let j = 0; j < this.count; j++) {
      const o = this.objects[j];
      if (o) readObject(o, a, j * FLOATS);
    }
    this.hasWritten = false;
  }

  /** The Float32Array view of the joints' locals in the module's memory (made again
   *  only when the memory grew). */
  locals() {
    const buffer = this.tassel.memory.buffer;
    if (!this.view || this.view.buffer !== buffer) {
      this.view = new Float32Array(buffer, this.localsPtr, this.floats);
      this.rootView = new Float32Array(buffer, this.rootPtr, FLOATS);
    }
    return this.view;
  }

  /** The current local transforms of the bones become their animated pose (as three-vrm's
   *  setInitState: the spring bones start again from here). */
  setInitState() {
    this.capture();
    this.tassel.x.tassel_reset(this.ptr);
  }

  /** The written bones go back to their animated pose and every solver starts again from
   *  it on the next update (three-vrm's reset). */
  reset() {
    const a = this.animated;
    for (const j of this.written) {
      const o = this.objects[j];
      setLocal(o, a, j * FLOATS, this.syncRotation);
    }
    this.hasWritten = false;
    this.tassel.x.tassel_reset(this.ptr);
  }

  teleport() {
    this.tassel.x.tassel_teleport(this.ptr);
  }

  update(delta) {
    const x = this.tassel.x;
    const locals = this.locals();
    const a = this.animated;
    const wrote = this.wrote;
    // The character's world transform: the scene's, refreshed (as three-vrm refreshes
    // what it reads).
    this.scene.updateWorldMatrix(true, false);
    decompose(this.scene.matrixWorld, this.rootView);
    for (let j = 0; j < this.count; j++) {
      const o = this.objects[j];
      const at = j * FLOATS;
      if (o !== null && !(this.hasWritten && this.isWritten[j] === 1 && holds(o, wrote, at))) {
        readObject(o, a, at);
      }
    }
    locals.set(a);
    if (x.tassel_frame(this.ptr, this.rootPtr, this.localsPtr, this.localsPtr, this.floats, delta) !== 0) {
      const message = this.tassel.string(x.tassel_last_error());
      if (message !== this.lastError) {
        this.lastError = message;
        if (this.onError) this.onError(message);
        else console.warn(`tassel-three: ${message} (the bones keep their animated pose)`);
      }
      return false;
    }
    this.lastError = null;
    const out = this.locals();
    const written = this.written;
    const objects = this.objects;
    const syncRotation = this.syncRotation;
    for (let w = 0; w < written.length; w++) {
      const j = written[w];
      const o = objects[j];
      const at = j * FLOATS;
      for (let k = 0; k < FLOATS; k++) wrote[at + k] = out[at + k];
      setLocal(o, out, at, syncRotation);
    }
    this.hasWritten = true;
    return true;
  }

  dispose() {
    if (this.ptr) {
      this.tassel.x.tassel_character_free(this.ptr);
      this.tassel.free(this.buffer);
      this.ptr = 0;
    }
  }
}

function readObject(o, out, at) {
  const p = o.position, q = o.quaternion, s = o.scale;
  out[at] = p.x; out[at + 1] = p.y; out[at + 2] = p.z;
  out[at + 3] = q.x; out[at + 4] = q.y; out[at + 5] = q.z; out[at + 6] = q.w;
  out[at + 7] = s.x; out[at + 8] = s.y; out[at + 9] = s.z;
}

/** Writes bone `o`'s local transform from `v[at..at + 10]` and refreshes its `matrix` and
 *  `matrixWorld` (from its parent's), as three-vrm leaves its spring bones. The quaternion
 *  is written through its fields: three.js's setter would also recompute the Euler
 *  `rotation`, which costs more than the whole spring step; `syncRotation` asks for it. */
function setLocal(o, v, at, syncRotation) {
  const tx = v[at], ty = v[at + 1], tz = v[at + 2];
  const x = v[at + 3], y = v[at + 4], z = v[at + 5], w = v[at + 6];
  const sx = v[at + 7], sy = v[at + 8], sz = v[at + 9];
  const p = o.position, q = o.quaternion, s = o.scale;
  p.x = tx; p.y = ty; p.z = tz;
  q._x = x; q._y = y; q._z = z; q._w = w;
  s.x = sx; s.y = sy; s.z = sz;
  if (syncRotation) o.rotation.setFromQuaternion(q, undefined, false);
  // As Matrix4.compose.
  const m = o.matrix.elements;
  const x2 = x + x, y2 = y + y, z2 = z + z;
  const xx = x * x2, xy = x * y2, xz = x * z2;
  const yy = y * y2, yz = y * z2, zz = z * z2;
  const wx = w * x2, wy = w * y2, wz = w * z2;
  m[0] = (1 - (yy + zz)) * sx; m[1] = (xy + wz) * sx; m[2] = (xz - wy) * sx; m[3] = 0;
  m[4] = (xy - wz) * sy; m[5] = (1 - (xx + zz)) * sy; m[6] = (yz + wx) * sy; m[7] = 0;
  m[8] = (xz + wy) * sz; m[9] = (yz - wx) * sz; m[10] = (1 - (xx + yy)) * sz; m[11] = 0;
  m[12] = tx; m[13] = ty; m[14] = tz; m[15] = 1;
  const parent = o.parent;
  const r = o.matrixWorld.elements;
  if (parent === null) {
    for (let i = 0; i < 16; i++) r[i] = m[i];
    return;
  }
  // As Matrix4.multiplyMatrices(parent.matrixWorld, matrix), the last row (0 0 0 1).
  const a = parent.matrixWorld.elements;
  const a11 = a[0], a12 = a[4], a13 = a[8], a14 = a[12];
  const a21 = a[1], a22 = a[5], a23 = a[9], a24 = a[13];
  const a31 = a[2], a32 = a[6], a33 = a[10], a34 = a[14];
  const a41 = a[3], a42 = a[7], a43 = a[11], a44 = a[15];
  for (let c = 0; c < 16; c += 4) {
    const b1 = m[c], b2 = m[c + 1], b3 = m[c + 2], b4 = m[c + 3];
    r[c] = a11 * b1 + a12 * b2 + a13 * b3 + a14 * b4;
    r[c + 1] = a21 * b1 + a22 * b2 + a23 * b3 + a24 * b4;
    r[c + 2] = a31 * b1 + a32 * b2 + a33 * b3 + a34 * b4;
    r[c + 3] = a41 * b1 + a42 * b2 + a43 * b3 + a44 * b4;
  }
}

/** Whether `o` still holds what was written (as float32: what the module gave). */
function holds(o, v, at) {
  const p = o.position, q = o.quaternion, s = o.scale;
  return Math.fround(q.x) === v[at + 3] && Math.fround(q.y) === v[at + 4] && Math.fround(q.z) === v[at + 5] && Math.fround(q.w) === v[at + 6]
    && Math.fround(p.x) === v[at] && Math.fround(p.y) === v[at + 1] && Math.fround(p.z) === v[at + 2]
    && Math.fround(s.x) === v[at + 7] && Math.fround(s.y) === v[at + 8] && Math.fround(s.z) === v[at + 9];
}

/** A Matrix4 (column-major, no shear) into 10 floats, without allocating. */
function decompose(m, out) {
  const e = m.elements;
  let sx = Math.hypot(e[0], e[1], e[2]);
  const sy = Math.hypot(e[4], e[5], e[6]);
  const sz = Math.hypot(e[8], e[9], e[10]);
  const det = e[0] * (e[5] * e[10] - e[6] * e[9]) - e[4] * (e[1] * e[10] - e[2] * e[9]) + e[8] * (e[1] * e[6] - e[2] * e[5]);
  if (det < 0) sx = -sx;
  out[0] = e[12]; out[1] = e[13]; out[2] = e[14];
  const ix = 1 / sx, iy = 1 / sy, iz = 1 / sz;
  const m11 = e[0] * ix, m12 = e[4] * iy, m13 = e[8] * iz;
  const m21 = e[1] * ix, m22 = e[5] * iy, m23 = e[9] * iz;
  const m31 = e[2] * ix, m32 = e[6] * iy, m33 = e[10] * iz;
  // As three.js's Quaternion.setFromRotationMatrix.
  const trace = m11 + m22 + m33;
  let qx, qy, qz, qw;
  if (trace > 0) {
    const s = 0.5 / Math.sqrt(trace + 1.0);
    qw = 0.25 / s; qx = (m32 - m23) * s; qy = (m13 - m31) * s; qz = (m21 - m12) * s;
  } else if (m11 > m22 && m11 > m33) {
    const s = 2.0 * Math.sqrt(1.0 + m11 - m22 - m33);
    qw = (m32 - m23) / s; qx = 0.25 * s; qy = (m12 + m21) / s; qz = (m13 + m31) / s;
  } else if (m22 > m33) {
    const s = 2.0 * Math.sqrt(1.0 + m22 - m11 - m33);
    qw = (m13 - m31) / s; qx = (m12 + m21) / s; qy = 0.25 * s; qz = (m23 + m32) / s;
  } else {
    const s = 2.0 * Math.sqrt(1.0 + m33 - m11 - m22);
    qw = (m21 - m12) / s; qx = (m13 + m31) / s; qy = (m23 + m32) / s; qz = 0.25 * s;
  }
  out[3] = qx; out[4] = qy; out[5] = qz; out[6] = qw;
  out[7] = sx; out[8] = sy; out[9] = sz;
}

/** What both public classes are: one character stepped by Tassel. */
class Stepped {
  constructor(driver) {
    this._driver = driver;
  }

  /** `fixed`, `spec`, `three-vrm` or `classic`. */
  get mode() { return this._driver.mode; }
  /** The three.js objects Tassel writes (the simulated bones). */
  get bones() { return Array.from(this._driver.written, (j) => this._driver.objects[j]); }
  /** The last update's error (null when it stepped). */
  get lastError() { return this._driver.lastError; }

  /** One frame of `delta` seconds (after the AnimationMixer's, if any): reads the bones'
   *  current local transforms and the scene's world transform, writes the simulated bones'
   *  local transforms (and refreshes their matrices). Returns false (the bones untouched)
   *  on bad input, such as NaN. */
  update(delta) { return this._driver.update(delta); }
  /** The simulated bones go back to their animated (initial) pose and start again from it. */
  reset() { this._driver.reset(); }
  /** The bones' current pose becomes the pose the simulation starts from. */
  setInitState() { this._driver.setInitState(); }
  /** The character was moved on purpose: start again at the new place, no whip. */
  teleport() { this._driver.teleport(); }
  /** Frees the module's memory for this character. */
  dispose() { this._driver.dispose(); }
}

/** A drop-in for three-vrm's VRMSpringBoneManager, stepped by Tassel: the file's VRM
 *  spring bones (VRMC_springBone 1.0 or VRM 0.x secondaryAnimation) in `fixed` (the same
 *  look at every frame rate; default), `spec` (the specification's update) or `three-vrm`
 *  mode (three-vrm 3.5.5's own results). */
export class TasselSpringBoneManager extends Stepped {
  /** `gltf`: the GLTFLoader result (with or without three-vrm's plugins); `bytes`: the same
   *  file's ArrayBuffer or Uint8Array. */
  static async fromGLTF(gltf, bytes, options = {}) {
    const tassel = await loadTassel(options.wasm);
    const ptr = tassel.load(bytes, options.rigToml ?? null, options.mode ?? 'fixed');
    return new TasselSpringBoneManager(new Driver(tassel, ptr, gltf, options));
  }
}

/** Any skinned glTF with a Tassel rig file (chains, springs, cloths, ropes; VRM springs
 *  too), stepped by Tassel. */
export class TasselCharacter extends Stepped {
  static async fromGLTF(gltf, bytes, rigToml, options = {}) {
    const tassel = await loadTassel(options.wasm);
    const ptr = tassel.load(bytes, rigToml ?? null, options.mode ?? null);
    return new TasselCharacter(new Driver(tassel, ptr, gltf, options));
  }
}
