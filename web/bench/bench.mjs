// `npm run bench` (or `node bench/bench.mjs [FRAMES] [RUNS] [COUNTS]`, COUNTS like 1,100): three-vrm's spring update
// against Tassel's in Node, side by side in this process (see core.mjs).
import { TasselSpringBoneManager, TasselCrowd } from '../dist/index.js';
import { loadGltfBytes, THREE } from '../test/gltf.mjs';
import '../test/load.mjs';
import { runBench } from './core.mjs';

const frames = Number(process.argv[2] ?? 200);
const runs = Number(process.argv[3] ?? 7);
const counts = (process.argv[4] ?? '1,100').split(',').map(Number);
console.log(`Node ${process.version}, three r${THREE.REVISION}`);
await runBench({ counts, frames, runs, loadGltfBytes, TasselSpringBoneManager, TasselCrowd, THREE });
