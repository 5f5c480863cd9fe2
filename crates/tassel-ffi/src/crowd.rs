//! The flat crowd: many characters of one kind (one file, one rig, one mode) stepped by one
//! call per frame over flat buffers: the crowd path of the core ([`VrmCrowd`],
//! [`ChainCrowd`]) where the kind has one, else each character's [`CharacterSim`].

use crate::flat::{read, write, FlatCharacter, FLOATS_PER_JOINT};
use std::sync::Arc;
use tassel::crowd::{ChainCrowd, CrowdKind, CrowdPose, VrmCrowd};
use tassel::{CharacterRig, CharacterSim, Transform};

/// How a crowd steps its characters.
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)]
enum Run {
    /// VRM spring bones only: side by side in lanes.
    Vrm(VrmCrowd),
    /// Bone chains only: side by side in lanes.
    Chains(ChainCrowd),
    /// Any other kind (springs, cloths, ropes, several solvers): one simulation a
    /// character, one after another.
    Characters(Vec<CharacterSim>),
}

/// Many characters of one kind (the file, rig and mode of a [`FlatCharacter`]), stepped
/// together: one call a frame for all of them, over flat buffers.
///
/// A frame reads only the joints the solvers read ([`read_joints`](Self::read_joints):
/// the simulated joints, their tails, colliders and ancestors) and writes only the
/// simulated ones ([`written_joints`](Self::written_joints)), each character after the
/// other in the buffers. A kind with VRM spring bones only, or bone chains only, runs on
/// the core's crowd path (characters side by side in SIMD lanes); any other kind runs one
/// [`CharacterSim`] per character. Either way a character's results are those of its own
/// [`FlatCharacter`] reset before its first frame, bit for bit: a character added to the
/// crowd starts from its pose on its first frame (as after [`FlatCharacter::reset`]).
///
/// ```
/// use tassel_ffi::{FlatCharacter, FlatCrowd, FLOATS_PER_JOINT};
///
/// let c = tassel::builtin::character();
/// let source = tassel_gltf::ExportSource::from_skeleton(&c.skeleton, tassel_gltf::BoneMesh::None);
/// let glb = tassel_gltf::export_glb(&source, &[]).map_err(|e| e.to_string())?;
/// let rig = c.rig.to_toml_string().map_err(|e| e.to_string())?;
/// let kind = FlatCharacter::load(&glb, Some(&rig), None)?;
/// let mut crowd = FlatCrowd::new(&kind);
/// for _ in 0..3 {
///     crowd.add();
/// }
/// // The input: each character's root, then the joints it reads (here at rest).
/// let mut rest = vec![0.0; kind.joint_count() * FLOATS_PER_JOINT];
/// kind.rest_locals(&mut rest)?;
/// let read = crowd.read_joints().to_vec();
/// let mut roots = Vec::new();
/// let mut locals = Vec::new();
/// for i in 0..crowd.len() {
///     roots.extend_from_slice(&[i as f32, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0]);
///     for &j in &read {
///         locals.extend_from_slice(&rest[j * FLOATS_PER_JOINT..(j + 1) * FLOATS_PER_JOINT]);
///     }
/// }
/// let mut out = vec![0.0; crowd.len() * crowd.written_joints().len() * FLOATS_PER_JOINT];
/// crowd.frame(&roots, &locals, &mut out, 1.0 / 60.0)?;
/// assert!(out.iter().all(|v| v.is_finite()));
/// # Ok::<(), String>(())
/// ```
#[derive(Debug, Clone)]
pub struct FlatCrowd {
    rig: Arc<CharacterRig>,
    run: Run,
    mode: &'static str,
    /// The nodes a frame reads, ascending, and each one's skeleton joint.
    read: Vec<usize>,
    read_joint: Vec<usize>,
    /// The nodes a frame writes, ascending, and each one's skeleton joint.
    written: Vec<usize>,
    written_joint: Vec<usize>,
    /// The whole pose is composed for the output (VRM node constraints turn joints the
    /// springs do not own), instead of the simulated rotations alone.
    whole_pose: bool,
    /// Each character's animated local pose (skeleton order), one after another: the
    /// joints not read stay at rest.
    locals: Vec<Transform>,
    roots: Vec<Transform>,
    /// The characters the last frame held (index, message).
    held: Vec<(usize, String)>,
    scratch_locals: Vec<Transform>,
    scratch_models: Vec<Transform>,
}

