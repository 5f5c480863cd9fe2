// TasselCrowd against TasselSpringBoneManager, its reference (which test/parity.mjs holds
// to three-vrm): for each VRM file and mode, COPIES loaded copies stepped by one crowd and
// COPIES more stepped by one manager each (reset before their first update: a crowd member
// starts from its pose), every copy swaying with its own phase. Every written bone's
// quaternion and world matrix must be the same numbers every frame, in both modes (as
// natively, crates/tassel-ffi/tests/crowd.rs; while one character's springs ran in eight
// lanes in WebAssembly, three of the seven files differed in fixed mode by an ulp or two
// from frame 3 on; in four lanes, `lanes/narrow.rs`, they agree) — through a hitch, a
// member's NaN (held: the crowd's update returns false, that member's bones untouched,
// the others step), a member's reset and a member leaving the crowd.

const COPIES = 3;
const FRAMES = 90;
const DT = 1 / 60;

function sway(scene, base, i, f) {
  const t = f * DT;
  scene.position.copy(base);
  scene.position.x += i + 0.3 * Math.sin(2 * Math.PI * t + i);
  scene.position.y += 0.1 * Math.cos(5 * t);
  scene.rotation.y = 0.2 * Math.sin(3 * t + i);
  scene.updateMatrix();
}

async function compareCrowd(ctx, name, bytes, mode) {
  const { loadGltfBytes, TasselSpringBoneManager, TasselCrowd, check } = ctx;
  const crowd = await TasselCrowd.fromBytes(bytes, { mode, onError: () => {} });
  check(crowd.kind === 'vrm', `${name}: a VRM file's crowd runs on the VRM crowd path (${crowd.kind})`);
  const pairs = [];
  for (let i = 0; i < COPIES; i++) {
    const a = await loadGltfBytes(bytes);
    const b = await loadGltfBytes(bytes);
    const member = crowd.add(a.gltf);
    const manager = await TasselSpringBoneManager.fromGLTF(b.gltf, b.data, { mode, onError: () => {} });
    manager.reset();
    // The manager's object of each node.
    const objectOf = new Map();
    b.gltf.scene.traverse((o) => {
      const n = b.gltf.parser.associations.get(o)?.nodes;
      if (n !== undefined && !objectOf.has(n)) objectOf.set(n, o);
    });
    const twin = (o) => objectOf.get(a.gltf.parser.associations.get(o)?.nodes);
    pairs.push({ i, member, manager, twin, a: a.gltf.scene, b: b.gltf.scene, base: a.gltf.scene.position.clone() });
  }
  let compared = 0;
  let mismatches = 0;
  for (let f = 1; f <= FRAMES; f++) {
    const dt = f === 30 ? 0.25 : DT;
    if (f === 50) {
      pairs[2].member.reset();
      pairs[2].manager.reset();
    }
    if (f === 70) {
      // The first member leaves; the last takes its place.
      pairs[0].member.dispose();
      pairs[0].manager.dispose();
      pairs.shift();
      check(crowd.size === COPIES - 1, `${name}: a member left the crowd`);
    }
    for (const p of pairs) {
      sway(p.a, p.base, p.i, f);
      sway(p.b, p.base, p.i, f);
    }
    // Frame 40: a NaN in the second copy's first written bone's parent (both sides).
    const bad = f === 40 ? pairs[1] : null;
    const before = bad ? bad.member.bones.map((o) => o.quaternion.toArray()) : null;
    const keep = [];
    if (bad) {
      const victim = bad.member.bones[0].parent;
      for (const o of [victim, bad.twin(victim)]) {
        keep.push([o, o.position.x]);
        o.position.x = NaN;
      }
    }
    const all = crowd.update(dt);
    check(all === (bad === null), `${name} ${mode} frame ${f}: the crowd's update gave ${all}`);
    for (const p of pairs) {
      const stepped = p.manager.update(dt);
      if (p === bad) {
        check(!stepped, `${name}: the manager refuses the NaN`);
        check(p.member.lastError && /not finite/.test(p.member.lastError), `${name}: the held member says why (${p.member.lastError})`);
        check(p.member.bones.every((o, k) => o.quaternion.toArray().every((v, c) => v === before[k][c])), `${name}: a held member's bones were written`);
        continue;
      }
      check(p.member.lastError === null, `${name} ${mode} frame ${f}: member ${p.i}: ${p.member.lastError}`);
      const ma = p.member.bones;
      check(ma.length === p.manager.bones.length, `${name}: the member writes ${ma.length} bones, the manager ${p.manager.bones.length}`);
      for (let k = 0; k < ma.length; k++) {
        const mbk = p.twin(ma[k]);
        const qa = ma[k].quaternion, qb = mbk.quaternion;
        const wa = ma[k].matrixWorld.elements, wb = mbk.matrixWorld.elements;
        const same = qa.x === qb.x && qa.y === qb.y && qa.z === qb.z && qa.w === qb.w && wa.every((v, c) => v === wb[c]);
        compared++;
        if (!same) {
          if (mismatches++ < 3) check(false, `${name} ${mode} frame ${f} copy ${p.i} bone ${ma[k].name}: crowd ${qa.toArray()} manager ${qb.toArray()}`);
        }
      }
    }
    for (const [victim, x] of keep) victim.position.x = x;
  }
  check(mismatches === 0, `${name} ${mode}: ${mismatches} of ${compared} bone-frames differ`);
  for (const p of pairs) p.manager.dispose();
  crowd.dispose();
  return compared;
}

