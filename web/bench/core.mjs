// The side-by-side benchmark of three-vrm's spring update and Tassel's (WebAssembly), in
// one JavaScript process (Node: bench.mjs; Chromium: index.html): N characters of the
// 16 x 8-joint rig with 8 colliders (rig.mjs) swaying on their roots; per frame, every
// character's manager.update(1/60) — Tassel's including the transfer of transforms from
// and to the three.js objects. Runs are interleaved (three-vrm, Tassel three-vrm mode,
// Tassel fixed, again...) and each figure is the median over runs, in ns per joint-step
// (a joint-step: one simulated joint in one update).
import { CHAINS, JOINTS_PER_CHAIN, springRigGlb } from './rig.mjs';

const JOINTS = CHAINS * JOINTS_PER_CHAIN;

async function characters(kind, n, ctx) {
  const bytes = springRigGlb();
  const out = [];
  for (let i = 0; i < n; i++) {
    const { gltf, manager } = await ctx.loadGltfBytes(bytes);
    let m = manager;
    if (kind !== 'three-vrm 3.5.5') {
      m = await ctx.TasselSpringBoneManager.fromGLTF(gltf, bytes, { mode: kind === 'Tassel three-vrm' ? 'three-vrm' : 'fixed' });
    }
    gltf.scene.position.set(i * 0.7, 0, 0);
    gltf.scene.updateMatrixWorld(true);
    out.push({ scene: gltf.scene, manager: m, x: i * 0.7 });
  }
  return out;
}

function run(chars, frames, dt, t0) {
  const start = performance.now();
  for (let f = 0; f < frames; f++) {
    const t = t0 + f * dt;
    for (const c of chars) {
      c.scene.position.x = c.x + 0.3 * Math.sin(2 * Math.PI * t);
      c.scene.updateMatrix();
      c.manager.update(dt);
    }
  }
  return performance.now() - start;
}

function median(v) {
  const s = [...v].sort((a, b) => a - b);
  return s[s.length >> 1];
}

export async function runBench({ counts = [1, 100], frames = 200, runs = 7, log = console.log, ...ctx }) {
  const kinds = ['three-vrm 3.5.5', 'Tassel three-vrm', 'Tassel fixed'];
  const results = [];
  for (const n of counts) {
    const sets = {};
    for (const k of kinds) sets[k] = await characters(k, n, ctx);
    const steps = Math.max(20, Math.round(frames / Math.sqrt(n)));
    const times = Object.fromEntries(kinds.map((k) => [k, []]));
    // Warm up for a second each: the JavaScript JIT and WebAssembly's tier-up (V8 starts
    // a module in its baseline compiler, Liftoff, and optimises hot functions later).
    for (const k of kinds) {
      const until = performance.now() + 1000;
      while (performance.now() < until) run(sets[k], 10, 1 / 60, 0);
    }
    for (let r = 0; r < runs; r++) {
      for (const k of kinds) {
        const ms = run(sets[k], steps, 1 / 60, (r + 1) * 10);
        times[k].push((ms * 1e6) / (steps * n * JOINTS));
      }
    }
    const row = { characters: n, joints: JOINTS };
    for (const k of kinds) row[k] = median(times[k]);
    row.speedup_three_vrm_mode = row['three-vrm 3.5.5'] / row['Tassel three-vrm'];
    row.speedup_fixed = row['three-vrm 3.5.5'] / row['Tassel fixed'];
    log(`${n} x ${JOINTS} joints: three-vrm ${row['three-vrm 3.5.5'].toFixed(1)} ns/joint, Tassel three-vrm mode ${row['Tassel three-vrm'].toFixed(1)} (${row.speedup_three_vrm_mode.toFixed(1)}x), Tassel fixed ${row['Tassel fixed'].toFixed(1)} (${row.speedup_fixed.toFixed(1)}x)`);
    results.push(row);
    for (const k of kinds) for (const c of sets[k]) c.manager.dispose?.();
  }
  return results;
}