impl FlatCrowd {
    /// An empty crowd of characters like `kind`: its file, rig and mode (its state is not
    /// copied: each character added starts afresh).
    pub fn new(kind: &FlatCharacter) -> Self {
        let sim = kind.sim();
        let rig = sim.rig().clone();
        let sk = Arc::new(rig.skeleton().clone());
        let built = match CrowdKind::of(&rig) {
            Some(CrowdKind::Vrm) => VrmCrowd::new(sk.clone(), Arc::new(rig.vrm().clone()))
                .ok()
                .map(Run::Vrm),
            Some(CrowdKind::Chains) => ChainCrowd::new(sk.clone(), Arc::new(rig.chains().clone()))
                .ok()
                .map(Run::Chains),
            None => None,
        };
        let run = built.unwrap_or_else(|| Run::Characters(Vec::new()));
        // What a frame reads: the character's own list (for VRM springs the VRM crowd's
        // input joints, made the same way as this crowd's; else every joint).
        let read = kind.read_joints().to_vec();
        let written = kind.simulated_joints().to_vec();
        let joint_of = |nodes: &[usize]| -> Vec<usize> {
            nodes.iter().map(|&node| kind.joint_of(node)).collect()
        };
        let whole_pose = matches!(run, Run::Vrm(_)) && rig.vrm().has_node_constraints();
        Self {
            run,
            mode: kind.mode(),
            read_joint: joint_of(&read),
            read,
            written_joint: joint_of(&written),
            written,
            whole_pose,
            locals: Vec::new(),
            roots: Vec::new(),
            held: Vec::new(),
            scratch_locals: sk.rest().to_vec(),
            scratch_models: sk.rest().to_vec(),
            rig,
        }
    }

