//! The flat frame API: one character loaded from glTF/GLB/VRM bytes, stepped one frame at
//! a time over plain `f32` buffers. No glam or Tassel type crosses it, so the C ABI
//! ([`crate::abi`]) and the WebAssembly module are thin shells over this one type.

use std::path::Path;
use std::sync::Arc;
use tassel::crowd::{CrowdKind, VrmCrowd};
use tassel::dynamics::vrm::VrmSpringBones;
use tassel::dynamics::{RigSettings, SimMode};
use tassel::glam::{Quat, Vec3};
use tassel::{CharacterSim, Skeleton, Transform};

/// Floats per joint transform: translation x y z, rotation quaternion x y z w, scale
/// x y z.
pub const FLOATS_PER_JOINT: usize = 10;

/// Floats per shared collider ([`FlatCharacter::shared_colliders`]): the shape's kind (0
/// sphere, 1 capsule, 2 tapered capsule, 3 box, 4 plane), four parameters (sphere: radius,
/// inside 0 or 1; capsule: radius, length; tapered capsule: radius0, radius1, length; box:
/// half extents x y z; the rest 0), then the world translation x y z and rotation
/// quaternion x y z w.
pub const FLOATS_PER_COLLIDER: usize = 12;

/// The largest rig file taken (16 MiB, as `tassel simulate`).
pub const MAX_RIG_BYTES: usize = 16 << 20;

/// One character behind the flat API: its solvers ([`CharacterSim`]), and its joints in
/// the file's node order (every node of the file is a joint, numbered as `tassel
/// simulate` numbers nodes).
///
/// ```
/// use tassel_ffi::{FlatCharacter, FLOATS_PER_JOINT};
///
/// // The built-in character as a GLB and its rig as TOML (a real file works the same:
/// // its bytes, and its rig file's text).
/// let c = tassel::builtin::character();
/// let source = tassel_gltf::ExportSource::from_skeleton(&c.skeleton, tassel_gltf::BoneMesh::None);
/// let glb = tassel_gltf::export_glb(&source, &[]).map_err(|e| e.to_string())?;
/// let rig = c.rig.to_toml_string().map_err(|e| e.to_string())?;
/// let mut character = FlatCharacter::load(&glb, Some(&rig), None)?;
/// let n = character.joint_count();
/// let mut locals = vec![0.0; n * FLOATS_PER_JOINT];
/// character.rest_locals(&mut locals)?;
/// let root = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
/// // The animated pose in, the simulated one out (here in place).
/// character.frame(&root, &mut locals, 1.0 / 60.0)?;
/// assert!(locals.iter().all(|v| v.is_finite()));
/// # Ok::<(), String>(())
/// ```
#[derive(Debug, Clone)]
pub struct FlatCharacter {
    sim: CharacterSim,
    mode: SimMode,
    /// Joint (skeleton order) of each node.
    node_to_joint: Vec<usize>,
    /// Node of each joint.
    joint_to_node: Vec<usize>,
    /// The nodes a solver writes, ascending.
    written: Vec<usize>,
    /// The nodes whose animated transforms a frame depends on, ascending.
    read: Vec<usize>,
    /// The animated pose of the frame being read, skeleton order (no allocation per
    /// frame).
    animated: Vec<Transform>,
}

/// The nodes `sim`'s frame reads (see [`FlatCharacter::read_joints`]), ascending: the
/// VRM crowd's input joints where the character could run on that crowd (the same plan
/// of the same springs), else every node.
fn read_nodes(sim: &CharacterSim, joint_to_node: &[usize]) -> Vec<usize> {
    let rig = sim.rig();
    let every = || (0..joint_to_node.len()).collect::<Vec<usize>>();
    let joints = match CrowdKind::of(rig) {
        Some(CrowdKind::Vrm) => {
            match VrmCrowd::new(
                Arc::new(rig.skeleton().clone()),
                Arc::new(rig.vrm().clone()),
            ) {
                Ok(crowd) => crowd.input_joints().to_vec(),
                Err(_) => return every(),
            }
        }
        _ => return every(),
    };
    let mut nodes: Vec<usize> = joints.iter().map(|&j| joint_to_node[j]).collect();
    nodes.sort_unstable();
    nodes
}

