// tassel-three in Node against three-vrm 3.5.5 in the same process (see parity.mjs), and
// its crowd against its manager (crowd.mjs), on every VRM file of ../shared/testdata/vrm.
import fs from 'node:fs';
import path from 'node:path';
import { TasselSpringBoneManager, TasselCrowd, TasselCharacter, loadTassel, builtinAvatar } from '../dist/index.js';
import { loadGltfBytes } from './gltf.mjs';
import { vrmFiles, testdata, THREE } from './load.mjs';
import { runParity } from './parity.mjs';
import { runCrowdParity } from './crowd.mjs';
import { runShareRig } from './share.mjs';

const files = vrmFiles().map((f) => ({ name: path.basename(f), bytes: fs.readFileSync(f) }));
const hook = files.length
  ? (await import(path.resolve(testdata, '../oracles/hooks/fixed_bone_length.mjs'))).default
  : null;
let failures = await runParity({ files, hook, loadGltfBytes, TasselSpringBoneManager, THREE, log: console.log })
  + await runCrowdParity({ files, loadGltfBytes, TasselSpringBoneManager, TasselCrowd, log: console.log });
// Animation events through tassel_event: the game's own, Tassel's, and a bad one.
async function runEvents() {
  if (!files.length) return 0;
  const g = await loadGltfBytes(files[0].bytes);
  const m = await TasselSpringBoneManager.fromGLTF(g.gltf, g.data, { mode: 'fixed' });
  let bad = 0;
  const ok = (c, what) => { if (!c) { bad++; console.log(`FAILED: ${what}`); } };
  ok(m.event('footstep') === false, "a game's own event is not Tassel's");
  ok(m.event('tassel:reset_dynamics') === true, 'tassel:reset_dynamics acts');
  let thrown = null;
  try { m.event('tassel:enable_force nope'); } catch (e) { thrown = e.message; }
  ok(thrown !== null && thrown.includes("'nope'"), `an unknown force is an error naming it: ${thrown}`);
  ok(m.update(1 / 60), `an update after the events: ${m.lastError}`);
  // Timed settings overrides through tassel_start_settings_override: refused on a file
  // without chains; on a skinned glTF with a chain (RiggedSimple.glb's two bones), a handle, a bad scale refused by name, a stop answered while it acts and not
  // after it ended, the events.
  thrown = null;
  try { m.startSettingsOverride({ stiffness: 0.5 }); } catch (e) { thrown = e.message; }
  ok(thrown !== null && thrown.includes('no chains'), `no chains, no override: ${thrown}`);
  const rigged = fs.readFileSync(path.join(testdata, 'gltf/RiggedSimple.glb'));
  const r = await loadGltfBytes(rigged);
  const root = 'Bone';
  const c = await TasselCharacter.fromGLTF(r.gltf, r.data, `[[chain]]\nname = "hair"\nroot = "${root}"\n`);
  ok(c.update(1 / 60), `a chain on ${root}: ${c.lastError}`);
  const h = c.startSettingsOverride({ stiffness: 0.5 }, { duration: Infinity, blendIn: 0.1, chain: 'hair' });
  ok(Number.isInteger(h) && h > 0, `a settings override's handle: ${h}`);
  thrown = null;
  try { c.startSettingsOverride({ radius: -1 }); } catch (e) { thrown = e.message; }
  ok(thrown !== null && thrown.includes('radius'), `a negative scale is an error naming it: ${thrown}`);
  thrown = null;
  try { c.startSettingsOverride({}, { chain: 'tail' }); } catch (e) { thrown = e.message; }
  ok(thrown !== null && thrown.includes("'tail'"), `an unknown chain is an error naming it: ${thrown}`);
  ok(c.update(1 / 60), `an update with an override: ${c.lastError}`);
  ok(c.stopSettingsOverride(h, 0) === true, 'stopping an acting override');
  ok(c.update(1 / 60), `an update after the stop: ${c.lastError}`);
  ok(c.stopSettingsOverride(h, 0) === false, 'an ended override is no one\'s');
  ok(c.event('tassel:override slow stiffness=0.5 duration=1') === true, 'tassel:override acts');
  ok(c.event('tassel:stop_override slow') === true, 'tassel:stop_override acts');
  // Shared collision: a holder's collider group handed to the chain's character.
  const holder = await TasselCharacter.fromGLTF(r.gltf, r.data,
    '[[collider]]\nname = "ball"\nbone = "Bone"\nshape = "sphere"\nradius = 0.5\n\n'
    + '[[collider_group]]\nname = "prop"\ncolliders = ["ball"]\n');
  const cape = await TasselCharacter.fromGLTF(r.gltf, r.data,
    `[[chain]]\nname = "cape"\nroot = "${root}"\nuse_shared_collision = true\nradius = 0.1\n`);
  ok(holder.update(1 / 60), `the holder steps: ${holder.lastError}`);
  const shared = holder.sharedColliders('prop');
  ok(shared.length === 12 && shared[0] === 0 && Math.abs(shared[1] - 0.5) < 1e-6,
    `one sphere of radius 0.5: ${Array.from(shared)}`);
  cape.setSharedColliders(shared);
  ok(cape.update(1 / 60), `the cape steps with a shared collider: ${cape.lastError}`);
  thrown = null;
  try { holder.sharedColliders('sword'); } catch (e) { thrown = e.message; }
  ok(thrown !== null && thrown.includes("'sword'"), `an unknown group is an error naming it: ${thrown}`);
  const badKind = shared.slice();
  badKind[0] = 9;
  thrown = null;
  try { cape.setSharedColliders(badKind); } catch (e) { thrown = e.message; }
  ok(thrown !== null && thrown.includes('kind 9'), `a bad kind is an error naming it: ${thrown}`);
  cape.setSharedColliders(new Float32Array(0));
  ok(cape.update(1 / 60), `the cape steps after clearing: ${cape.lastError}`);
  holder.dispose();
  cape.dispose();
  c.dispose();
  m.dispose();
  console.log(bad ? 'events: FAILED' : 'events: tassel:reset_dynamics acts, a game event passes, a bad one throws; settings overrides start, stop and refuse a bad scale; shared colliders pass between characters');
  return bad;
}
failures += await runEvents();
// The objects between the written bones and the scene (the built-in avatar's hips,
// spine, chest, head, arm...: refreshed by the manager, not written): with the spine and
// the left arm animated every frame, every such object's matrixWorld after an update is
// what three's own scene.updateMatrixWorld(true) then makes of the same local transforms;
// an ancestor with matrixAutoUpdate off keeps the matrix the app gave it, as in three.
async function runAncestors() {
  const bytes = await builtinAvatar();
  const { gltf } = await loadGltfBytes(bytes);
  const m = await TasselSpringBoneManager.fromGLTF(gltf, bytes, { mode: 'fixed' });
  const named = (n) => gltf.scene.getObjectByName(n);
  const spine = named('spine'), arm = named('upper_arm_l'), hand = named('hand_l');
  let bad = 0, worst = 0, compared = 0;
  const ok = (c, what) => { if (!c) { bad++; console.log(`FAILED: ${what}`); } };
  ok(spine && arm && hand, 'the avatar has spine, upper_arm_l and hand_l');
  // What the manager answers for: the scene, the bones it writes and every object between
  // them (the rest of the tree is left to the renderer, as three-vrm leaves it).
  const objects = new Set([gltf.scene]);
  for (const b of m.bones) for (let o = b; o && !objects.has(o); o = o.parent) objects.add(o);
  ok(objects.size > m.bones.length + 5, `ancestors to refresh: ${objects.size - m.bones.length}`);
  for (let f = 0; f < 60; f++) {
    spine.quaternion.setFromAxisAngle(new THREE.Vector3(1, 0, 0), 0.4 * Math.sin(f / 9));
    arm.quaternion.setFromAxisAngle(new THREE.Vector3(0, 0, 1), 0.8 * Math.sin(f / 7));
    if (f === 59) {
      // The app takes the hand's matrix over (on the last frame: later frames would leave
      // its matrixWorld as three's updateWorldMatrix leaves an object whose matrix is not
      // updated automatically, which updateMatrixWorld(true) forces).
      hand.matrixAutoUpdate = false;
      hand.matrix.makeTranslation(0, -0.1, 0.02);
      hand.matrixWorldNeedsUpdate = true;
    }
    gltf.scene.position.x = 0.3 * Math.sin(f / 5);
    gltf.scene.updateMatrix();
    ok(m.update(1 / 60), `frame ${f}: ${m.lastError}`);
    const got = [...objects].map((o) => [...o.matrixWorld.elements]);
    const handMatrix = [...hand.matrix.elements];
    gltf.scene.updateMatrixWorld(true);
    [...objects].forEach((o, i) => {
      for (let c = 0; c < 16; c++) worst = Math.max(worst, Math.abs(got[i][c] - o.matrixWorld.elements[c]));
      compared++;
    });
    ok(hand.matrix.elements.every((v, c) => v === handMatrix[c]), `frame ${f}: the hand's own matrix was kept`);
  }
  ok(worst <= 1e-6, `every matrixWorld within 1e-6 of three's: ${worst}`);
  m.dispose();
  console.log(bad ? 'ancestors: FAILED' : `ancestors: ${compared} object-frames within ${worst.toExponential(1)} of three's updateMatrixWorld, the app's own matrix kept`);
  return bad;
}
failures += await runAncestors();
failures += await runShareRig({ loadGltfBytes, TasselSpringBoneManager, loadTassel, builtinAvatar, log: console.log });
console.log(failures ? `node parity: ${failures} FAILED` : `node parity: all passed (${files.length} files)`);
process.exit(failures ? 1 : 0);