    /// How the crowd steps: `"vrm"` (VRM spring bones side by side in SIMD lanes),
    /// `"chains"` (bone chains side by side) or `"characters"` (one simulation a
    /// character).
    pub fn kind(&self) -> &'static str {
        match self.run {
            Run::Vrm(_) => "vrm",
            Run::Chains(_) => "chains",
            Run::Characters(_) => "characters",
        }
    }

    /// The mode the characters step in.
    pub fn mode(&self) -> &'static str {
        self.mode
    }

    /// Number of characters.
    pub fn len(&self) -> usize {
        self.roots.len()
    }

    /// True when there is no character.
    pub fn is_empty(&self) -> bool {
        self.roots.is_empty()
    }

    /// The joints (nodes) whose animated local transforms a frame reads, ascending: the
    /// input holds these, in this order, for each character.
    pub fn read_joints(&self) -> &[usize] {
        &self.read
    }

    /// The joints (nodes) a frame writes, ascending: the output holds these, in this order,
    /// for each character.
    pub fn written_joints(&self) -> &[usize] {
        &self.written
    }

    /// Adds a character; returns its index. It starts from its pose on its first frame.
    pub fn add(&mut self) -> usize {
        let i = match &mut self.run {
            Run::Vrm(c) => c.add(),
            Run::Chains(c) => c.add(),
            Run::Characters(sims) => {
                sims.push(CharacterSim::from_rig(self.rig.clone()));
                sims.len() - 1
            }
        };
        self.locals.extend_from_slice(self.rig.skeleton().rest());
        self.roots.push(Transform::IDENTITY);
        i
    }

    /// Removes character `i`; the last character takes its index (as `Vec::swap_remove`)
    /// and carries on exactly as it would have.
    pub fn swap_remove(&mut self, i: usize) -> Result<(), String> {
        self.check(i)?;
        let result = match &mut self.run {
            Run::Vrm(c) => c.swap_remove(i),
            Run::Chains(c) => c.swap_remove(i),
            Run::Characters(sims) => {
                sims.swap_remove(i);
                Ok(())
            }
        };
        result.map_err(|e| e.to_string())?;
        let n = self.rig.skeleton().len();
        let last = self.roots.len() - 1;
        self.roots.swap_remove(i);
        if i != last {
            self.locals.copy_within(last * n..(last + 1) * n, i * n);
        }
        self.locals.truncate(last * n);
        Ok(())
    }

    /// See `tassel_crowd_mark_pose_unchanged`.
    pub fn mark_pose_unchanged(&mut self, i: usize) -> Result<(), String> {
        self.check(i)?;
        match &mut self.run {
            Run::Vrm(c) => c.mark_pose_unchanged(i).map_err(|e| e.to_string()),
            // Nothing to reuse: the mark changes nothing.
            Run::Chains(_) | Run::Characters(_) => Ok(()),
        }
    }

    /// Character `i` starts again from its pose on the next frame (a cut, a respawn).
    pub fn reset(&mut self, i: usize) -> Result<(), String> {
        self.check(i)?;
        match &mut self.run {
            Run::Vrm(c) => c.reset(i).map_err(|e| e.to_string()),
            Run::Chains(c) => c.reset(i).map_err(|e| e.to_string()),
            Run::Characters(sims) => {
                sims[i].reset();
                Ok(())
            }
        }
    }

    /// The characters the last frame held for bad input (index, what was wrong), in
    /// index order: their output was not written and their state is as before.
    pub fn held(&self) -> &[(usize, String)] {
        &self.held
    }

    fn check(&self, i: usize) -> Result<(), String> {
        if i < self.len() {
            Ok(())
        } else {
            Err(format!(
                "crowd character {i} does not exist (the crowd has {})",
                self.len()
            ))
        }
    }

    /// The floats [`frame`](Self::frame)'s buffers hold: roots, locals, out.
    pub fn buffer_lengths(&self) -> [usize; 3] {
        let n = self.len();
        [
            n * FLOATS_PER_JOINT,
            n * self.read.len() * FLOATS_PER_JOINT,
            n * self.written.len() * FLOATS_PER_JOINT,
        ]
    }

    /// One frame of every character. `roots`: each character's world transform (10
    /// floats a character); `locals`: each character's animated local transforms of
    /// [`read_joints`](Self::read_joints) (10 floats a joint), character after
    /// character; `out`: each character's simulated local transforms of
    /// [`written_joints`](Self::written_joints), character after character. `dt`:
    /// seconds since the last frame (≥ 0).
    ///
    /// `Err` for wrong lengths or a bad `dt`: nothing changes. A character whose input is
    /// bad (NaN, a rotation that is not a unit quaternion) is *held*: not stepped, its
    /// output not written, listed in [`held`](Self::held); every other character steps as
    /// it would have, and the frame returns `Ok(false)`. `Ok(true)`: every character
    /// stepped.
    pub fn frame(
        &mut self,
        roots: &[f32],
        locals: &[f32],
        out: &mut [f32],
        dt: f32,
    ) -> Result<bool, String> {
        let want = self.buffer_lengths();
        for (what, len, want) in [
            ("roots", roots.len(), want[0]),
            ("locals", locals.len(), want[1]),
            ("out", out.len(), want[2]),
        ] {
            if len != want {
                return Err(format!(
                    "{what} holds {len} floats; the crowd needs {want} ({} characters, {} \
                     read and {} written joints, {FLOATS_PER_JOINT} floats a transform)",
                    self.len(),
                    self.read.len(),
                    self.written.len()
                ));
            }
        }
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(format!("dt {dt} is not a time step (finite, >= 0)"));
        }
        let n = self.rig.skeleton().len();
        let per = self.read.len() * FLOATS_PER_JOINT;
        for (i, root) in roots.chunks_exact(FLOATS_PER_JOINT).enumerate() {
            self.roots[i] = read(root);
            let pose = &mut self.locals[i * n..(i + 1) * n];
            let input = &locals[i * per..(i + 1) * per];
            for (&j, t) in self
                .read_joint
                .iter()
                .zip(input.chunks_exact(FLOATS_PER_JOINT))
            {
                pose[j] = read(t);
            }
        }
        self.held.clear();
        let (all, roots) = (&self.locals, &self.roots);
        let input = |i: usize| CrowdPose {
            transform: roots[i],
            locals: &all[i * n..(i + 1) * n],
        };
        let failed = match &mut self.run {
            Run::Vrm(c) => c.frame(dt, input).is_err(),
            Run::Chains(c) => c.frame(dt, input).is_err(),
            Run::Characters(sims) => {
                for (i, sim) in sims.iter_mut().enumerate() {
                    let p = input(i);
                    if let Err(e) = sim.frame(p.locals, p.transform, dt) {
                        self.held.push((i, crate::flat::message(e)));
                    }
                }
                false
            }
        };
        if failed {
            let message = |(i, e): (usize, &tassel::Error)| (i, crate::flat::message(e.clone()));
            match &self.run {
                Run::Vrm(c) => self.held.extend(c.held().map(message)),
                Run::Chains(c) => self.held.extend(c.held().map(message)),
                Run::Characters(_) => {}
            }
        }
        self.write_out(out);
        Ok(self.held.is_empty())
    }

    /// Every character's output but the held ones'.
    fn write_out(&mut self, out: &mut [f32]) {
        let n = self.rig.skeleton().len();
        let per = self.written.len() * FLOATS_PER_JOINT;
        let mut held = self.held.iter().map(|(i, _)| *i).peekable();
        for i in 0..self.len() {
            if held.peek() == Some(&i) {
                held.next();
                continue;
            }
            let slot = &mut out[i * per..(i + 1) * per];
            let input = &self.locals[i * n..(i + 1) * n];
            let pose: &[Transform] = match &self.run {
                Run::Characters(sims) => &sims[i].pose().locals,
                run => {
                    let locals = &mut self.scratch_locals;
                    if self.whole_pose {
                        locals.copy_from_slice(input);
                    } else {
                        // The crowds turn simulated joints only: their animated
                        // translation and scale are the output's.
                        for &j in &self.written_joint {
                            locals[j] = input[j];
                        }
                    }
                    // Cannot fail: `i` exists and the buffers have the skeleton's length.
                    let _ = match run {
                        Run::Vrm(c) if self.whole_pose => {
                            c.write_pose(i, locals, &mut self.scratch_models)
                        }
                        Run::Vrm(c) => c.write_rotations(i, locals),
                        Run::Chains(c) => c.write_rotations(i, locals),
                        Run::Characters(_) => Ok(()),
                    };
                    locals
                }
            };
            for (&j, chunk) in self
                .written_joint
                .iter()
                .zip(slot.chunks_exact_mut(FLOATS_PER_JOINT))
            {
                write(&pose[j], chunk);
            }
        }
    }
}