/// The largest springs JSON taken (16 MiB, as a rig file).
pub const MAX_SPRINGS_JSON_BYTES: usize = 16 << 20;

/// VRM spring bones from JSON text with node indices into the caller's joint list (see
/// [`FlatCharacter::from_skeleton`]), read by the file loader's own reader on a glTF
/// document made of the joints (names, children in list order, rest translations) and the
/// extension.
fn springs_from_json(
    text: &str,
    names: &[&str],
    parents: &[i64],
    rest: &[f32],
    node_to_joint: &[usize],
) -> Result<VrmSpringBones, String> {
    use serde_json::{json, Value};
    if text.len() > MAX_SPRINGS_JSON_BYTES {
        return Err(format!(
            "the springs JSON is larger than the limit of {MAX_SPRINGS_JSON_BYTES} bytes"
        ));
    }
    let ext: Value = serde_json::from_str(text).map_err(|e| format!("springs JSON: {e}"))?;
    let Some(obj) = ext.as_object() else {
        return Err("springs JSON: not an object".into());
    };
    let extensions = if obj.contains_key("springs") || obj.contains_key("specVersion") {
        json!({ "VRMC_springBone": ext })
    } else if obj.contains_key("boneGroups") {
        json!({ "VRM": { "secondaryAnimation": ext } })
    } else {
        return Err(
            "springs JSON: neither a VRMC_springBone object (springs, specVersion) \
                    nor VRM 0.x's secondaryAnimation (boneGroups)"
                .into(),
        );
    };
    let n = names.len();
    let mut children = vec![Vec::new(); n];
    for (j, &p) in parents.iter().enumerate() {
        if p >= 0 {
            children[p as usize].push(j);
        }
    }
    let nodes: Vec<Value> = (0..n)
        .map(|j| {
            let t = &rest[j * FLOATS_PER_JOINT..j * FLOATS_PER_JOINT + 3];
            json!({ "name": names[j], "children": children[j], "translation": t })
        })
        .collect();
    let doc = json!({ "nodes": nodes, "extensions": extensions });
    let mut warnings = Vec::new();
    let info = tassel_gltf::read_spring_bones(&doc, node_to_joint, &mut warnings)
        .map_err(|e| e.to_string().replace("<json>: ", ""))?;
    Ok(info.map(|i| i.springs).unwrap_or_default())
}

/// `"fixed"`, `"spec"`, `"three-vrm"`, `"classic"`, `"kawaii"` or `"spcr"` (as `tassel simulate
/// --mode`).
pub fn parse_mode(name: &str) -> Result<SimMode, String> {
    [
        SimMode::Fixed,
        SimMode::Spec,
        SimMode::ThreeVrm,
        SimMode::Classic,
        SimMode::Kawaii,
        SimMode::Spcr,
    ]
    .into_iter()
    .find(|m| m.name() == name)
    .ok_or_else(|| {
        format!("mode '{name}' is not one of fixed, spec, three-vrm, classic, kawaii, spcr (as tassel simulate --mode)")
    })
}

impl FlatCharacter {
    /// A character from the bytes of a GLB, VRM or glTF file (a `.gltf` whose buffers are
    /// external files is an error naming the URI: memory reads no files; see
    /// [`load_file`](Self::load_file)), an optional rig file's text (chains, springs,
    /// cloths, ropes; optional for a VRM, whose spring bones run in any case) and an
    /// optional mode (see [`parse_mode`]; `None`: as `tassel simulate` without `--mode`,
    /// `fixed` unless the rig sets its chains to `classic`).
    ///
    /// The character is left as `tassel simulate` has it before its frame 1: a
    /// zero-length frame at the rest pose, the character at the origin.
    pub fn load(bytes: &[u8], rig_toml: Option<&str>, mode: Option<&str>) -> Result<Self, String> {
        if bytes.is_empty() {
            return Err("the file's bytes are empty".into());
        }
        let model = tassel_gltf::load_slice(bytes, None, "the file").map_err(|e| e.to_string())?;
        Self::from_model(model, rig_toml, mode)
    }

