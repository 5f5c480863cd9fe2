// The side-by-side benchmark of three-vrm's spring update and Tassel's (WebAssembly), in
// one JavaScript process (Node: bench.mjs; Chromium: index.html): N characters of the
// 16 x 8-joint rig with 8 colliders (rig.mjs), or of `ctx.bytes` (the user's file in
// Node, Tassel's built-in avatar in either), swaying on their roots; per frame, every
// character's manager.update(1/60), or one TasselCrowd.update(1/60) for all — Tassel's
// including the transfer of transforms from and to the three.js objects. Runs are
// interleaved (three-vrm, Tassel three-vrm mode, Tassel fixed, the crowd in both, again...)
// and each figure is the median over runs (11 runs of 400/√N frames for N characters by
// default: runs of a few milliseconds moved the medians by a fifth on a shared machine),
// in ns per joint-step (a joint-step: one simulated joint in one update).
import { CHAINS, JOINTS_PER_CHAIN, springRigGlb } from './rig.mjs';

const RIG_JOINTS = CHAINS * JOINTS_PER_CHAIN;

// What is measured: three-vrm's manager per character; Tassel's manager per character
// (one WebAssembly call each); Tassel's crowd (one call a frame for all characters); the
// crowd leaving matrixWorld to the renderer (`worldMatrices: false`); and the crowd's
// WebAssembly step alone, without the transfer (its frame call on the buffers the last
// update filled: what the transfer to and from three.js adds is the difference).
const KINDS = {
  'three-vrm 3.5.5': { mode: null, crowd: false },
  'Tassel three-vrm': { mode: 'three-vrm', crowd: false },
  'Tassel fixed': { mode: 'fixed', crowd: false },
  'crowd three-vrm': { mode: 'three-vrm', crowd: true },
  'crowd fixed': { mode: 'fixed', crowd: true },
  'crowd three-vrm, no matrixWorld': { mode: 'three-vrm', crowd: true, options: { worldMatrices: false } },
  'crowd three-vrm, step alone': { mode: 'three-vrm', crowd: true, stepAlone: true },
};

/** The crowd's WebAssembly frame alone (the buffers as its last update left them). This
 *  reaches into TasselCrowd's private fields: a measurement, not an API. */
function stepAlone(crowd, dt) {
  const [rp, lp, op] = crowd._buffers;
  const n = crowd.size;
  const code = crowd._tassel.x.tassel_crowd_frame(crowd._ptr, rp[0], n * 10, lp[0], n * crowd._read.length * 10,
    op[0], n * crowd._written.length * 10, dt);
  if (code !== 0) throw new Error(`the crowd's frame failed (${code})`);
}

async function characters(kind, n, ctx) {
  const { mode, crowd: inCrowd, options = {}, stepAlone: alone = false } = KINDS[kind];
  const bytes = ctx.bytes ?? springRigGlb();
  const crowd = inCrowd ? await ctx.TasselCrowd.fromBytes(bytes, { mode, ...options }) : null;
  const chars = [];
  for (let i = 0; i < n; i++) {
    const { gltf, manager } = await ctx.loadGltfBytes(bytes);
    let m = manager;
    if (crowd) m = crowd.add(gltf);
    else if (mode) m = await ctx.TasselSpringBoneManager.fromGLTF(gltf, bytes, { mode });
    gltf.scene.position.set(i * 0.7, 0, 0);
    gltf.scene.updateMatrixWorld(true);
    chars.push({ scene: gltf.scene, manager: m, x: i * 0.7 });
  }
  // The step alone steps from the pose of one real update.
  if (alone) crowd.update(1 / 60);
  return { chars, crowd, alone };
}

function run(set, frames, dt, t0) {
  const { chars, crowd, alone } = set;
  const start = performance.now();
  if (alone) {
    for (let f = 0; f < frames; f++) stepAlone(crowd, dt);
    return performance.now() - start;
  }
  for (let f = 0; f < frames; f++) {
    const t = t0 + f * dt;
    for (const c of chars) {
      c.scene.position.x = c.x + 0.3 * Math.sin(2 * Math.PI * t);
      c.scene.updateMatrix();
      if (!crowd) c.manager.update(dt);
    }
    if (crowd) crowd.update(dt);
  }
  return performance.now() - start;
}

function median(v) {
  const s = [...v].sort((a, b) => a - b);
  return s[s.length >> 1];
}

export async function runBench({ counts = [1, 100], frames = 400, runs = 11, log = console.log, ...ctx }) {
  const kinds = Object.keys(KINDS);
  const results = [];
  // Per joint: the spring joints three-vrm's manager steps (the rig's 128 by construction).
  let JOINTS = RIG_JOINTS;
  if (ctx.bytes) {
    const { manager } = await ctx.loadGltfBytes(ctx.bytes);
    JOINTS = manager?.joints?.size ?? 0;
    if (!JOINTS) throw new Error('the file has no VRM spring joints');
  }
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
    const base = row['three-vrm 3.5.5'];
    row.speedup = Object.fromEntries(kinds.slice(1).map((k) => [k, base / row[k]]));
    log(`${n} x ${JOINTS} joints: three-vrm ${base.toFixed(1)} ns/joint; ` + kinds.slice(1).map((k) => `${k} ${row[k].toFixed(1)} (${row.speedup[k].toFixed(1)}x)`).join(', '));
    results.push(row);
    for (const k of kinds) {
      for (const c of sets[k].chars) if (!sets[k].crowd) c.manager.dispose?.();
      sets[k].crowd?.dispose();
    }
  }
  return results;
}