/** `worldMatrices: false` against the default: the same local transforms bit for bit every
 *  frame (the simulation never reads matrixWorld), the written bones' matrixWorld left as
 *  it was by update, and three.js's own scene.updateMatrixWorld() (what the renderer runs)
 *  then gives what the default wrote (to float rounding: three.js multiplies the whole
 *  4x4, the layer skips the local matrix's constant last row). */
async function compareWorldMatrices(ctx, name, bytes) {
  const { loadGltfBytes, TasselCrowd, check } = ctx;
  const a = await loadGltfBytes(bytes);
  const b = await loadGltfBytes(bytes);
  const full = await TasselCrowd.fromBytes(bytes, { mode: 'three-vrm' });
  const lean = await TasselCrowd.fromBytes(bytes, { mode: 'three-vrm', worldMatrices: false });
  const ma = full.add(a.gltf), mb = lean.add(b.gltf);
  const base = a.gltf.scene.position.clone();
  let compared = 0;
  let worst = 0;
  for (let f = 1; f <= 40; f++) {
    sway(a.gltf.scene, base, 0, f);
    sway(b.gltf.scene, base, 0, f);
    const before = mb.bones.map((o) => [...o.matrixWorld.elements]);
    check(full.update(DT) && lean.update(DT), `${name}: worldMatrices: both crowds step`);
    const ba = ma.bones, bb = mb.bones;
    check(ba.length === bb.length && ba.length > 0, `${name}: worldMatrices: ${ba.length} and ${bb.length} bones`);
    for (let k = 0; k < ba.length; k++) {
      const qa = ba[k].quaternion, qb = bb[k].quaternion;
      check(qa.equals(qb) && ba[k].matrix.elements.every((v, c) => v === bb[k].matrix.elements[c]),
        `${name} frame ${f} bone ${ba[k].name}: worldMatrices: false changed the local transform`);
      check(bb[k].matrixWorld.elements.every((v, c) => v === before[k][c]), `${name} frame ${f} bone ${bb[k].name}: worldMatrices: false wrote matrixWorld`);
    }
    b.gltf.scene.updateMatrixWorld(true);
    for (let k = 0; k < ba.length; k++) {
      const wa = ba[k].matrixWorld.elements, wb = bb[k].matrixWorld.elements;
      for (let c = 0; c < 16; c++) worst = Math.max(worst, Math.abs(wa[c] - wb[c]));
      compared++;
    }
  }
  check(worst <= 1e-6, `${name}: worldMatrices: false then scene.updateMatrixWorld() is ${worst} from what update wrote`);
  full.dispose();
  lean.dispose();
  return { compared, worst };
}

/** Every file (`{ name, bytes }`) in fixed and three-vrm mode. Returns the failures. */
export async function runCrowdParity({ files, loadGltfBytes, TasselSpringBoneManager, TasselCrowd, log }) {
  let failures = 0;
  const check = (ok, what) => {
    if (!ok) {
      log(`FAIL crowd: ${what}`);
      failures++;
    }
  };
  const ctx = { loadGltfBytes, TasselSpringBoneManager, TasselCrowd, check };
  if (files.length > 0) {
    const { name, bytes } = files[0];
    const { compared, worst } = await compareWorldMatrices(ctx, name, bytes);
    log(`crowd ${name} worldMatrices: false: local transforms bit for bit, matrixWorld untouched; after scene.updateMatrixWorld() ${compared} bone-frames within ${worst.toExponential(1)} of update's`);
  }
  for (const { name, bytes } of files) {
    for (const mode of ['fixed', 'three-vrm']) {
      const compared = await compareCrowd(ctx, name, bytes, mode);
      log(`crowd ${name} ${mode}: ${COPIES} members against their managers, ${compared} bone-frames: bit for bit`);
    }
  }
  return failures;
}