    /// As [`load`](Self::load), from a file: a `.gltf` may read its buffers beside it.
    pub fn load_file(
        path: &Path,
        rig_toml: Option<&str>,
        mode: Option<&str>,
    ) -> Result<Self, String> {
        let model = tassel_gltf::load(path).map_err(|e| e.to_string())?;
        Self::from_model(model, rig_toml, mode)
    }

    fn from_model(
        model: tassel_gltf::Model,
        rig_toml: Option<&str>,
        mode: Option<&str>,
    ) -> Result<Self, String> {
        let vrm: VrmSpringBones = model.vrm.map(|v| v.springs).unwrap_or_default();
        Self::from_parts(
            model.skeleton,
            model.node_to_joint,
            model.joint_to_node,
            vrm,
            rig_toml,
            mode,
        )
    }

    /// A character from a skeleton the caller owns (an engine's or a tool's, not a file):
    /// joint names (unique, not empty), parents (`-1` for a root; any order, no cycle),
    /// rest local transforms (10 floats a joint, as [`frame`](Self::frame)), an optional
    /// rig file's text, optional VRM spring bones as JSON text — a `VRMC_springBone` 1.0
    /// extension object (it has `springs` or `specVersion`) or VRM 0.x's
    /// `secondaryAnimation` (it has `boneGroups`), with node indices into the joint list —
    /// and an optional mode. Either rig input, or both, may be given. Every buffer keeps
    /// the caller's joint order. A VRM 0.x bone group walks each joint's children in the
    /// joint list's order; its leaf joints get a tail along their rest translation.
    ///
    /// A rest rotation whose length is within 1e-6 of 1 is used as given (bit for bit);
    /// another one is normalized; a zero or non-finite one is an error naming the joint.
    /// The file loader ([`load`](Self::load)) and this constructor share everything after
    /// the skeleton and the springs are read.
    pub fn from_skeleton(
        names: &[&str],
        parents: &[i64],
        rest: &[f32],
        rig_toml: Option<&str>,
        springs_json: Option<&str>,
        mode: Option<&str>,
    ) -> Result<Self, String> {
        let n = names.len();
        if n == 0 {
            return Err("no joints".into());
        }
        if n > tassel::MAX_JOINTS {
            return Err(format!(
                "{n} joints; at most {} are taken",
                tassel::MAX_JOINTS
            ));
        }
        if parents.len() != n {
            return Err(format!(
                "{} parents for {n} joints (one each, -1 for a root)",
                parents.len()
            ));
        }
        if rest.len() != n * FLOATS_PER_JOINT {
            return Err(format!(
                "rest holds {} floats; {n} joints need {}",
                rest.len(),
                n * FLOATS_PER_JOINT
            ));
        }
        let mut seen = std::collections::HashMap::new();
        let mut builder = tassel::SkeletonBuilder::new();
        for (j, &name) in names.iter().enumerate() {
            if name.is_empty() {
                return Err(format!("joint {j} has no name"));
            }
            if let Some(k) = seen.insert(name, j) {
                return Err(format!("joint {j} repeats the name '{name}' of joint {k}"));
            }
            let parent = match parents[j] {
                -1 => None,
                p if p >= 0 && (p as usize) < n && p as usize != j => Some(p as usize),
                p => {
                    return Err(format!(
                        "joint {j} ('{name}'): parent {p} is not -1 or another joint (0..{n})"
                    ))
                }
            };
            let mut t = read(&rest[j * FLOATS_PER_JOINT..(j + 1) * FLOATS_PER_JOINT]);
            let len2 = t.rotation.length_squared();
            if !t.is_finite() || len2 <= 1e-12 {
                return Err(format!(
                    "joint {j} ('{name}'): the rest transform must be finite, its rotation not zero"
                ));
            }
            if (len2 - 1.0).abs() > 2e-6 {
                t.rotation = t.rotation.normalize();
            }
            builder.add(name, parent, t);
        }
        let (skeleton, node_to_joint) = builder.build().map_err(|e| match e {
            tassel::Error::Cycle(name) => {
                format!("the parents make a cycle through joint '{name}'")
            }
            e => e.to_string(),
        })?;
        let mut joint_to_node = vec![0; n];
        for (node, &j) in node_to_joint.iter().enumerate() {
            joint_to_node[j] = node;
        }
        let vrm = match springs_json {
            None => VrmSpringBones::default(),
            Some(text) => springs_from_json(text, names, parents, rest, &node_to_joint)?,
        };
        vrm.validate_for(&skeleton)
            .map_err(|e| format!("spring bones: {e}"))?;
        Self::from_parts(skeleton, node_to_joint, joint_to_node, vrm, rig_toml, mode)
    }

