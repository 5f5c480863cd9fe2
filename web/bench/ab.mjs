// A/B of two builds of the module in one Node process: copy one build's index.js to
// dist/index_b.js (beside dist/index.js and its wasm: a change to the transfer code), or
// give two folders each holding an index.js and its tassel.wasm (`AB_A=dir AB_B=dir`: a
// change to the Rust too), then `node web/bench/ab.mjs [COUNT] [MODE] [crowd|manager]`
// (default 100 copies of the built-in avatar in a TasselCrowd, `three-vrm` mode; `manager`:
// a TasselSpringBoneManager each). Runs alternate; medians of 9 runs of 300 frames. The
// build made second starts with a few per cent of advantage on a busy machine: run both
// orders (swap the two) before believing a small difference.
import path from 'node:path';
import { pathToFileURL } from 'node:url';

const from = (dir, fallback) => (dir ? pathToFileURL(path.resolve(dir, 'index.js')).href : fallback);
const A = await import(from(process.env.AB_A, '../dist/index.js'));
const B = await import(from(process.env.AB_B, '../dist/index_b.js'));
import { loadGltfBytes } from '../test/gltf.mjs';
import '../test/load.mjs';

const n = Number(process.argv[2] ?? 100);
const mode = process.argv[3] ?? 'three-vrm';
const managers = process.argv[4] === 'manager';
const bytes = await A.builtinAvatar();
const joints = 44;

async function make(M) {
  const crowd = managers ? null : await M.TasselCrowd.fromBytes(bytes, { mode });
  const chars = [];
  for (let i = 0; i < n; i++) {
    const { gltf } = await loadGltfBytes(bytes);
    const manager = managers ? await M.TasselSpringBoneManager.fromGLTF(gltf, bytes, { mode }) : crowd.add(gltf);
    gltf.scene.position.set(i * 0.7, 0, 0);
    gltf.scene.updateMatrixWorld(true);
    chars.push({ scene: gltf.scene, x: i * 0.7, manager });
  }
  return { crowd, chars, f: 0 };
}

function run(s, frames) {
  const t0 = performance.now();
  for (let k = 0; k < frames; k++, s.f++) {
    const t = s.f / 60;
    for (const c of s.chars) {
      c.scene.position.x = c.x + 0.3 * Math.sin(2 * Math.PI * t);
      c.scene.updateMatrix();
      if (managers) c.manager.update(1 / 60);
    }
    s.crowd?.update(1 / 60);
  }
  return ((performance.now() - t0) * 1e6) / (frames * n * joints);
}

const a = await make(A);
const b = await make(B);
for (let w = 0; w < 3; w++) {
  run(a, 100);
  run(b, 100);
}
const ta = [];
const tb = [];
for (let r = 0; r < 9; r++) {
  ta.push(run(a, 300));
  tb.push(run(b, 300));
}
const med = (v) => [...v].sort((x, y) => x - y)[v.length >> 1];
console.log(`${n} copies, ${mode}, ${managers ? 'managers' : 'a crowd'}: A (index.js) ${med(ta).toFixed(1)} ns, B (index_b.js) ${med(tb).toFixed(1)} ns per joint-step (B/A ${(med(tb) / med(ta)).toFixed(3)})`);
