// The benchmark's character, made here: a plain glTF (GLB, nodes only) with a
// VRMC_springBone 1.0 rig of 16 chains of 8 joints (9 nodes each: 8 simulated joints and
// a tail) hanging in a ring from a head, and 8 sphere colliders on the head and the body.
export const CHAINS = 16;
export const JOINTS_PER_CHAIN = 8;
export const COLLIDERS = 8;

export function springRigGlb() {
  const nodes = [
    { name: 'hips', translation: [0, 1.0, 0], children: [1] },
    { name: 'head', translation: [0, 0.5, 0], children: [] },
  ];
  const colliders = [];
  for (let i = 0; i < COLLIDERS; i++) {
    const a = (i / COLLIDERS) * 2 * Math.PI;
    colliders.push({
      node: i < COLLIDERS / 2 ? 1 : 0,
      shape: { sphere: { offset: [0.12 * Math.cos(a), i < COLLIDERS / 2 ? -0.1 : 0.3, 0.12 * Math.sin(a)], radius: 0.06 } },
    });
  }
  const springs = [];
  for (let c = 0; c < CHAINS; c++) {
    const a = (c / CHAINS) * 2 * Math.PI;
    let parent = 1;
    const joints = [];
    for (let j = 0; j <= JOINTS_PER_CHAIN; j++) {
      const index = nodes.length;
      nodes.push({
        name: `hair_${c}_${j}`,
        translation: j === 0 ? [0.15 * Math.cos(a), 0, 0.15 * Math.sin(a)] : [0.01 * Math.cos(a), -0.05, 0.01 * Math.sin(a)],
        children: [],
      });
      nodes[parent].children.push(index);
      parent = index;
      joints.push({ node: index, hitRadius: 0.02, stiffness: 1.0, gravityPower: 0.5, gravityDir: [0, -1, 0], dragForce: 0.4 });
    }
    springs.push({ name: `hair_${c}`, joints, colliderGroups: [0] });
  }
  for (const n of nodes) if (!n.children.length) delete n.children;
  const json = {
    asset: { version: '2.0', generator: 'tassel-three bench' },
    extensionsUsed: ['VRMC_springBone'],
    scene: 0,
    scenes: [{ nodes: [0] }],
    nodes,
    extensions: {
      VRMC_springBone: {
        specVersion: '1.0',
        colliders,
        colliderGroups: [{ name: 'body', colliders: colliders.map((_, i) => i) }],
        springs,
      },
    },
  };
  const text = new TextEncoder().encode(JSON.stringify(json));
  const padded = (text.length + 3) & ~3;
  const out = new Uint8Array(20 + padded).fill(0x20);
  const dv = new DataView(out.buffer);
  out.set(new TextEncoder().encode('glTF'), 0);
  dv.setUint32(4, 2, true);
  dv.setUint32(8, out.length, true);
  dv.setUint32(12, padded, true);
  dv.setUint32(16, 0x4e4f534a, true);
  out.set(text, 20);
  return out;
}