    fn from_parts(
        skeleton: Skeleton,
        node_to_joint: Vec<usize>,
        joint_to_node: Vec<usize>,
        vrm: VrmSpringBones,
        rig_toml: Option<&str>,
        mode: Option<&str>,
    ) -> Result<Self, String> {
        let mut rig = match rig_toml {
            Some(text) if text.len() > MAX_RIG_BYTES => {
                return Err(format!(
                    "the rig file is larger than the limit of {MAX_RIG_BYTES} bytes"
                ))
            }
            Some(text) => RigSettings::from_toml_str(text).map_err(|e| format!("rig: {e}"))?,
            None if !vrm.is_empty() => RigSettings::default(),
            None => {
                return Err("no VRM spring bones; give a rig file (TOML) \
                            with its chains, springs, cloths or ropes"
                    .into())
            }
        };
        let requested = mode.map(parse_mode).transpose()?;
        let (mode, options) = SimMode::apply(requested, &mut rig, !vrm.is_empty())
            .map_err(|e| format!("mode: {e}"))?;
        let rest = skeleton.rest().to_vec();
        let mut sim =
            CharacterSim::with_vrm(skeleton, &rig, &vrm, options).map_err(|e| e.to_string())?;
        // The state before `tassel simulate`'s frame 1.
        sim.frame(&rest, Transform::IDENTITY, 0.0)
            .map_err(|e| e.to_string())?;
        let mut written: Vec<usize> = sim
            .simulated_joints()
            .iter()
            .map(|&j| joint_to_node[j])
            .collect();
        written.sort_unstable();
        let read = read_nodes(&sim, &joint_to_node);
        Ok(Self {
            sim,
            mode,
            node_to_joint,
            joint_to_node,
            written,
            read,
            animated: rest,
        })
    }

    /// A new character of the same kind, as [`load`](Self::load) would make it from the
    /// same file, rig and mode (fresh state, the rest pose, no shared colliders, the
    /// default SIMD use), sharing this one's compiled rig: no file is parsed and nothing
    /// is compiled again, and many copies of one avatar keep one rig in memory. This
    /// character's own state (stepped or not) is not copied.
    pub fn fresh_copy(&self) -> Result<Self, String> {
        let mut sim = CharacterSim::from_rig(self.sim.rig().clone());
        let rest = sim.skeleton().rest().to_vec();
        // The state before `tassel simulate`'s frame 1, as a load leaves it.
        sim.frame(&rest, Transform::IDENTITY, 0.0)
            .map_err(|e| e.to_string())?;
        Ok(Self {
            sim,
            mode: self.mode,
            node_to_joint: self.node_to_joint.clone(),
            joint_to_node: self.joint_to_node.clone(),
            written: self.written.clone(),
            read: self.read.clone(),
            animated: rest,
        })
    }

    /// How many joints (the file's nodes).
    pub fn joint_count(&self) -> usize {
        self.node_to_joint.len()
    }

    /// Node `joint`'s name (a node without one is called `node<i>`; a repeated name gets
    /// `#<i>`, as everywhere in Tassel).
    pub fn joint_name(&self, joint: usize) -> Option<&str> {
        let j = *self.node_to_joint.get(joint)?;
        Some(self.sim.skeleton().name(j))
    }

    /// Node `joint`'s parent node (`None`: a root of the scene, or no such joint).
    pub fn joint_parent(&self, joint: usize) -> Option<usize> {
        let j = *self.node_to_joint.get(joint)?;
        self.sim.skeleton().parent(j).map(|p| self.joint_to_node[p])
    }

