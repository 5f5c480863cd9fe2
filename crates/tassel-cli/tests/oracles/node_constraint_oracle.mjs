#!/usr/bin/env node
// Node-constraint reference for tests/vrm_parity.rs: @pixiv/three-vrm-node-constraint run
// headless on a glTF whose buffers are data URIs. The test copies this file next to the
// three-vrm install (target/oracles) so that the packages resolve.
//
//   node node_constraint_oracle.mjs FILE --frames N --dt S --out OUT.json
//
// Each frame f = 1..N (t = f·dt) sets node 0's and node 1's local rotation to their rest
// rotation times the test's motion (below, the same as in the Rust test), calls
// `manager.update()` and then `updateMatrixWorld` (as an app's render would), and records
// every node's world position and world quaternion.
import fs from 'node:fs';
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { VRMNodeConstraintLoaderPlugin } from '@pixiv/three-vrm-node-constraint';

if (typeof globalThis.ProgressEvent === 'undefined') {
  globalThis.ProgressEvent = class ProgressEvent extends Event {
    constructor(type, init = {}) { super(type); Object.assign(this, init); }
  };
}

const args = process.argv.slice(2);
const file = args[0];
const opt = (k, d) => { const i = args.indexOf(k); return i >= 0 ? args[i + 1] : d; };
const frames = Number(opt('--frames', '60'));
const dt = Number(opt('--dt', String(1 / 60)));
const out = opt('--out');

// The motion: node 1 turns about a skewed axis and twists about Y; node 0 rocks about Z.
const axis = new THREE.Vector3(1, 2, 3).normalize();
const motion1 = (t) => new THREE.Quaternion().setFromAxisAngle(axis, 0.8 * Math.sin(2 * Math.PI * 0.7 * t))
  .multiply(new THREE.Quaternion().setFromAxisAngle(new THREE.Vector3(0, 1, 0), 0.5 * Math.sin(2 * Math.PI * 1.3 * t)));
const motion0 = (t) => new THREE.Quaternion().setFromAxisAngle(new THREE.Vector3(0, 0, 1), 0.3 * Math.sin(2 * Math.PI * 0.5 * t));

const text = fs.readFileSync(file, 'utf8');
const loader = new GLTFLoader();
loader.register((parser) => new VRMNodeConstraintLoaderPlugin(parser));
const gltf = await new Promise((res, rej) => loader.parse(text, '', res, rej));
const manager = gltf.userData.vrmNodeConstraintManager;
if (!manager) throw new Error('no node constraints in ' + file);
const nodes = await gltf.parser.getDependencies('node');
const rest = nodes.map((n) => n.quaternion.clone());
const samples = [];
const v = new THREE.Vector3(), q = new THREE.Quaternion();
for (let f = 1; f <= frames; f++) {
  const t = f * dt;
  nodes[1].quaternion.copy(rest[1]).multiply(motion1(t));
  nodes[0].quaternion.copy(rest[0]).multiply(motion0(t));
  gltf.scene.updateMatrixWorld(true);
  manager.update();
  gltf.scene.updateMatrixWorld(true);
  const pos = [], quat = [];
  for (const n of nodes) {
    n.getWorldPosition(v); pos.push([v.x, v.y, v.z]);
    n.getWorldQuaternion(q); quat.push([q.x, q.y, q.z, q.w]);
  }
  samples.push({ frame: f, t, world_pos: pos, world_quat: quat });
}
const json = JSON.stringify({ constraints: manager.constraints.size, samples });
if (out) fs.writeFileSync(out, json); else process.stdout.write(json);
