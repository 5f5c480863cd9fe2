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
const failures = await runParity({ files, hook, loadGltfBytes, TasselSpringBoneManager, THREE, log: console.log })
  + await runCrowdParity({ files, loadGltfBytes, TasselSpringBoneManager, TasselCrowd, log: console.log });
console.log(failures ? `node parity: ${failures} FAILED` : `node parity: all passed (${files.length} files)`);
process.exit(failures ? 1 : 0);