    /// The joints a solver writes (node indices, ascending): every other joint's output is
    /// its input.
    pub fn simulated_joints(&self) -> &[usize] {
        &self.written
    }

    /// The joints (node indices, ascending) whose animated transforms a frame depends on:
    /// the others' inputs change nothing in the simulated joints (a caller may leave them
    /// as they were, and skip reading them from its scene). For VRM spring bones without
    /// node constraints, the joints their update reads (the springs, their ancestors and
    /// the colliders' nodes, as the crowd reads them); otherwise every joint.
    pub fn read_joints(&self) -> &[usize] {
        &self.read
    }

    /// The mode the character steps in.
    pub fn mode(&self) -> &'static str {
        self.mode.name()
    }

    /// The rest pose (the file's node transforms): [`FLOATS_PER_JOINT`] floats a joint.
    pub fn rest_locals(&self, out: &mut [f32]) -> Result<(), String> {
        self.check_len("out", out.len())?;
        let rest = self.sim.skeleton().rest();
        for (node, chunk) in out.chunks_exact_mut(FLOATS_PER_JOINT).enumerate() {
            write(&rest[self.node_to_joint[node]], chunk);
        }
        Ok(())
    }

    /// One frame in place: `root` is the character's world transform (10 floats),
    /// `locals` the animated local transforms of every joint in joint order on the way in
    /// and the simulated ones on the way out (only the simulated joints are written), `dt`
    /// the time since the last frame in seconds (0 is a valid frame: nothing moves in
    /// time). On an error (wrong lengths, NaN, a rotation that is not a unit quaternion,
    /// a negative `dt`) nothing changes, in the buffer or in the character.
    pub fn frame(&mut self, root: &[f32], locals: &mut [f32], dt: f32) -> Result<(), String> {
        self.step(root, locals, dt)?;
        self.write_simulated(locals);
        Ok(())
    }

    /// One frame from `locals_in` into `locals_out` (every joint: the animated ones as
    /// they came in); otherwise as [`frame`](Self::frame). On an error `locals_out` is
    /// left as it was.
    pub fn frame_into(
        &mut self,
        root: &[f32],
        locals_in: &[f32],
        locals_out: &mut [f32],
        dt: f32,
    ) -> Result<(), String> {
        self.check_len("locals_out", locals_out.len())?;
        self.step(root, locals_in, dt)?;
        locals_out.copy_from_slice(locals_in);
        self.write_simulated(locals_out);
        Ok(())
    }

    /// Every solver starts again from the animated pose on the next frame (whatever that
    /// frame's `dt`).
    pub fn reset(&mut self) {
        self.sim.reset();
    }

    /// The character was moved on purpose (a respawn, a cut): the next frame starts again
    /// from the pose at the new place instead of whipping the hair across the world (as
    /// [`reset`](Self::reset)).
    pub fn teleport(&mut self) {
        self.sim.reset();
    }

    /// Acts on an animation event starting with `tassel:` (see
    /// [`CharacterSim::apply_event`]: reset the dynamics, set a chain alpha, turn an
    /// external force of the rig on or off or apply it once): `Ok(true)` when it acted,
    /// `Ok(false)` for an event that is not Tassel's, an error naming a bad one.
    pub fn apply_event(&mut self, event: &str) -> Result<bool, String> {
        self.sim.apply_event(event).map_err(|e| e.to_string())
    }

    /// Starts a timed settings override of the chains (see
    /// [`CharacterSim::start_settings_override`]): `scales` multiply damping, stiffness,
    /// world damping location, world damping rotation, radius and limit angle of the chain
    /// named `chain` (`None`: every chain) for `duration` seconds (infinite: until
    /// stopped), blending in over `blend_in` and out over `blend_out`. Returns its handle
    /// (> 0), or an error naming a bad value or chain.
    pub fn start_settings_override(
        &mut self,
        scales: [f32; 6],
        duration: f32,
        blend_in: f32,
        blend_out: f32,
        chain: Option<&str>,
    ) -> Result<u32, String> {
        let timing = tassel::dynamics::chain::OverrideTiming {
            duration,
            blend_in,
            blend_out,
        };
        let scale = tassel::dynamics::chain::SettingsScale::from_array(scales);
        self.sim
            .start_settings_override(scale, timing, chain, None)
            .map(|h| h.0)
            .map_err(|e| e.to_string())
    }

    /// Stops a settings override by its handle, blending out over `blend_out` seconds (0:
    /// at once); false when no override has it (it ended).
    pub fn stop_settings_override(&mut self, handle: u32, blend_out: f32) -> bool {
        self.sim
            .stop_settings_override(tassel::dynamics::chain::OverrideHandle(handle), blend_out)
    }

    /// This character's colliders in the world as its last frame placed them — every
    /// collider, or the rig's `[[collider_group]]` named `group` — as
    /// [`FLOATS_PER_COLLIDER`] floats each into `out` (see
    /// [`CharacterSim::shared_colliders`]). Returns how many there are; writes nothing when
    /// `out` is too short for them all (ask with an empty `out`).
    pub fn shared_colliders(&self, group: Option<&str>, out: &mut [f32]) -> Result<usize, String> {
        use tassel::collide::Shape;
        let count = self
            .sim
            .rig()
            .chains()
            .shared_set(group)
            .map_err(|e| e.to_string())?
            .len();
        if out.len() < count * FLOATS_PER_COLLIDER {
            return Ok(count);
        }
        let mut slots = out.chunks_exact_mut(FLOATS_PER_COLLIDER);
        self.sim
            .visit_shared_colliders(group, |c| {
                let (kind, p) = match c.shape {
                    Shape::Sphere { radius, inside } => {
                        (0.0, [radius, f32::from(u8::from(inside)), 0.0, 0.0])
                    }
                    Shape::Capsule { radius, length } => (1.0, [radius, length, 0.0, 0.0]),
                    Shape::TaperedCapsule {
                        radius0,
                        radius1,
                        length,
                    } => (2.0, [radius0, radius1, length, 0.0]),
                    Shape::Box { half_extents: h } => (3.0, [h.x, h.y, h.z, 0.0]),
                    Shape::Plane => (4.0, [0.0; 4]),
                };
                let (t, r) = (c.transform.translation, c.transform.rotation);
                if let Some(o) = slots.next() {
                    o.copy_from_slice(&[
                        kind, p[0], p[1], p[2], p[3], t.x, t.y, t.z, r.x, r.y, r.z, r.w,
                    ]);
                }
            })
            .map_err(|e| e.to_string())
    }

    /// Sets the colliders other characters share with this one from
    /// [`FLOATS_PER_COLLIDER`] floats each (as [`FlatCharacter::shared_colliders`] writes
    /// them; see [`CharacterSim::set_shared_colliders`]). An error names a collider whose
    /// kind, shape or transform is bad; nothing changes then.
    pub fn set_shared_colliders(&mut self, data: &[f32]) -> Result<(), String> {
        use tassel::collide::{PlacedCollider, Shape};
        if !data.len().is_multiple_of(FLOATS_PER_COLLIDER) {
            return Err(format!(
                "{} floats are not whole colliders of {FLOATS_PER_COLLIDER}",
                data.len()
            ));
        }
        let mut list = Vec::with_capacity(data.len() / FLOATS_PER_COLLIDER);
        for (i, c) in data.chunks_exact(FLOATS_PER_COLLIDER).enumerate() {
            let shape = match c[0] {
                0.0 => Shape::Sphere {
                    radius: c[1],
                    inside: c[2] != 0.0,
                },
                1.0 => Shape::Capsule {
                    radius: c[1],
                    length: c[2],
                },
                2.0 => Shape::TaperedCapsule {
                    radius0: c[1],
                    radius1: c[2],
                    length: c[3],
                },
                3.0 => Shape::Box {
                    half_extents: Vec3::new(c[1], c[2], c[3]),
                },
                4.0 => Shape::Plane,
                k => {
                    return Err(format!(
                        "shared collider {i}: kind {k} is not 0 (sphere), 1 (capsule), 2 \
                         (tapered capsule), 3 (box) or 4 (plane)"
                    ))
                }
            };
            list.push(PlacedCollider {
                shape,
                transform: Transform::from_translation_rotation(
                    Vec3::new(c[5], c[6], c[7]),
                    Quat::from_xyzw(c[8], c[9], c[10], c[11]),
                ),
            });
        }
        self.sim
            .set_shared_colliders(&list)
            .map_err(|e| e.to_string())
    }

    /// The solvers, for Rust callers who want more than the flat API (chain tips, VRM
    /// tails, the output in model space).
    pub fn sim(&self) -> &CharacterSim {
        &self.sim
    }

    /// The node of skeleton joint `joint` (the order of [`Self::sim`]'s poses).
    pub fn node_of(&self, joint: usize) -> Option<usize> {
        self.joint_to_node.get(joint).copied()
    }

    /// The skeleton joint of node `node` (a node that exists).
    pub(crate) fn joint_of(&self, node: usize) -> usize {
        self.node_to_joint[node]
    }

    fn check_len(&self, what: &str, len: usize) -> Result<(), String> {
        let want = self.joint_count() * FLOATS_PER_JOINT;
        if len == want {
            Ok(())
        } else {
            Err(format!(
                "{what} holds {len} floats; the character has {} joints, {want} floats \
                 ({FLOATS_PER_JOINT} a joint)",
                self.joint_count()
            ))
        }
    }

    fn step(&mut self, root: &[f32], locals: &[f32], dt: f32) -> Result<(), String> {
        if root.len() != FLOATS_PER_JOINT {
            return Err(format!(
                "root holds {} floats, not {FLOATS_PER_JOINT} (tx ty tz qx qy qz qw sx sy sz)",
                root.len()
            ));
        }
        self.check_len("locals", locals.len())?;
        for (node, chunk) in locals.chunks_exact(FLOATS_PER_JOINT).enumerate() {
            self.animated[self.node_to_joint[node]] = read(chunk);
        }
        // The simulation checks every input before it touches its state.
        self.sim
            .frame(&self.animated, read(root), dt)
            .map_err(message)?;
        Ok(())
    }

    fn write_simulated(&self, out: &mut [f32]) {
        let locals = &self.sim.pose().locals;
        for &node in &self.written {
            let at = node * FLOATS_PER_JOINT;
            write(
                &locals[self.node_to_joint[node]],
                &mut out[at..at + FLOATS_PER_JOINT],
            );
        }
    }
}

