// tassel-three in Node against three-vrm 3.5.5 in the same process (see parity.mjs), and
// its crowd against its manager (crowd.mjs), on every VRM file of ../shared/testdata/vrm.
import fs from 'node:fs';
import path from 'node:path';
import { TasselSpringBoneManager, TasselCrowd } from '../dist/index.js';
import { loadGltfBytes } from './gltf.mjs';
import { vrmFiles, testdata, THREE } from './load.mjs';
import { runParity } from './parity.mjs';
import { runCrowdParity } from './crowd.mjs';

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
  m.dispose();
  console.log(bad ? 'events: FAILED' : 'events: tassel:reset_dynamics acts, a game event passes, a bad one throws');
  return bad;
}
failures += await runEvents();
console.log(failures ? `node parity: ${failures} FAILED` : `node parity: all passed (${files.length} files)`);
process.exit(failures ? 1 : 0);
