// Managers of one file share its compiled rig (Tassel.character, tassel_character_copy):
// a shared manager steps bit for bit as one loaded on its own (`shareRig: false`), also
// when it is made after another of its kind stepped; equal bytes in another array share,
// other bytes or another mode do not; the template goes with the kind's last user. Runs
// on the built-in avatar and the bench rig (no ../shared needed).
import { springRigGlb } from '../bench/rig.mjs';

/** Every written bone's quaternion after one update of `m` at frame `f` (the scene swaying). */
function step(gltf, m, f) {
  gltf.scene.position.x = 0.3 * Math.sin((2 * Math.PI * f) / 60);
  gltf.scene.rotation.y = 0.4 * Math.sin((3 * Math.PI * f) / 60);
  gltf.scene.updateMatrix();
  if (!m.update(1 / 60)) throw new Error(`update failed: ${m.lastError}`);
  return m.bones.flatMap((b) => [b.quaternion.x, b.quaternion.y, b.quaternion.z, b.quaternion.w]);
}

export async function runShareRig({ loadGltfBytes, TasselSpringBoneManager, loadTassel, builtinAvatar, log }) {
  let bad = 0;
  const ok = (c, what) => { if (!c) { bad++; log(`FAILED: ${what}`); } };
  const tassel = await loadTassel();
  const bytes = await builtinAvatar();
  const other = springRigGlb();
  // The kinds of this test's files (other tests' managers may hold kinds of their own).
  const same = (x, y) => x.length === y.length && x.every((v, i) => v === y[i]);
  const kinds = () => [...tassel.kinds.values()].flat().filter((k) => same(k.data, bytes) || same(k.data, other));
  ok(kinds().length === 0, `no kind of these files before the test: ${kinds().length}`);
  const make = async (data, options) => {
    const { gltf } = await loadGltfBytes(data);
    return { gltf, m: await TasselSpringBoneManager.fromGLTF(gltf, data, { mode: 'fixed', ...options }) };
  };
  const a = await make(bytes, {});
  const own = await make(bytes, { shareRig: false });
  ok(kinds().length === 1 && kinds()[0].users === 1, 'one kind, one user (the own one is not counted)');
  let first = null;
  let moved = 0;
  for (let f = 0; f < 30; f++) {
    const qa = step(a.gltf, a.m, f);
    const qo = step(own.gltf, own.m, f);
    ok(qa.every((v, i) => Object.is(v, qo[i])), `frame ${f}: the shared manager = one on its own`);
    first ??= qa;
    moved = Math.max(moved, ...qa.map((v, i) => Math.abs(v - first[i])));
  }
  ok(moved > 1e-3, `the motion turns the bones (${moved})`);
  // Made after `a` stepped: a fresh character, not a's state. Equal bytes in another array
  // share the kind.
  const b = await make(bytes.slice(), {});
  const fresh = await make(bytes, { shareRig: false });
  ok(kinds().length === 1 && kinds()[0].users === 2, `equal bytes share: ${kinds().map((k) => k.users)}`);
  a.m.dispose();
  ok(kinds().length === 1 && kinds()[0].users === 1, 'a disposed user leaves the kind to the others');
  for (let f = 0; f < 60; f++) {
    const qb = step(b.gltf, b.m, f);
    const qf = step(fresh.gltf, fresh.m, f);
    ok(qb.every((v, i) => Object.is(v, qf[i])), `frame ${f}: a later shared manager = a new one`);
  }
  // Other bytes, another mode: kinds of their own.
  const rig = await make(other, {});
  const spec = await make(bytes, { mode: 'spec' });
  ok(kinds().length === 3, `three kinds: ${kinds().length}`);
  for (const x of [b, rig, spec, own, fresh]) x.m.dispose();
  // A second dispose releases nothing more (the kind's count stays right).
  b.m.dispose();
  ok(kinds().length === 0, `every template freed with its last user: ${kinds().length} left`);
  log(bad ? `share: ${bad} failures` : 'share: managers of one file share its rig, bit for bit as their own');
  return bad;
}