/// A frame's error as the flat API reports it (a joint is named as a node, the flat API's
/// joints being the file's nodes).
pub(crate) fn message(e: tassel::Error) -> String {
    match e {
        tassel::Error::NonFinite(what) => {
            format!("non-finite value in {what}").replace("joint '", "joint (node) '")
        }
        e => e.to_string(),
    }
}

/// Ten floats (tx ty tz qx qy qz qw sx sy sz) as a transform.
pub(crate) fn read(v: &[f32]) -> Transform {
    Transform::new(
        Vec3::new(v[0], v[1], v[2]),
        Quat::from_xyzw(v[3], v[4], v[5], v[6]),
        Vec3::new(v[7], v[8], v[9]),
    )
}

/// A transform as ten floats.
pub(crate) fn write(t: &Transform, out: &mut [f32]) {
    out[..3].copy_from_slice(&t.translation.to_array());
    out[3..7].copy_from_slice(&t.rotation.to_array());
    out[7..10].copy_from_slice(&t.scale.to_array());
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every mode the C ABI and the web take by name is the CLI's `--mode` name, and a name
    /// that is none of them is refused with the list.
    #[test]
    fn every_mode_parses_by_its_name() {
        for (name, mode) in [
            ("fixed", SimMode::Fixed),
            ("spec", SimMode::Spec),
            ("three-vrm", SimMode::ThreeVrm),
            ("classic", SimMode::Classic),
            ("kawaii", SimMode::Kawaii),
            ("spcr", SimMode::Spcr),
        ] {
            assert_eq!(parse_mode(name), Ok(mode), "{name}");
            assert_eq!(mode.name(), name);
        }
        let e = parse_mode("spcrr").unwrap_err();
        assert!(e.contains("spcrr") && e.contains("kawaii, spcr"), "{e}");
    }
}
