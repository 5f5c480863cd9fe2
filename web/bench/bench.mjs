// `npm run bench --prefix web [-- FILE|avatar]` (or `node bench/bench.mjs [FILE|avatar]
// [FRAMES] [RUNS] [COUNTS]`, COUNTS like 1,10,100): three-vrm's spring update against
// Tassel's in Node, side by side in this process (see core.mjs), on the bench rig, on FILE
// (a .vrm, or a glTF with VRMC_springBone) or on Tassel's built-in avatar (`avatar`: a
// VRM 1.0 character with a skinned body, 83 nodes, 44 spring joints, 6 colliders; counts
// 1, 10 and 100 unless given).
import fs from 'node:fs';
import { TasselSpringBoneManager, TasselCrowd, builtinAvatar } from '../dist/index.js';
import { loadGltfBytes, THREE } from '../test/gltf.mjs';
import '../test/load.mjs';
import { runBench } from './core.mjs';

const args = process.argv.slice(2);
const file = args.length && !/^[0-9,]+$/.test(args[0]) ? args.shift() : null;
const frames = Number(args[0] ?? 400);
const runs = Number(args[1] ?? 11);
const counts = (args[2] ?? (file === 'avatar' ? '1,10,100' : '1,100')).split(',').map(Number);
let bytes;
if (file === 'avatar') {
  bytes = await builtinAvatar();
} else if (file) {
  try {
    bytes = new Uint8Array(fs.readFileSync(file));
  } catch (e) {
    console.error(`${file}: ${e.message}`);
    process.exit(1);
  }
}
console.log(`Node ${process.version}, three r${THREE.REVISION}${file === 'avatar' ? ', the built-in avatar' : file ? `, ${file}` : ', the bench rig'}`);
await runBench({ counts, frames, runs, bytes, loadGltfBytes, TasselSpringBoneManager, TasselCrowd, THREE });
