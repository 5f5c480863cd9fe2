// A/B of two builds of the module in one Node process, for changes to the transfer code:
// copy one build's index.js to dist/index_b.js (beside dist/index.js and its wasm), then
// `node web/bench/ab.mjs [COUNT] [MODE]` (default 100 copies of the built-in avatar in a
// TasselCrowd, `three-vrm` mode). Runs alternate; medians of 9 runs of 300 frames. The
// build made second starts with a few per cent of advantage on a busy machine: run both
// orders (swap the two files) before believing a small difference.
import * as A from '../dist/index.js';
import * as B from '../dist/index_b.js';
import { loadGltfBytes } from '../test/gltf.mjs';
import '../test/load.mjs';

const n = Number(process.argv[2] ?? 100);
const mode = process.argv[3] ?? 'three-vrm';
const bytes = await A.builtinAvatar();
const joints = 44;

async function make(M) {
  const crowd = await M.TasselCrowd.fromBytes(bytes, { mode });
  const chars = [];
  for (let i = 0; i < n; i++) {
    const { gltf } = await loadGltfBytes(bytes);
    crowd.add(gltf);
    gltf.scene.position.set(i * 0.7, 0, 0);
    gltf.scene.updateMatrixWorld(true);
    chars.push({ scene: gltf.scene, x: i * 0.7 });
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
    }
    s.crowd.update(1 / 60);
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
console.log(`${n} copies, ${mode}: A (index.js) ${med(ta).toFixed(1)} ns, B (index_b.js) ${med(tb).toFixed(1)} ns per joint-step (B/A ${(med(tb) / med(ta)).toFixed(3)})`);
