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
// A settings override's scales, in the C ABI's order.
const SCALE_NAMES = ['damping', 'stiffness', 'worldDampingLocation', 'worldDampingRotation', 'radius', 'limitAngle'];

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

/** Tassel's built-in character as a VRM 1.0 file (a Uint8Array of GLB bytes: a skinned
 *  body, 82 bones, its hair, tail, skirt and charm as 13 VRM springs of 44 joints over 6
 *  colliders), made by the module: an avatar to try, and to redistribute, without a file
 *  of one's own. Load it as any .vrm (`GLTFLoader.parse(bytes.buffer, ...)`). */
export async function builtinAvatar(source) {
  const tassel = await loadTassel(source);
  const x = tassel.x;
  const len = x.tassel_builtin_avatar(0, 0);
  if (!len) throw tassel.error('the built-in avatar was not made');
  const buf = tassel.copyIn(new Uint8Array(len));
  try {
    if (x.tassel_builtin_avatar(buf[0], len) !== len) throw tassel.error('the built-in avatar was not made');
    return new Uint8Array(tassel.memory.buffer, buf[0], len).slice();
  } finally {
    tassel.free(buf);
  }
}

/** The module's exports, with strings and buffers across its memory. */
class Tassel {
  constructor(exports) {
    this.x = exports;
    this.memory = exports.memory;
    this.version = this.string(exports.tassel_version());
    // The compiled characters shared by the managers and characters of one file (see
    // `character`): a sample of the bytes' hash -> [{ data, rig, mode, template, users }].
    this.kinds = new Map();
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

  /** A new character of the file's bytes, rig and mode that shares its compiled rig with
   *  every other character made here from the same bytes, rig and mode (a copy of one
   *  loaded template: the file is parsed and compiled once, and a hundred copies of an
   *  avatar keep one rig in the module's memory — 20 % faster per frame at 100 copies,
   *  measured). Returns [pointer to the character, release]: `release()` after freeing it
   *  frees the template with its last user. The bytes are compared whole with the
   *  template's own copy of them, so changed bytes are a new kind. */
  character(bytes, rigToml, mode) {
    const data = bytes instanceof Uint8Array ? bytes : new Uint8Array(bytes);
    const key = `${sampleHash(data)}:${mode ?? ''}`;
    let kind = this.kinds.get(key)?.find((k) => k.rig === (rigToml ?? null) && sameBytes(k.data, data));
    if (!kind) {
      // Loaded first: a file that does not load leaves no entry behind.
      kind = { data: data.slice(), rig: rigToml ?? null, mode: mode ?? null, template: this.load(data, rigToml, mode), users: 0 };
      let list = this.kinds.get(key);
      if (!list) this.kinds.set(key, (list = []));
      list.push(kind);
    }
    const ptr = this.x.tassel_character_copy(kind.template);
    if (!ptr) {
      if (kind.users === 0) this.dropKind(key, kind);
      throw this.error('the character could not be copied');
    }
    kind.users++;
    let released = false;
    const release = () => {
      if (released) return;
      released = true;
      if (--kind.users === 0) this.dropKind(key, kind);
    };
    return [ptr, release];
  }

  dropKind(key, kind) {
    this.x.tassel_character_free(kind.template);
    const list = this.kinds.get(key);
    list.splice(list.indexOf(kind), 1);
    if (list.length === 0) this.kinds.delete(key);
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

/** A hash of the length and up to 4 096 evenly spaced bytes of `data`: where to look for
 *  a kind (the bytes are then compared whole). */
function sampleHash(data) {
  const n = data.length;
  const stride = Math.max(1, Math.floor(n / 4096));
  let h = 0x811c9dc5 ^ n;
  for (let i = 0; i < n; i += stride) h = Math.imul(h ^ data[i], 0x01000193);
  return h >>> 0;
}

/** Whether two byte arrays hold the same bytes. */
function sameBytes(a, b) {
  if (a.length !== b.length) return false;
  for (let i = 0; i < a.length; i++) if (a[i] !== b[i]) return false;
  return true;
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

/** The three.js parts of some joints, fetched once: each object's position, quaternion and
 *  scale, its `matrix` and `matrixWorld` elements and its parent's `matrixWorld` elements,
 *  in arrays of one type each. The per-frame loops read and write through these (each
 *  array's elements share one shape), not through the objects themselves, whose classes
 *  differ (Bone, Object3D, Group, Mesh...) and would make every property access
 *  megamorphic (measured: the transfer took 2-3x the time). The bones' parents are taken
 *  as they are when the character is made (as three-vrm reads its joints' structure
 *  once). */
class BoneParts {
  constructor(objects, joints) {
    this.object = joints.map((j) => objects[j]);
    this.p = this.object.map((o) => o?.position ?? null);
    this.q = this.object.map((o) => o?.quaternion ?? null);
    this.s = this.object.map((o) => o?.scale ?? null);
    this.m = this.object.map((o) => o?.matrix.elements ?? null);
    this.w = this.object.map((o) => o?.matrixWorld.elements ?? null);
    this.pw = this.object.map((o) => o?.parent?.matrixWorld.elements ?? null);
  }

  /** Part `k`'s local transform into `out[at..at + 10]` (nothing for a joint without an
   *  object: its value stays). */
  read(k, out, at) {
    const p = this.p[k];
    if (p === null) return;
    const q = this.q[k], s = this.s[k];
    out[at] = p.x; out[at + 1] = p.y; out[at + 2] = p.z;
    out[at + 3] = q._x; out[at + 4] = q._y; out[at + 5] = q._z; out[at + 6] = q._w;
    out[at + 7] = s.x; out[at + 8] = s.y; out[at + 9] = s.z;
  }

  /** Whether part `k` still holds `v[at..at + 10]` (as float32: what the module gave). */
  holds(k, v, at) {
    const p = this.p[k], q = this.q[k], s = this.s[k];
    return p !== null
      && Math.fround(q._x) === v[at + 3] && Math.fround(q._y) === v[at + 4] && Math.fround(q._z) === v[at + 5] && Math.fround(q._w) === v[at + 6]
      && Math.fround(p.x) === v[at] && Math.fround(p.y) === v[at + 1] && Math.fround(p.z) === v[at + 2]
      && Math.fround(s.x) === v[at + 7] && Math.fround(s.y) === v[at + 8] && Math.fround(s.z) === v[at + 9];
  }

  /** Writes part `k`'s local transform from `v[at..at + 10]` and refreshes its `matrix`
   *  and (with `world`) its `matrixWorld` from its parent's, as three-vrm leaves its spring
   *  bones. The quaternion is written through its fields: three.js's setter would also
   *  recompute the Euler `rotation`, which costs more than the whole spring step;
   *  `syncRotation` asks for it. With `turnOnly` the position and scale objects are left
   *  alone: a crowd only turns the bones it writes, so they already hold the values in
   *  `v` (this frame's animated ones, read from them or unchanged since); each is a heap
   *  object of its own, and touching it was a fifth of the crowd's transfer. */
  write(k, v, at, syncRotation, world, turnOnly = false) {
    const tx = v[at], ty = v[at + 1], tz = v[at + 2];
    const x = v[at + 3], y = v[at + 4], z = v[at + 5], w = v[at + 6];
    const sx = v[at + 7], sy = v[at + 8], sz = v[at + 9];
    const q = this.q[k];
    if (!turnOnly) {
      const p = this.p[k], s = this.s[k];
      p.x = tx; p.y = ty; p.z = tz;
      s.x = sx; s.y = sy; s.z = sz;
    }
    q._x = x; q._y = y; q._z = z; q._w = w;
    if (syncRotation) this.object[k].rotation.setFromQuaternion(q, undefined, false);
    // As Matrix4.compose.
    const m = this.m[k];
    const x2 = x + x, y2 = y + y, z2 = z + z;
    const xx = x * x2, xy = x * y2, xz = x * z2;
    const yy = y * y2, yz = y * z2, zz = z * z2;
    const wx = w * x2, wy = w * y2, wz = w * z2;
    const m0 = (1 - (yy + zz)) * sx, m1 = (xy + wz) * sx, m2 = (xz - wy) * sx;
    const m4 = (xy - wz) * sy, m5 = (1 - (xx + zz)) * sy, m6 = (yz + wx) * sy;
    const m8 = (xz + wy) * sz, m9 = (yz - wx) * sz, m10 = (1 - (xx + yy)) * sz;
    m[0] = m0; m[1] = m1; m[2] = m2; m[3] = 0;
    m[4] = m4; m[5] = m5; m[6] = m6; m[7] = 0;
    m[8] = m8; m[9] = m9; m[10] = m10; m[11] = 0;
    m[12] = tx; m[13] = ty; m[14] = tz; m[15] = 1;
    if (!world) return;
    const r = this.w[k];
    const a = this.pw[k];
    if (a === null) {
      for (let i = 0; i < 16; i++) r[i] = m[i];
      return;
    }
    // As Matrix4.multiplyMatrices(parent.matrixWorld, matrix), the local matrix's last
    // row being (0 0 0 1).
    const a11 = a[0], a12 = a[4], a13 = a[8], a14 = a[12];
    const a21 = a[1], a22 = a[5], a23 = a[9], a24 = a[13];
    const a31 = a[2], a32 = a[6], a33 = a[10], a34 = a[14];
    const a41 = a[3], a42 = a[7], a43 = a[11], a44 = a[15];
    r[0] = a11 * m0 + a12 * m1 + a13 * m2;
    r[1] = a21 * m0 + a22 * m1 + a23 * m2;
    r[2] = a31 * m0 + a32 * m1 + a33 * m2;
    r[3] = a41 * m0 + a42 * m1 + a43 * m2;
    r[4] = a11 * m4 + a12 * m5 + a13 * m6;
    r[5] = a21 * m4 + a22 * m5 + a23 * m6;
    r[6] = a31 * m4 + a32 * m5 + a33 * m6;
    r[7] = a41 * m4 + a42 * m5 + a43 * m6;
    r[8] = a11 * m8 + a12 * m9 + a13 * m10;
    r[9] = a21 * m8 + a22 * m9 + a23 * m10;
    r[10] = a31 * m8 + a32 * m9 + a33 * m10;
    r[11] = a41 * m8 + a42 * m9 + a43 * m10;
    r[12] = a11 * tx + a12 * ty + a13 * tz + a14;
    r[13] = a21 * tx + a22 * ty + a23 * tz + a24;
    r[14] = a31 * tx + a32 * ty + a33 * tz + a34;
    r[15] = a41 * tx + a42 * ty + a43 * tz + a44;
  }

  /** Refreshes part `k`'s `matrix` and `matrixWorld` from its own local transform and its
   *  parent's `matrixWorld`, as three's `updateWorldMatrix(false, false)` does, without
   *  writing the local transform: an object between the written bones and the scene
   *  that nothing writes. Through three itself where its flags ask for something else
   *  (`matrixAutoUpdate` or `matrixWorldAutoUpdate` off, a `pivot`). */
  refresh(k) {
    // (The matrices as `write` makes them, written out again: one function for both, called
    // from each, made the written bones 4-10 % slower, measured with bench/ab.mjs.)
    const o = this.object[k];
    if (o.matrixAutoUpdate !== true || o.matrixWorldAutoUpdate !== true || (o.pivot ?? null) !== null) {
      o.updateWorldMatrix(false, false);
      return;
    }
    o.matrixWorldNeedsUpdate = false;
    const p = this.p[k], q = this.q[k], s = this.s[k];
    const tx = p.x, ty = p.y, tz = p.z, x = q._x, y = q._y, z = q._z, w = q._w, sx = s.x, sy = s.y, sz = s.z;
    // As Matrix4.compose.
    const m = this.m[k];
    const x2 = x + x, y2 = y + y, z2 = z + z;
    const xx = x * x2, xy = x * y2, xz = x * z2;
    const yy = y * y2, yz = y * z2, zz = z * z2;
    const wx = w * x2, wy = w * y2, wz = w * z2;
    const m0 = (1 - (yy + zz)) * sx, m1 = (xy + wz) * sx, m2 = (xz - wy) * sx;
    const m4 = (xy - wz) * sy, m5 = (1 - (xx + zz)) * sy, m6 = (yz + wx) * sy;
    const m8 = (xz + wy) * sz, m9 = (yz - wx) * sz, m10 = (1 - (xx + yy)) * sz;
    m[0] = m0; m[1] = m1; m[2] = m2; m[3] = 0;
    m[4] = m4; m[5] = m5; m[6] = m6; m[7] = 0;
    m[8] = m8; m[9] = m9; m[10] = m10; m[11] = 0;
    m[12] = tx; m[13] = ty; m[14] = tz; m[15] = 1;
    const r = this.w[k];
    const a = this.pw[k];
    if (a === null) {
      for (let i = 0; i < 16; i++) r[i] = m[i];
      return;
    }
    // As Matrix4.multiplyMatrices(parent.matrixWorld, matrix), the local matrix's last
    // row being (0 0 0 1).
    const a11 = a[0], a12 = a[4], a13 = a[8], a14 = a[12];
    const a21 = a[1], a22 = a[5], a23 = a[9], a24 = a[13];
    const a31 = a[2], a32 = a[6], a33 = a[10], a34 = a[14];
    const a41 = a[3], a42 = a[7], a43 = a[11], a44 = a[15];
    r[0] = a11 * m0 + a12 * m1 + a13 * m2;
    r[1] = a21 * m0 + a22 * m1 + a23 * m2;
    r[2] = a31 * m0 + a32 * m1 + a33 * m2;
    r[3] = a41 * m0 + a42 * m1 + a43 * m2;
    r[4] = a11 * m4 + a12 * m5 + a13 * m6;
    r[5] = a21 * m4 + a22 * m5 + a23 * m6;
    r[6] = a31 * m4 + a32 * m5 + a33 * m6;
    r[7] = a41 * m4 + a42 * m5 + a43 * m6;
    r[8] = a11 * m8 + a12 * m9 + a13 * m10;
    r[9] = a21 * m8 + a22 * m9 + a23 * m10;
    r[10] = a31 * m8 + a32 * m9 + a33 * m10;
    r[11] = a41 * m8 + a42 * m9 + a43 * m10;
    r[12] = a11 * tx + a12 * ty + a13 * tz + a14;
    r[13] = a21 * tx + a22 * ty + a23 * tz + a24;
    r[14] = a31 * tx + a32 * ty + a33 * tz + a34;
    r[15] = a41 * tx + a42 * ty + a43 * tz + a44;
  }
}

/** The module's `size_t` list (32 bits in wasm32) that `fill(ptr, count)` writes. */
function indices(tassel, count, fill, what) {
  const buf = tassel.copyIn(new Uint8Array(Math.max(count, 1) * 4));
  try {
    if (fill(buf[0], count) !== 0) throw tassel.error(what);
    return Array.from(new Uint32Array(tassel.memory.buffer, buf[0], count));
  } finally {
    tassel.free(buf);
  }
}

/** A loaded character's joints (the file's nodes): their count and depths. */
function jointTable(tassel, ptr) {
  const x = tassel.x;
  const n = x.tassel_joint_count(ptr);
  const parents = new Int32Array(n);
  for (let j = 0; j < n; j++) parents[j] = x.tassel_joint_parent(ptr, j);
  const depth = (j) => (parents[j] < 0 ? 0 : 1 + depth(parents[j]));
  const depths = Int32Array.from(parents, (_, j) => depth(j));
  return { n, depths };
}

/** Joints in the order they are written: parents before children (a child's world matrix
 *  is made from its parent's, written first). */
function parentsFirst(joints, depths) {
  return [...joints].sort((a, b) => depths[a] - depths[b] || a - b);
}

/** The order a character's bones are written in, parents first: entries `k >= 0` write
 *  `parts`' k-th joint (given in `order`); with `world`, entries `-1 - i` refresh the
 *  matrixWorld of `refresh`'s i-th object (`refresh`: BoneParts), an object between a
 *  written bone and the scene that is not written itself (a spring chain's non-simulated
 *  parent and its ancestors), so that every matrixWorld written is made from its parent's
 *  of this frame, not the last render's. Taken from the objects' parents when the
 *  character is made. (Refreshed in BoneParts rather than by three's generic
 *  updateWorldMatrix: the 10 ancestors of the built-in avatar were 4 % of the web
 *  manager's frame through three.) */
function writePlan(parts, order, scene, world) {
  const written = new Set(parts.object.filter((o) => o));
  const refresh = [];
  if (world) {
    const seen = new Set();
    for (const o of parts.object) {
      if (!o) continue;
      for (let a = o.parent; a && a !== scene && !written.has(a) && !seen.has(a); a = a.parent) {
        seen.add(a);
        refresh.push(a);
      }
    }
  }
  const depth = (o) => {
    let d = 0;
    for (let a = o.parent; a; a = a.parent) d++;
    return d;
  };
  const entries = [];
  order.forEach((k, rank) => {
    const o = parts.object[k];
    if (o) entries.push({ e: k, depth: depth(o), rank });
  });
  refresh.forEach((o, i) => entries.push({ e: -1 - i, depth: depth(o), rank: -1 }));
  entries.sort((a, b) => a.depth - b.depth || a.rank - b.rank);
  return { plan: Int32Array.from(entries, (x) => x.e), refresh: new BoneParts(refresh, refresh.map((_, i) => i)) };
}

/** Writes a character's bones by its plan (see writePlan): joint k from `v[base + at(k)..]`. */
function writeBones(parts, { plan, refresh }, v, base, at, syncRotation, world, turnOnly = false) {
  for (let i = 0; i < plan.length; i++) {
    const e = plan[i];
    if (e >= 0) parts.write(e, v, base + at[e], syncRotation, world, turnOnly);
    else refresh.refresh(-1 - e);
  }
}

/** One character stepped by Tassel: what both public classes drive. */
class Driver {
  constructor(tassel, ptr, gltf, options, turnOnly = false) {
    const x = tassel.x;
    this.tassel = tassel;
    this.ptr = ptr;
    this.scene = gltf.scene;
    this.onError = options.onError ?? null;
    this.syncRotation = options.syncRotation ?? false;
    this.worldMatrices = options.worldMatrices ?? true;
    // VRM spring bones alone only turn the bones they write (a rig file's solvers are not
    // assumed to): their position and scale objects are then left alone.
    this.turnOnly = turnOnly;
    this.lastError = null;
    this.mode = tassel.string(x.tassel_mode(ptr));
    const { n, depths } = jointTable(tassel, ptr);
    this.count = n;
    this.objects = nodeObjects(gltf, n);
    const simulated = indices(tassel, x.tassel_simulated_joint_count(ptr), (p, c) => x.tassel_simulated_joints(ptr, p, c), 'simulated joints');
    this.written = Int32Array.from(parentsFirst(simulated.filter((j) => this.objects[j] !== null), depths));
    this.all = new BoneParts(this.objects, Array.from({ length: n }, (_, j) => j));
    this.out = new BoneParts(this.objects, Array.from(this.written));
    this.plan = writePlan(this.out, Array.from(this.written, (_, k) => k), this.scene, this.worldMatrices);
    // Where written joint k's transform is in the joints' buffer.
    this.writtenAt = Int32Array.from(this.written, (j) => j * FLOATS);
    this.isWritten = new Uint8Array(n);
    for (const j of this.written) this.isWritten[j] = 1;
    // The joints a frame depends on (for VRM springs: the springs, their ancestors and the
    // colliders' nodes): update reads only these; the others keep their last value.
    this.readJoints = Int32Array.from(indices(tassel, x.tassel_read_joint_count(ptr), (p, c) => x.tassel_read_joints(ptr, p, c), 'read joints'));
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
    for (let j = 0; j < this.count; j++) this.all.read(j, this.animated, j * FLOATS);
    this.hasWritten = false;
  }

  /** The Float32Array view of the joints' locals in the module's memory (made again
   *  only when the memory grew: growing detaches the old buffer, and a view of a detached
   *  buffer has length 0 — cheaper to ask than `memory.buffer`, a call into the engine). */
  locals() {
    if (!this.view || this.view.length === 0) {
      const buffer = this.tassel.memory.buffer;
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
    this.scene.updateWorldMatrix(true, false);
    writeBones(this.out, this.plan, this.animated, 0, this.writtenAt, this.syncRotation, this.worldMatrices);
    this.hasWritten = false;
    this.tassel.x.tassel_reset(this.ptr);
  }

  teleport() {
    this.tassel.x.tassel_teleport(this.ptr);
  }

  /** Acts on an animation event starting with `tassel:` (`tassel:reset_dynamics`,
   *  `tassel:set_alpha 0.3 [chain]`, `tassel:enable_force NAME`, `tassel:disable_force
   *  NAME`, `tassel:force_once NAME`, `tassel:override NAME stiffness=0.5 duration=2 ...`,
   *  `tassel:stop_override NAME [blend_out]`): true when it acted, false for the game's
   *  own events; throws on a malformed one or a name that does not exist. */
  event(name) {
    const text = this.tassel.cstring(name);
    try {
      const r = this.tassel.x.tassel_event(this.ptr, text[0]);
      if (r < 0) throw this.tassel.error('the event failed');
      return r === 1;
    } finally {
      this.tassel.free(text);
    }
  }

  /** Starts a timed settings override of the rig's chains (KawaiiPhysics'
   *  StartPhysicsSettingsOverride): `scale` multiplies `damping`, `stiffness`,
   *  `worldDampingLocation`, `worldDampingRotation`, `radius` and `limitAngle` (unset: 1)
   *  of the chain named `chain` (unset: every chain) for `duration` seconds (Infinity:
   *  until stopped), blending in over `blendIn` and out over `blendOut`. Up to 8 act at
   *  once and they multiply. Returns a handle for `stopSettingsOverride`; throws on a bad
   *  scale, time or chain. */
  startSettingsOverride(scale = {}, { duration = 2, blendIn = 0.2, blendOut = 0.5, chain = null } = {}) {
    const six = new Float32Array(SCALE_NAMES.map((n) => scale[n] ?? 1));
    const buf = this.tassel.copyIn(new Uint8Array(six.buffer));
    const name = this.tassel.cstring(chain);
    try {
      const h = this.tassel.x.tassel_start_settings_override(
        this.ptr, buf[0], duration, blendIn, blendOut, name[0]);
      if (h < 0) throw this.tassel.error('the settings override failed');
      return h;
    } finally {
      this.tassel.free(buf);
      this.tassel.free(name);
    }
  }

  /** Stops a settings override by its handle, blending out over `blendOut` seconds (0: at
   *  once): true when one had the handle, false when it had ended. */
  stopSettingsOverride(handle, blendOut = 0.5) {
    const r = this.tassel.x.tassel_stop_settings_override(this.ptr, handle, blendOut);
    if (r < 0) throw this.tassel.error('stopping the settings override failed');
    return r === 1;
  }

  /** This character's colliders in the world as its last update placed them (every
   *  collider, or the rig's `[[collider_group]]` named `group`): a Float32Array of 12
   *  floats each (kind 0 sphere / 1 capsule / 2 tapered capsule / 3 box / 4 plane, four
   *  shape parameters, world translation x y z, rotation quaternion x y z w), for another
   *  character's `setSharedColliders`. Throws on a group the rig does not define. */
  sharedColliders(group = null) {
    const x = this.tassel.x;
    const name = this.tassel.cstring(group);
    try {
      const n = Number(x.tassel_shared_colliders(this.ptr, name[0], 0, 0));
      if (n < 0) throw this.tassel.error('reading the shared colliders failed');
      if (n === 0) return new Float32Array(0);
      const buf = this.tassel.copyIn(new Uint8Array(n * 12 * 4));
      try {
        const wrote = Number(x.tassel_shared_colliders(this.ptr, name[0], buf[0], n));
        if (wrote !== n) throw this.tassel.error('reading the shared colliders failed');
        return new Float32Array(this.tassel.memory.buffer, buf[0], n * 12).slice();
      } finally {
        this.tassel.free(buf);
      }
    } finally {
      this.tassel.free(name);
    }
  }

  /** Sets the colliders other characters share with this one (12 floats each, as
   *  `sharedColliders` gives them; empty: none): the rig's chains with
   *  `use_shared_collision = true` collide with them from the next update. Throws on a bad
   *  kind, shape or transform. */
  setSharedColliders(floats) {
    const data = floats instanceof Float32Array ? floats : new Float32Array(floats);
    if (data.length % 12 !== 0) throw new Error(`tassel-three: ${data.length} floats are not whole colliders of 12`);
    const n = data.length / 12;
    const buf = n ? this.tassel.copyIn(new Uint8Array(data.buffer, data.byteOffset, data.byteLength)) : [0, 0];
    try {
      if (this.tassel.x.tassel_set_shared_colliders(this.ptr, buf[0], n) < 0) {
        throw this.tassel.error('setting the shared colliders failed');
      }
    } finally {
      this.tassel.free(buf);
    }
  }

  update(delta) {
    const x = this.tassel.x;
    const locals = this.locals();
    const a = this.animated;
    const wrote = this.wrote;
    const all = this.all;
    const isWritten = this.isWritten;
    // The character's world transform: the scene's, refreshed (as three-vrm refreshes
    // what it reads).
    this.scene.updateWorldMatrix(true, false);
    decompose(this.scene.matrixWorld, this.rootView, 0);
    const check = this.hasWritten;
    const readJoints = this.readJoints;
    for (let r = 0; r < readJoints.length; r++) {
      const j = readJoints[r];
      const at = j * FLOATS;
      if (!(check && isWritten[j] === 1 && all.holds(j, wrote, at))) all.read(j, a, at);
    }
    locals.set(a);
    if (x.tassel_frame(this.ptr, this.rootPtr, this.localsPtr, this.localsPtr, this.floats, delta) !== 0) {
      this.failed(this.tassel.string(x.tassel_last_error()));
      return false;
    }
    this.lastError = null;
    const out = this.locals();
    const writtenAt = this.writtenAt;
    // Every joint's (only the written ones' are ever compared): one copy.
    wrote.set(out);
    writeBones(this.out, this.plan, out, 0, writtenAt, this.syncRotation, this.worldMatrices, this.turnOnly);
    this.hasWritten = true;
    return true;
  }

  /** Reports a failed update's message (once until an update steps again). */
  failed(message) {
    if (message !== this.lastError) {
      this.lastError = message;
      if (this.onError) this.onError(message);
      else console.warn(`tassel-three: ${message} (the bones keep their animated pose)`);
    }
  }

  dispose() {
    if (this.ptr) {
      this.tassel.x.tassel_character_free(this.ptr);
      this.tassel.free(this.buffer);
      this.ptr = 0;
      this.release?.();
    }
  }
}

/** A Matrix4 (column-major, no shear) into 10 floats, without allocating. */
function decompose(m, out, at) {
  const e = m.elements;
  // (Math.sqrt of the sum, not Math.hypot: V8's hypot is a slow generic call.)
  let sx = Math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
  const sy = Math.sqrt(e[4] * e[4] + e[5] * e[5] + e[6] * e[6]);
  const sz = Math.sqrt(e[8] * e[8] + e[9] * e[9] + e[10] * e[10]);
  const det = e[0] * (e[5] * e[10] - e[6] * e[9]) - e[4] * (e[1] * e[10] - e[2] * e[9]) + e[8] * (e[1] * e[6] - e[2] * e[5]);
  if (det < 0) sx = -sx;
  out[at] = e[12]; out[at + 1] = e[13]; out[at + 2] = e[14];
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
  out[at + 3] = qx; out[at + 4] = qy; out[at + 5] = qz; out[at + 6] = qw;
  out[at + 7] = sx; out[at + 8] = sy; out[at + 9] = sz;
}

/** The driver of a new character of `bytes`: sharing the compiled rig of the others of the
 *  same bytes, rig and mode unless `options.shareRig` is false (then loaded on its own). */
function driverOf(tassel, gltf, bytes, rigToml, mode, options, turnOnly = false) {
  const [ptr, release] = options.shareRig === false
    ? [tassel.load(bytes, rigToml, mode), null]
    : tassel.character(bytes, rigToml, mode);
  try {
    const driver = new Driver(tassel, ptr, gltf, options, turnOnly);
    driver.release = release;
    return driver;
  } catch (e) {
    tassel.x.tassel_character_free(ptr);
    release?.();
    throw e;
  }
}

/** What both public classes are: one character stepped by Tassel. */
class Stepped {
  constructor(driver) {
    this._driver = driver;
  }

  /** `fixed`, `spec`, `three-vrm`, `classic`, `kawaii` or `spcr`. */
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

  /** Acts on an animation event starting with `tassel:` (`tassel:reset_dynamics`,
   *  `tassel:set_alpha 0.3 [chain]`, `tassel:enable_force NAME`, `tassel:disable_force
   *  NAME`, `tassel:force_once NAME`): true when it acted, false for the game's own events;
   *  throws on a malformed one or a name that does not exist. */
  event(name) { return this._driver.event(name); }
  /** Starts a timed settings override of the rig's chains (see the README): returns its
   *  handle. */
  startSettingsOverride(scale, options) { return this._driver.startSettingsOverride(scale, options); }
  /** Stops a settings override by its handle: true when one had it. */
  stopSettingsOverride(handle, blendOut) { return this._driver.stopSettingsOverride(handle, blendOut); }
  /** This character's colliders in the world (a Float32Array, 12 floats each; see the
   *  README), for another character's `setSharedColliders`. */
  sharedColliders(group) { return this._driver.sharedColliders(group); }
  /** Sets the colliders other characters share with this one (their chains with
   *  `use_shared_collision` collide with them). */
  setSharedColliders(floats) { this._driver.setSharedColliders(floats); }
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
    const rigToml = options.rigToml ?? null;
    return new TasselSpringBoneManager(driverOf(tassel, gltf, bytes, rigToml, options.mode ?? 'fixed', options, rigToml == null));
  }
}

/** Any skinned glTF with a Tassel rig file (chains, springs, cloths, ropes; VRM springs
 *  too), stepped by Tassel. */
export class TasselCharacter extends Stepped {
  static async fromGLTF(gltf, bytes, rigToml, options = {}) {
    const tassel = await loadTassel(options.wasm);
    return new TasselCharacter(driverOf(tassel, gltf, bytes, rigToml ?? null, options.mode ?? null, options));
  }
}

/** Many characters of one file stepped together: one WebAssembly call a frame for all of
 *  them. A file whose only solver is VRM spring bones (or bone chains) runs on Tassel's
 *  crowd path, the characters side by side in SIMD lanes; any other file one character
 *  after another, still in one call. Each member gives the results its own
 *  `TasselSpringBoneManager` / `TasselCharacter` would (reset before its first update),
 *  bit for bit.
 *
 *    const crowd = await TasselCrowd.fromBytes(bytes, { mode: 'fixed' });
 *    const a = crowd.add(gltfA), b = crowd.add(gltfB);   // GLTFLoader results of the file
 *    vrmA.springBoneManager = a;   // optional: a member's update() does nothing, so
 *                                  // vrm.update(delta) leaves the springs to the crowd
 *    crowd.update(delta);          // every member, after their animation and vrm.update
 */
export class TasselCrowd {
  /** `bytes`: the file (GLB, VRM or glTF with embedded buffers); options as
   *  TasselSpringBoneManager.fromGLTF's, and `rigToml` for chains, springs, cloths and
   *  ropes (needed for a file without VRM spring bones). */
  static async fromBytes(bytes, options = {}) {
    const tassel = await loadTassel(options.wasm);
    const kind = tassel.load(bytes, options.rigToml ?? null, options.mode ?? null);
    try {
      return new TasselCrowd(tassel, kind, options);
    } catch (e) {
      tassel.x.tassel_character_free(kind);
      throw e;
    }
  }

  constructor(tassel, kind, options) {
    const x = tassel.x;
    this._tassel = tassel;
    this._kind = kind;
    this._onError = options.onError ?? null;
    this._syncRotation = options.syncRotation ?? false;
    this._worldMatrices = options.worldMatrices ?? true;
    const ptr = x.tassel_crowd_new(kind);
    if (!ptr) throw tassel.error('the crowd was not made');
    this._ptr = ptr;
    this.mode = tassel.string(x.tassel_mode(kind));
    /** How the members step: 'vrm' or 'chains' (side by side in SIMD lanes) or
     *  'characters' (one after another). */
    this.kind = tassel.string(x.tassel_crowd_kind(ptr));
    const { n, depths } = jointTable(tassel, kind);
    this._count = n;
    this._read = indices(tassel, x.tassel_crowd_read_joint_count(ptr), (p, c) => x.tassel_crowd_read_joints(ptr, p, c), 'read joints');
    this._written = indices(tassel, x.tassel_crowd_written_joint_count(ptr), (p, c) => x.tassel_crowd_written_joints(ptr, p, c), 'written joints');
    // The written joints' places in the output, parents first.
    const place = new Map(this._written.map((j, k) => [j, k]));
    this._order = Array.from(parentsFirst(this._written, depths), (j) => place.get(j));
    // Where written joint k's transform is in a member's output.
    this._writtenAt = Int32Array.from(this._written, (_, k) => k * FLOATS);
    // Each written joint's place among the read joints (-1: not read).
    const readAt = new Map(this._read.map((j, r) => [j, r]));
    this._writtenRead = Int32Array.from(this._written, (j) => readAt.get(j) ?? -1);
    this._readWritten = Int32Array.from(this._read, (j) => place.get(j) ?? -1);
    this._rest = new Float32Array(n * FLOATS);
    const restBuf = tassel.copyIn(new Uint8Array(n * FLOATS * 4));
    try {
      if (x.tassel_rest_locals(kind, restBuf[0], n * FLOATS) !== 0) throw tassel.error('rest pose');
      this._rest.set(new Float32Array(tassel.memory.buffer, restBuf[0], n * FLOATS));
    } finally {
      tassel.free(restBuf);
    }
    this._members = [];
    this._capacity = 0;
    this._buffers = null;
    this._views = null;
    this._held = new Uint8Array(0);
    this.lastError = null;
  }

  /** Number of members. */
  get size() { return this._members.length; }
  /** The members, in crowd order. */
  get members() { return [...this._members]; }

  /** Adds a loaded copy of the file (its GLTFLoader result): its bones are mapped through
   *  `gltf.parser.associations`, its root is `gltf.scene`. It starts from its pose on its
   *  first update. */
  add(gltf) {
    if (!this._ptr) throw new Error('tassel-three: the crowd was disposed');
    const objects = nodeObjects(gltf, this._count);
    const i = this._tassel.x.tassel_crowd_add(this._ptr);
    if (i < 0) throw this._tassel.error('add');
    const member = new TasselCrowdMember(this, gltf.scene, objects, Number(i));
    this._members.push(member);
    this._reserve(this._members.length);
    return member;
  }

  _reserve(count) {
    if (count <= this._capacity) return;
    const cap = Math.max(count, this._capacity * 2, 8);
    const t = this._tassel;
    const sizes = [cap * FLOATS, cap * this._read.length * FLOATS, cap * this._written.length * FLOATS];
    const next = sizes.map((s) => t.copyIn(new Uint8Array(Math.max(s, 1) * 4)));
    if (this._buffers) for (const b of this._buffers) t.free(b);
    this._buffers = next;
    this._capacity = cap;
    this._views = null;
    this._held = new Uint8Array(cap);
  }

  /** Float32Array views of the roots, inputs and outputs in the module's memory (made
   *  again only when the memory grew or the buffers moved). */
  _viewsNow() {
    const buffer = this._tassel.memory.buffer;
    if (!this._views || this._views[0].buffer !== buffer) {
      this._views = this._buffers.map(([ptr, bytes]) => new Float32Array(buffer, ptr, bytes >> 2));
    }
    return this._views;
  }

  /** One frame of `delta` seconds for every member: reads each member's bones (the
   *  joints the solvers read) and scene transform, steps all in one call, writes the
   *  simulated bones. Returns false when some member's input was bad (NaN...): those keep
   *  their animated pose (their `lastError` says why), the others stepped. */
  update(delta) {
    const members = this._members;
    const count = members.length;
    if (count === 0 || !this._ptr) return true;
    const [roots, locals] = this._viewsNow();
    const R = this._read.length * FLOATS;
    const W = this._written.length * FLOATS;
    const readWritten = this._readWritten;
    for (let m = 0; m < count; m++) {
      const member = members[m];
      member._scene.updateWorldMatrix(true, false);
      decompose(member._scene.matrixWorld, roots, m * FLOATS);
      const parts = member._in;
      const a = member._animated;
      const wrote = member._wrote;
      const check = member._hasWritten;
      for (let r = 0, at = 0; at < R; r++, at += FLOATS) {
        const k = readWritten[r];
        if (!(check && k >= 0 && parts.holds(r, wrote, k * FLOATS))) parts.read(r, a, at);
      }
      locals.set(a, m * R);
    }
    const x = this._tassel.x;
    const [rp, lp, op] = this._buffers;
    const code = x.tassel_crowd_frame(this._ptr, rp[0], count * FLOATS, lp[0], count * R, op[0], count * W, delta);
    const held = this._held;
    held.fill(0);
    if (code < 0) {
      this._failed(this._tassel.string(x.tassel_last_error()), null);
      return false;
    }
    if (code === 1) {
      const list = indices(this._tassel, x.tassel_crowd_held_count(this._ptr), (p, c) => x.tassel_crowd_held(this._ptr, p, c), 'held');
      this._failed(this._tassel.string(x.tassel_last_error()), list);
      for (const i of list) held[i] = 1;
    } else {
      this.lastError = null;
    }
    // Made again if the frame grew the module's memory (which detaches the old views).
    const out = this._viewsNow()[2];
    const syncRotation = this._syncRotation;
    const world = this._worldMatrices;
    const writtenAt = this._writtenAt;
    for (let m = 0; m < count; m++) {
      const member = members[m];
      if (held[m] === 1) continue;
      member.lastError = null;
      const base = m * W;
      member._wrote.set(out.subarray(base, base + W));
      // The crowd's kinds (VRM springs, chains) turn joints only.
      writeBones(member._out, member._plan, out, base, writtenAt, syncRotation, world, true);
      member._hasWritten = true;
    }
    return code === 0;
  }

  _failed(message, list) {
    const who = list === null ? this._members : list.map((i) => this._members[i]);
    for (const m of who) m.lastError = message;
    if (message !== this.lastError) {
      this.lastError = message;
      if (this._onError) this._onError(message);
      else console.warn(`tassel-three: ${message} (those bones keep their animated pose)`);
    }
  }

  _remove(member) {
    const i = this._members.indexOf(member);
    if (i < 0) return;
    if (this._tassel.x.tassel_crowd_remove(this._ptr, i) !== 0) throw this._tassel.error('remove');
    const last = this._members.pop();
    if (last !== member) {
      this._members[i] = last;
      last._index = i;
    }
    member._crowd = null;
  }

  /** Frees the module's memory for the crowd (its members leave it). */
  dispose() {
    if (!this._ptr) return;
    const x = this._tassel.x;
    x.tassel_crowd_free(this._ptr);
    x.tassel_character_free(this._kind);
    if (this._buffers) for (const b of this._buffers) this._tassel.free(b);
    for (const m of this._members) m._crowd = null;
    this._members = [];
    this._ptr = 0;
  }
}

/** One character of a TasselCrowd. It can stand in for three-vrm's spring-bone manager
 *  (`vrm.springBoneManager = member`): its `update` does nothing, the crowd's steps it. */
export class TasselCrowdMember {
  constructor(crowd, scene, objects, index) {
    this._crowd = crowd;
    this._scene = scene;
    this._index = index;
    this._objects = objects;
    this._in = new BoneParts(objects, crowd._read);
    this._out = new BoneParts(objects, crowd._written);
    this._plan = writePlan(this._out, crowd._order, scene, crowd._worldMatrices);
    this._animated = new Float32Array(crowd._read.length * FLOATS);
    crowd._read.forEach((j, r) => this._animated.set(crowd._rest.subarray(j * FLOATS, (j + 1) * FLOATS), r * FLOATS));
    this._wrote = new Float32Array(crowd._written.length * FLOATS);
    this._hasWritten = false;
    this.lastError = null;
    this._capture();
  }

  /** `fixed`, `spec`, `three-vrm`, `classic`, `kawaii` or `spcr`. */
  get mode() { return this._crowd?.mode ?? null; }
  /** The three.js objects Tassel writes (the simulated bones). */
  get bones() { return this._out.object.filter((o) => o !== null && o !== undefined); }
  /** Its place in the crowd (changes when a member before it is removed). */
  get index() { return this._index; }

  _capture() {
    for (let r = 0; r < this._in.p.length; r++) this._in.read(r, this._animated, r * FLOATS);
    this._hasWritten = false;
  }

  /** Does nothing: the crowd's update steps every member (so that three-vrm's
   *  `vrm.update(delta)` can run with this member as its spring-bone manager). */
  update() { return true; }

  /** The simulated bones go back to their animated pose and start again from it. */
  reset() {
    const crowd = this._crowd;
    if (!crowd) return;
    // The written joints' animated pose (their rest pose for joints the solvers do not read).
    const wr = crowd._writtenRead;
    const pose = new Float32Array(wr.length * FLOATS);
    for (let k = 0; k < wr.length; k++) {
      const j = crowd._written[k];
      pose.set(wr[k] >= 0 ? this._animated.subarray(wr[k] * FLOATS, (wr[k] + 1) * FLOATS) : crowd._rest.subarray(j * FLOATS, (j + 1) * FLOATS), k * FLOATS);
    }
    this._scene.updateWorldMatrix(true, false);
    writeBones(this._out, this._plan, pose, 0, crowd._writtenAt, crowd._syncRotation, crowd._worldMatrices);
    this._hasWritten = false;
    crowd._tassel.x.tassel_crowd_reset(crowd._ptr, this._index);
  }

  /** The bones' current pose becomes the pose the simulation starts from. */
  setInitState() {
    const crowd = this._crowd;
    if (!crowd) return;
    this._capture();
    crowd._tassel.x.tassel_crowd_reset(crowd._ptr, this._index);
  }

  /** The character was moved on purpose: start again at the new place, no whip. */
  teleport() {
    const crowd = this._crowd;
    if (crowd) crowd._tassel.x.tassel_crowd_reset(crowd._ptr, this._index);
  }

  /** Leaves the crowd (the last member takes its place). */
  dispose() {
    this._crowd?._remove(this);
  }
}
