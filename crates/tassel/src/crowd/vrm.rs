//! [`VrmCrowd`]: the VRM spring-bone frame of [`crate::dynamics::vrm::VrmJob`] (every
//! mode) for many characters of one rig, [`LANES`] characters per lane group.
//!
//! The frame is the scalar job's, reorganised for lanes: the rig's links are sorted by
//! joint (ancestors first), so its lazy model refresh is one pass over the joints in
//! skeleton order, and every branch that depends only on the rig (shape kinds, centres,
//! tails) is the same for all lanes. Branches that depend on a character's state (a
//! contact, a fallback, a reset) are computed for every lane and selected per lane.

#[cfg(target_arch = "x86_64")]
use super::avx::Fa;
#[cfg(target_arch = "x86_64")]
use super::avx512::Fz;
use super::lanes::{rotation_arc_from, Lane, Mask, Trs, F, LANES, M, Q, V3};
use super::vrm_contact::{collide_tail, Placed};
use super::{Isa, SimdUse};
use crate::dynamics::path::CharacterPath;
use crate::dynamics::vrm::{VrmMode, VrmRig, VrmShape};
use crate::error::{Error, Result};
use crate::math::{normalize_or, Transform};
use crate::pose::LocalToModelJob;
use crate::skeleton::Skeleton;
use glam::{Quat, Vec3};
use rayon::prelude::*;
use std::sync::Arc;

/// One character's input for a crowd frame: where it is and its animated pose.
#[derive(Debug, Clone, Copy)]
pub struct CrowdPose<'a> {
    /// The character's world transform this frame.
    pub transform: Transform,
    /// Its animated local transforms (one per skeleton joint).
    pub locals: &'a [Transform],
}

/// What the crowd needs of one link, precomputed with the scalar code's own operations.
#[derive(Debug, Clone)]
struct LinkPlan {
    slot: usize,
    center: Option<usize>,
    tail_slot: Option<usize>,
    tail_local: Vec3,
    rest_local: Transform,
    /// `rest_local.rotation * bone_axis`.
    rest_bone: Vec3,
    bone_axis: Vec3,
    /// `normalize_or(bone_axis, Y)`, and its half-turn quaternion.
    arc_from: Vec3,
    half_turn: Quat,
    /// `1 − drag_force`.
    keep: f32,
    hit_radius: f32,
    colliders: std::ops::Range<usize>,
}

/// The joints a crowd computes (every link, tail, centre and collider joint and their
/// ancestors), in skeleton order, and the links on them.
#[derive(Debug, Clone)]
struct Plan {
    joints: Vec<usize>,
    parent: Vec<Option<usize>>,
    /// The link on each slot, if any.
    link_at: Vec<Option<usize>>,
    /// Slots whose model a link's rotation can change (a link or below one).
    affected: Vec<bool>,
    /// Slots whose animated model a specification step reads before its update writes
    /// it, or never writes: every slot not affected, a root link (its own model), a
    /// centre, a collider's joint, and the ancestors of all these (their models are
    /// composed from the parent's). The others' animated models are overwritten unread.
    read_animated: Vec<bool>,
    /// Skeleton joints not in `joints` (their input is checked, not used).
    unplanned: Vec<usize>,
    links: Vec<LinkPlan>,
    colliders: Vec<(usize, VrmShape)>,
}

impl Plan {
    fn new(sk: &Skeleton, rig: &VrmRig) -> Result<Plan> {
        let n = sk.len();
        let mut needed = vec![false; n];
        let mark = |j: usize, needed: &mut Vec<bool>| {
            let mut k = Some(j);
            while let Some(x) = k {
                if needed[x] {
                    break;
                }
                needed[x] = true;
                k = sk.parent(x);
            }
        };
        for l in &rig.links {
            mark(l.joint, &mut needed);
            if let Some(t) = l.tail_joint {
                mark(t, &mut needed);
            }
            if let Some(c) = l.center {
                mark(c, &mut needed);
            }
        }
        for (j, _) in &rig.colliders {
            mark(*j, &mut needed);
        }
        let joints: Vec<usize> = (0..n).filter(|&j| needed[j]).collect();
        let unplanned: Vec<usize> = (0..n).filter(|&j| !needed[j]).collect();
        let mut slot_of = vec![usize::MAX; n];
        for (s, &j) in joints.iter().enumerate() {
            slot_of[j] = s;
        }
        let parent: Vec<Option<usize>> = joints
            .iter()
            .map(|&j| sk.parent(j).map(|p| slot_of[p]))
            .collect();
        let mut link_at = vec![None; joints.len()];
        let mut links = Vec::with_capacity(rig.links.len());
        for (i, l) in rig.links.iter().enumerate() {
            if let Some(c) = l.center {
                if c > l.joint {
                    return Err(Error::InvalidParameter(format!(
                        "crowd: spring joint '{}' has its centre '{}' after it in the \
                         skeleton; a crowd needs the centre to be an ancestor or earlier joint",
                        sk.name(l.joint),
                        sk.name(c)
                    )));
                }
            }
            let slot = slot_of[l.joint];
            link_at[slot] = Some(i);
            let arc_from = normalize_or(l.bone_axis, Vec3::Y);
            let o = arc_from.any_orthonormal_vector();
            links.push(LinkPlan {
                slot,
                center: l.center.map(|c| slot_of[c]),
                tail_slot: l.tail_joint.map(|t| slot_of[t]),
                tail_local: l.tail_local,
                rest_local: l.rest_local,
                rest_bone: l.rest_local.rotation * l.bone_axis,
                bone_axis: l.bone_axis,
                arc_from,
                half_turn: Quat::from_xyzw(o.x, o.y, o.z, 0.0),
                keep: 1.0 - l.drag_force,
                hit_radius: l.hit_radius,
                colliders: l.colliders.clone(),
            });
        }
        let mut affected = vec![false; joints.len()];
        for s in 0..joints.len() {
            affected[s] = link_at[s].is_some() || parent[s].is_some_and(|p| affected[p]);
        }
        let colliders: Vec<(usize, VrmShape)> = rig
            .colliders
            .iter()
            .map(|&(j, shape)| (slot_of[j], shape))
            .collect();
        let mut read_animated: Vec<bool> = (0..joints.len())
            .map(|s| !affected[s] || (link_at[s].is_some() && parent[s].is_none()))
            .collect();
        for lp in &links {
            if let Some(c) = lp.center {
                read_animated[c] = true;
            }
        }
        for &(slot, _) in &colliders {
            read_animated[slot] = true;
        }
        // Parents come before their children, so one pass from the end reaches the roots.
        for s in (0..joints.len()).rev() {
            if read_animated[s] {
                if let Some(p) = parent[s] {
                    read_animated[p] = true;
                }
            }
        }
        Ok(Plan {
            joints,
            parent,
            link_at,
            affected,
            read_animated,
            unplanned,
            links,
            colliders,
        })
    }
}

/// A lane group: the state of up to [`LANES`] characters, one per lane.
#[derive(Debug, Clone)]
struct Pack {
    /// Characters in use (the rest of the lanes run on the rest pose, unseen).
    count: usize,
    current_tail: Vec<V3>,
    prev_tail: Vec<V3>,
    length: Vec<F>,
    stale_tail: Vec<V3>,
    rotation: Vec<Q>,
    /// Fixed mode: the rotations one step before `rotation` (unused in the other modes).
    rotation_before: Vec<Q>,
    /// The rotations the last frame wrote (fixed mode: between the last two steps).
    out_rotation: Vec<Q>,
    /// Fixed mode: last frame's animated locals (per plan slot) and each character's
    /// recent transforms, and the time not yet stepped.
    prev_locals: Vec<Trs>,
    paths: Vec<CharacterPath>,
    accumulator: [f32; LANES],
    prev_component: Trs,
    needs_reset: [bool; LANES],
    resets: [u64; LANES],
    /// The first bad input of the last frame (lane, error): the group was not stepped.
    error: Option<(usize, Error)>,
}

impl Pack {
    fn new(links: usize, slots: usize) -> Pack {
        let zero = V3::splat(Vec3::ZERO);
        let id = Q::splat(Quat::IDENTITY);
        Pack {
            count: 0,
            current_tail: vec![zero; links],
            prev_tail: vec![zero; links],
            length: vec![F::splat(0.0); links],
            stale_tail: vec![zero; links],
            rotation: vec![id; links],
            rotation_before: vec![id; links],
            out_rotation: vec![id; links],
            prev_locals: vec![Trs::splat(&Transform::IDENTITY); slots],
            paths: vec![CharacterPath::default(); LANES],
            accumulator: [0.0; LANES],
            prev_component: Trs::splat(&Transform::IDENTITY),
            needs_reset: [true; LANES],
            resets: [0; LANES],
            error: None,
        }
    }
}

/// One character's state, taken out of its lane (to move it to another).
#[derive(Debug, Clone)]
struct LaneState {
    current_tail: Vec<Vec3>,
    prev_tail: Vec<Vec3>,
    length: Vec<f32>,
    stale_tail: Vec<Vec3>,
    rotation: Vec<Quat>,
    rotation_before: Vec<Quat>,
    out_rotation: Vec<Quat>,
    prev_locals: Vec<Transform>,
    path: CharacterPath,
    accumulator: f32,
    prev_component: Transform,
    needs_reset: bool,
    resets: u64,
}

impl Pack {
    fn lane(&self, l: usize) -> LaneState {
        LaneState {
            current_tail: self.current_tail.iter().map(|v| v.get(l)).collect(),
            prev_tail: self.prev_tail.iter().map(|v| v.get(l)).collect(),
            length: self.length.iter().map(|v| v.get(l)).collect(),
            stale_tail: self.stale_tail.iter().map(|v| v.get(l)).collect(),
            rotation: self.rotation.iter().map(|q| q.get(l)).collect(),
            rotation_before: self.rotation_before.iter().map(|q| q.get(l)).collect(),
            out_rotation: self.out_rotation.iter().map(|q| q.get(l)).collect(),
            prev_locals: self.prev_locals.iter().map(|t| t.get(l)).collect(),
            path: self.paths[l],
            accumulator: self.accumulator[l],
            prev_component: self.prev_component.get(l),
            needs_reset: self.needs_reset[l],
            resets: self.resets[l],
        }
    }

    fn set_lane(&mut self, l: usize, s: &LaneState) {
        for (d, v) in self.current_tail.iter_mut().zip(&s.current_tail) {
            d.set(l, *v);
        }
        for (d, v) in self.prev_tail.iter_mut().zip(&s.prev_tail) {
            d.set(l, *v);
        }
        for (d, v) in self.length.iter_mut().zip(&s.length) {
            d.0[l] = *v;
        }
        for (d, v) in self.stale_tail.iter_mut().zip(&s.stale_tail) {
            d.set(l, *v);
        }
        for (d, q) in self.rotation.iter_mut().zip(&s.rotation) {
            d.set(l, *q);
        }
        for (d, q) in self.rotation_before.iter_mut().zip(&s.rotation_before) {
            d.set(l, *q);
        }
        for (d, q) in self.out_rotation.iter_mut().zip(&s.out_rotation) {
            d.set(l, *q);
        }
        for (d, t) in self.prev_locals.iter_mut().zip(&s.prev_locals) {
            d.set(l, t);
        }
        self.paths[l] = s.path;
        self.accumulator[l] = s.accumulator;
        self.prev_component.set(l, &s.prev_component);
        self.needs_reset[l] = s.needs_reset;
        self.resets[l] = s.resets;
    }
}

/// One thread's working buffers.
#[derive(Debug, Clone)]
struct Scratch {
    locals: Vec<Trs>,
    models: Vec<Trs>,
    reset_models: Vec<Trs>,
    step_locals: Vec<Trs>,
    step_models: Vec<Trs>,
    placed: Vec<Placed>,
    full_locals: Vec<Transform>,
    full_models: Vec<Transform>,
    component: Trs,
}

impl Scratch {
    fn new(plan: &Plan, joints: usize) -> Scratch {
        let id = Trs::splat(&Transform::IDENTITY);
        let zero = V3::splat(Vec3::ZERO);
        Scratch {
            locals: vec![id; plan.joints.len()],
            models: vec![id; plan.joints.len()],
            reset_models: vec![id; plan.joints.len()],
            step_locals: vec![id; plan.joints.len()],
            step_models: vec![id; plan.joints.len()],
            placed: vec![
                Placed {
                    a: zero,
                    b: zero,
                    mid: zero,
                    half: F::splat(0.0),
                };
                plan.colliders.len()
            ],
            full_locals: vec![Transform::IDENTITY; joints],
            full_models: vec![Transform::IDENTITY; joints],
            component: id,
        }
    }
}

/// Many characters with the same VRM spring bones, advanced together.
///
/// Every character shares one skeleton and one compiled [`VrmRig`] (behind [`Arc`]) and
/// has its own state: a character costs its state only (about 60 bytes per spring joint).
/// A frame reads each character's world transform and animated pose through a closure,
/// steps all characters ([`LANES`] per lane group, the groups spread over the current
/// rayon pool's threads) and keeps each character's simulated rotations, which
/// [`VrmCrowd::write_pose`] writes into a pose.
///
/// Results are those of [`crate::CharacterSim::with_vrm`] on the same input, bit for
/// bit, and do not depend on the number of threads. Every mode: `fixed` (steps at the rig's
/// rate with the pose and the character transform interpolated, output between the last
/// two steps), `spec` and `three-vrm`.
///
/// ```
/// use std::sync::Arc;
/// use tassel::crowd::{CrowdPose, VrmCrowd};
/// use tassel::dynamics::vrm::{VrmMode, VrmOptions, VrmRig};
/// use tassel::{builtin, Transform};
///
/// let (skeleton, bones) = builtin::bench_vrm(4, 5, 2);
/// let options = VrmOptions { mode: VrmMode::Spec, ..Default::default() };
/// let rig = Arc::new(VrmRig::new(&skeleton, &bones, options)?);
/// let skeleton = Arc::new(skeleton);
/// let mut crowd = VrmCrowd::new(skeleton.clone(), rig)?;
/// for _ in 0..20 {
///     crowd.add();
/// }
/// let rest = skeleton.rest().to_vec();
/// for frame in 0..10 {
///     crowd.frame(1.0 / 60.0, |i| CrowdPose {
///         transform: Transform::from_translation(glam::Vec3::X * (i as f32 + frame as f32 * 0.01)),
///         locals: &rest,
///     })?;
/// }
/// let mut locals = rest.clone();
/// let mut models = rest.clone();
/// crowd.write_pose(3, &mut locals, &mut models)?;
/// # Ok::<(), tassel::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct VrmCrowd {
    skeleton: Arc<Skeleton>,
    rig: Arc<VrmRig>,
    plan: Plan,
    packs: Vec<Pack>,
    len: usize,
    scratch: Vec<Scratch>,
    /// Per frame: each link's `stiffness · dt` and `gravity · dt`.
    stiffness_dt: Vec<f32>,
    external: Vec<Vec3>,
    simd: SimdUse,
}

impl VrmCrowd {
    /// An empty crowd of characters with `skeleton` and `rig` (compiled for it).
    pub fn new(skeleton: Arc<Skeleton>, rig: Arc<VrmRig>) -> Result<Self> {
        if rig.joint_count() != skeleton.len() {
            return Err(Error::LengthMismatch {
                what: "VRM rig joints",
                expected: skeleton.len(),
                got: rig.joint_count(),
            });
        }
        let plan = Plan::new(&skeleton, &rig)?;
        let links = rig.links.len();
        Ok(Self {
            skeleton,
            rig,
            plan,
            packs: Vec::new(),
            len: 0,
            scratch: Vec::new(),
            stiffness_dt: vec![0.0; links],
            external: vec![Vec3::ZERO; links],
            simd: SimdUse::Auto,
        })
    }

    /// Adds a character; returns its index. It starts from its pose on its first frame.
    pub fn add(&mut self) -> usize {
        if self.len.is_multiple_of(LANES) {
            self.packs
                .push(Pack::new(self.rig.links.len(), self.plan.joints.len()));
        }
        let i = self.len;
        let pack = &mut self.packs[i / LANES];
        pack.count += 1;
        // A lane a removed character left: start it afresh.
        let lane = i % LANES;
        pack.needs_reset[lane] = true;
        pack.resets[lane] = 0;
        pack.accumulator[lane] = 0.0;
        pack.paths[lane] = CharacterPath::default();
        self.len += 1;
        i
    }

    /// Removes character `i`; the last character takes its index (as `Vec::swap_remove`),
    /// and carries on exactly as it would have.
    pub fn swap_remove(&mut self, i: usize) -> Result<()> {
        self.check(i)?;
        let last = self.len - 1;
        if i != last {
            let moved = self.packs[last / LANES].lane(last % LANES);
            self.packs[i / LANES].set_lane(i % LANES, &moved);
        }
        let pack = &mut self.packs[last / LANES];
        pack.count -= 1;
        pack.needs_reset[last % LANES] = true;
        if pack.count == 0 {
            self.packs.pop();
        }
        self.len -= 1;
        Ok(())
    }

    /// Swaps characters `i` and `j` (their indices; each carries on exactly as it would
    /// have). Characters share a lane group [`LANES`] at a time, in index order; which
    /// ones share a group changes the VRM crowd's cost little (about 3 % between
    /// characters that move alike and characters that do not, `tassel bench --vrm spec
    /// --crowd 192 --phase-step S`), the chain crowd's much more
    /// ([`super::ChainCrowd::swap`]). Allocates (both characters' state, briefly).
    pub fn swap(&mut self, i: usize, j: usize) -> Result<()> {
        self.check(i)?;
        self.check(j)?;
        super::swap_lanes(&mut self.packs, i, j, |p, l| p.lane(l), Pack::set_lane);
        Ok(())
    }

    /// Which lane code steps the crowd: the widest the CPU has ([`SimdUse::Auto`], the
    /// default: AVX-512, else AVX2, else portable), AVX2 at most ([`SimdUse::Avx2`]) or
    /// the portable code ([`SimdUse::Portable`]; the crowd has no scalar code of its own,
    /// so [`SimdUse::Scalar`] runs that too: its scalar reference is
    /// [`crate::CharacterSim`]). The results are the same bits whichever runs; the
    /// choice is for measuring and testing each.
    pub fn set_simd(&mut self, simd: SimdUse) {
        self.simd = simd;
    }

    /// Number of characters.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when there is no character.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The shared skeleton.
    pub fn skeleton(&self) -> &Arc<Skeleton> {
        &self.skeleton
    }

    /// The shared rig.
    pub fn rig(&self) -> &Arc<VrmRig> {
        &self.rig
    }

    fn check(&self, i: usize) -> Result<()> {
        if i < self.len {
            Ok(())
        } else {
            Err(Error::InvalidParameter(format!(
                "crowd character {i} does not exist (the crowd has {})",
                self.len
            )))
        }
    }

    /// Makes character `i` start again from its pose on the next frame.
    pub fn reset(&mut self, i: usize) -> Result<()> {
        self.check(i)?;
        self.packs[i / LANES].needs_reset[i % LANES] = true;
        Ok(())
    }

    /// Character `i` was moved on purpose: it starts again instead of whipping.
    pub fn teleport(&mut self, i: usize) -> Result<()> {
        self.reset(i)
    }

    /// How many resets character `i` had (first frame, teleports, non-finite recoveries).
    pub fn reset_count(&self, i: usize) -> Option<u64> {
        (i < self.len).then(|| self.packs[i / LANES].resets[i % LANES])
    }

    /// Character `i`'s local rotation of link `link` (in [`VrmRig::links`] order).
    pub fn rotation(&self, i: usize, link: usize) -> Option<Quat> {
        if i >= self.len || link >= self.rig.links.len() {
            return None;
        }
        Some(self.packs[i / LANES].out_rotation[link].get(i % LANES))
    }

    /// Character `i`'s current tail of link `link`, world space (or its spring's centre
    /// space when the spring has a centre), as the last frame left it.
    pub fn tail(&self, i: usize, link: usize) -> Option<Vec3> {
        if i >= self.len || link >= self.rig.links.len() {
            return None;
        }
        Some(self.packs[i / LANES].current_tail[link].get(i % LANES))
    }

    /// Character `i`'s pose after the last frame: `locals` holds its animated pose of that
    /// frame on entry; the node constraints and the springs' rotations are written into
    /// it, and `models` receives the model pose. Never allocates.
    pub fn write_pose(
        &self,
        i: usize,
        locals: &mut [Transform],
        models: &mut [Transform],
    ) -> Result<()> {
        self.check(i)?;
        let sk = &*self.skeleton;
        LocalToModelJob {
            skeleton: sk,
            root: Transform::IDENTITY,
            locals,
            models,
        }
        .run()?;
        if !self.rig.constraints.list.is_empty() {
            let component = self.packs[i / LANES].prev_component.get(i % LANES);
            self.rig.constraints.apply(sk, &component, locals, models);
        }
        let pack = &self.packs[i / LANES];
        for (k, l) in self.rig.links.iter().enumerate() {
            locals[l.joint].rotation = pack.out_rotation[k].get(i % LANES);
        }
        LocalToModelJob {
            skeleton: sk,
            root: Transform::IDENTITY,
            locals,
            models,
        }
        .run()
    }

    /// Advances every character by `dt` seconds (finite, ≥ 0; the first frame of a
    /// character only takes its pose, whatever `dt`). `input(i)` gives character `i`'s
    /// world transform and animated pose; it is called once per character, from the
    /// rayon pool's threads.
    ///
    /// A character whose input is bad (wrong length, not finite, beyond the limits) makes
    /// the frame return an error naming it; the [`LANES`] characters of its lane group
    /// are not stepped this frame, every other character is. Never allocates once each
    /// thread has run a frame.
    pub fn frame<'a, I>(&mut self, dt: f32, input: I) -> Result<()>
    where
        I: Fn(usize) -> CrowdPose<'a> + Sync,
    {
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(Error::InvalidTimeStep(dt));
        }
        if self.packs.is_empty() {
            return Ok(());
        }
        // The update's time step: the frame's, or fixed mode's step.
        let h = match self.rig.options.mode {
            VrmMode::Fixed => 1.0 / self.rig.options.step_rate,
            _ => dt,
        };
        for (k, l) in self.rig.links.iter().enumerate() {
            self.stiffness_dt[k] = l.stiffness * h;
            self.external[k] = l.gravity * h;
        }
        let threads = rayon::current_num_threads().max(1);
        let chunk = self.packs.len().div_ceil(threads);
        let chunks = self.packs.len().div_ceil(chunk);
        while self.scratch.len() < chunks {
            self.scratch
                .push(Scratch::new(&self.plan, self.skeleton.len()));
        }
        let ctx = Ctx {
            sk: &self.skeleton,
            rig: &self.rig,
            plan: &self.plan,
            stiffness_dt: &self.stiffness_dt,
            external: &self.external,
            dt,
            isa: Isa::of(self.simd),
        };
        let input = &input;
        self.packs
            .par_chunks_mut(chunk)
            .zip(self.scratch[..chunks].par_iter_mut())
            .enumerate()
            .for_each(|(c, (packs, scratch))| {
                for (k, pack) in packs.iter_mut().enumerate() {
                    let base = (c * chunk + k) * LANES;
                    pack.error = ctx.run(pack, scratch, base, input).err();
                }
            });
        match self.packs.iter().find_map(|p| p.error.clone()) {
            Some((_, e)) => Err(e),
            None => Ok(()),
        }
    }
}

/// What every lane group's step reads.
struct Ctx<'c> {
    sk: &'c Skeleton,
    rig: &'c VrmRig,
    plan: &'c Plan,
    stiffness_dt: &'c [f32],
    external: &'c [Vec3],
    dt: f32,
    isa: Isa,
}

impl Ctx<'_> {
    /// Loads, checks and steps one lane group in the lane type `self.isa` chose: the
    /// explicit AVX-512 or AVX2 type (`crowd/avx512.rs`, `crowd/avx.rs`; AVX2's was 1.2x
    /// faster than the same code over `F` compiled for AVX2, which was 1.5x faster than
    /// SSE2: `tassel bench --crowd 200 --vrm spec`), else over `F` with the baseline
    /// SSE2. Every lane operation of each is IEEE-exact, so all give the same bits.
    fn run<'a, I>(
        &self,
        pack: &mut Pack,
        scratch: &mut Scratch,
        base: usize,
        input: &I,
    ) -> std::result::Result<(), (usize, Error)>
    where
        I: Fn(usize) -> CrowdPose<'a> + Sync,
    {
        // SAFETY (both): the function only requires the instructions of its lane type,
        // and `Isa::of` chose that type because the CPU has them.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        match self.isa {
            Isa::Avx512 => return unsafe { self.run_avx512(pack, scratch, base, input) },
            Isa::Avx2 => return unsafe { self.run_avx2(pack, scratch, base, input) },
            Isa::Portable => {}
        }
        self.gather::<F, I>(pack, scratch, base, input)?;
        self.step_baseline(pack, scratch);
        Ok(())
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn run_avx2<'a, I>(
        &self,
        pack: &mut Pack,
        scratch: &mut Scratch,
        base: usize,
        input: &I,
    ) -> std::result::Result<(), (usize, Error)>
    where
        I: Fn(usize) -> CrowdPose<'a> + Sync,
    {
        // The explicit AVX2 lane type only inside this function, after the CPU was
        // found to have AVX2 (the condition of its soundness).
        self.gather::<Fa, I>(pack, scratch, base, input)?;
        self.step_avx2(pack, scratch);
        Ok(())
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
    fn run_avx512<'a, I>(
        &self,
        pack: &mut Pack,
        scratch: &mut Scratch,
        base: usize,
        input: &I,
    ) -> std::result::Result<(), (usize, Error)>
    where
        I: Fn(usize) -> CrowdPose<'a> + Sync,
    {
        // The explicit AVX-512 lane type only inside this function, after the CPU was
        // found to have it (the condition of its soundness).
        self.gather::<Fz, I>(pack, scratch, base, input)?;
        self.step_avx512(pack, scratch);
        Ok(())
    }

    // The step itself is not generic over the input: compiled once, here, rather than
    // inlined into every caller's `frame` (a whole step per closure type).
    #[inline(never)]
    fn step_baseline(&self, pack: &mut Pack, s: &mut Scratch) {
        self.step_lanes::<F>(pack, s)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline(never)]
    fn step_avx2(&self, pack: &mut Pack, s: &mut Scratch) {
        self.step_lanes::<Fa>(pack, s)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
    #[inline(never)]
    fn step_avx512(&self, pack: &mut Pack, s: &mut Scratch) {
        self.step_lanes::<Fz>(pack, s)
    }

    /// [`Ctx::gather_checked`]'s result, faster where the input is good and no
    /// constraint applies: the poses are transposed into lanes first and checked there,
    /// eight characters per operation. Any failed check (or constraints) runs
    /// `gather_checked` itself, so the error is the same.
    #[inline(always)]
    fn gather<'a, T: Lane, I>(
        &self,
        pack: &mut Pack,
        scratch: &mut Scratch,
        base: usize,
        input: &I,
    ) -> std::result::Result<(), (usize, Error)>
    where
        I: Fn(usize) -> CrowdPose<'a> + Sync,
    {
        let sk = self.sk;
        let n = sk.len();
        if !self.rig.constraints.list.is_empty() {
            return self.gather_checked(pack, scratch, base, input);
        }
        let rest: &[Transform] = sk.rest();
        let mut poses = [rest; LANES];
        let mut component = Trs::splat(&Transform::IDENTITY);
        let used = pack.count.min(LANES);
        for (lane, slot) in poses.iter_mut().enumerate().take(used) {
            let pose = input(base + lane);
            if pose.locals.len() != n || !pose.transform.within_limits() {
                return self.gather_checked(pack, scratch, base, input);
            }
            *slot = pose.locals;
            component.set(lane, &pose.transform);
        }
        let mut ok = <T::M as Mask>::of(M::from_bools(std::array::from_fn(|l| l >= used)));
        let mut all = <T::M as Mask>::NONE.not();
        // Each slot's lanes in one transposition ([`Lane::transforms`]), checked as they
        // come out of it.
        for (s, &j) in self.plan.joints.iter().enumerate() {
            let locals = T::transforms(&std::array::from_fn(|lane| &poses[lane][j]));
            all = all.and(within_limits(&locals));
            scratch.locals[s] = locals.f();
        }
        ok = ok.or(all);
        let mut fine = ok == <T::M as Mask>::ALL;
        for pose in &poses[..used] {
            for &j in &self.plan.unplanned {
                fine &= pose[j].within_limits();
            }
        }
        if !fine {
            return self.gather_checked(pack, scratch, base, input);
        }
        scratch.component = component;
        Ok(())
    }

    /// Checks the group's input and loads it into `scratch.locals` and
    /// `scratch.component`; unused lanes get the rest pose. Touches no state. Lane by
    /// lane, the first bad input of the first bad lane is the error: the reference for
    /// [`Ctx::gather`], which it runs where constraints change the pose or a check failed.
    fn gather_checked<'a, I>(
        &self,
        pack: &mut Pack,
        scratch: &mut Scratch,
        base: usize,
        input: &I,
    ) -> std::result::Result<(), (usize, Error)>
    where
        I: Fn(usize) -> CrowdPose<'a> + Sync,
    {
        let sk = self.sk;
        let n = sk.len();
        let mut component = Trs::splat(&Transform::IDENTITY);
        for lane in 0..LANES {
            let i = base + lane;
            if lane >= pack.count {
                for (s, &j) in self.plan.joints.iter().enumerate() {
                    scratch.locals[s].set(lane, &sk.rest()[j]);
                }
                continue;
            }
            let pose = input(i);
            if pose.locals.len() != n {
                return Err((
                    lane,
                    Error::LengthMismatch {
                        what: "crowd character's animated pose",
                        expected: n,
                        got: pose.locals.len(),
                    },
                ));
            }
            let all_ok = pose
                .locals
                .iter()
                .fold(true, |ok, t| ok & t.within_limits());
            if let Some(j) = (!all_ok)
                .then(|| pose.locals.iter().position(|t| !t.within_limits()))
                .flatten()
            {
                return Err((
                    lane,
                    Error::NonFinite(format!(
                        "crowd character {i}: animated pose of joint '{}' is not finite, not a \
                         unit rotation, or lies beyond {:e}",
                        sk.name(j),
                        crate::limits::MAX_COORDINATE
                    )),
                ));
            }
            if !pose.transform.within_limits() {
                return Err((
                    lane,
                    Error::NonFinite(format!(
                        "crowd character {i}: transform is not finite or lies beyond {:e}",
                        crate::limits::MAX_COORDINATE
                    )),
                ));
            }
            component.set(lane, &pose.transform);
            let source: &[Transform] = if self.rig.constraints.list.is_empty() {
                pose.locals
            } else {
                // Node constraints first, as the single-character job applies them.
                scratch.full_locals.copy_from_slice(pose.locals);
                crate::pose::local_to_model_into(
                    sk,
                    &scratch.full_locals,
                    &mut scratch.full_models,
                );
                self.rig.constraints.apply(
                    sk,
                    &pose.transform,
                    &mut scratch.full_locals,
                    &mut scratch.full_models,
                );
                &scratch.full_locals
            };
            for (s, &j) in self.plan.joints.iter().enumerate() {
                scratch.locals[s].set(lane, &source[j]);
            }
        }
        scratch.component = component;
        Ok(())
    }
}

/// [`Transform::within_limits`] per lane (the same operations: glam's four-component dot
/// for the rotation's squared length).
#[inline(always)]
fn within_limits<T: Lane>(t: &Trs<T>) -> T::M {
    let max = T::splat(crate::limits::MAX_COORDINATE);
    let unit = (t.r.dot(t.r) - T::splat(1.0)).abs().le(T::splat(0.21));
    let (a, s) = (t.t.abs(), t.s.abs());
    unit.and(a.x.le(max))
        .and(a.y.le(max))
        .and(a.z.le(max))
        .and(s.x.le(max))
        .and(s.y.le(max))
        .and(s.z.le(max))
}

/// The model transform of a slot with `local` under its parent's model in `models`
/// (`None`: a skeleton root, under the identity as [`LocalToModelJob`] puts it).
#[inline(always)]
fn under<T: Lane>(models: &[Trs], parent: Option<usize>, local: &Trs) -> Trs<T> {
    let local = Trs::<T>::of(local);
    match parent {
        Some(p) => Trs::<T>::of(&models[p]).mul(&local),
        None => Trs::<T>::splat(&Transform::IDENTITY).mul(&local),
    }
}

/// The joints a frame (or a step) works on: the character transform, locals, models.
struct Poses<'p, T = F> {
    comp: Trs<T>,
    locals: &'p [Trs],
    models: &'p mut [Trs],
}

// `match` rather than `Option::map` in the hot path: a closure is a function of its own,
// compiled without the AVX2 code generation of the function it is called from.
#[allow(clippy::manual_map)]
impl Ctx<'_> {
    /// One frame of one lane group, its hot part (the model pose, the colliders, the
    /// specification's update) computed in the lane type `T`.
    #[inline(always)]
    fn step_lanes<T: Lane>(&self, pack: &mut Pack, s: &mut Scratch) {
        let plan = self.plan;
        let opts = &self.rig.options;
        let mode = opts.mode;
        let comp = s.component;
        let fixed = mode == VrmMode::Fixed;
        if fixed {
            for lane in 0..LANES {
                pack.paths[lane].push(comp.get(lane), self.dt);
            }
        }
        let mut reset = M::from_bools(pack.needs_reset);
        if opts.teleport_distance > 0.0 {
            let moved = (comp.t - pack.prev_component.t).length();
            reset = reset.or(moved.gt(F::splat(opts.teleport_distance)));
        }
        // The animated model pose (as the single-character frame computes it); where the
        // specification's update runs, only of the slots it reads before writing them.
        let updates = !fixed && self.dt > 0.0 && reset != M::ALL;
        for k in 0..plan.joints.len() {
            if updates && !plan.read_animated[k] {
                continue;
            }
            s.models[k] = under::<T>(&s.models, plan.parent[k], &s.locals[k]).f();
        }
        if reset != M::ALL {
            if fixed {
                self.run_fixed::<T>(pack, s, reset);
            } else if self.dt > 0.0 {
                let Scratch {
                    locals,
                    models,
                    placed,
                    ..
                } = s;
                let mut poses = Poses {
                    comp: Trs::<T>::of(&comp),
                    locals,
                    models,
                };
                self.place_colliders(&poses, placed);
                self.update(pack, &mut poses, placed, mode, <T::M as Mask>::ALL);
            }
        }
        // Guard: a non-finite state starts again from the pose.
        let mut bad = <T::M as Mask>::NONE;
        for i in 0..self.rig.links.len() {
            let tail = V3::<T>::of(pack.current_tail[i]);
            let rotation = Q::<T>::of(pack.rotation[i]);
            bad = bad.or(tail.finite().and(rotation.finite()).not());
        }
        let again = reset.or(bad.m());
        if again.any() {
            let still_bad = self.reset(pack, s, again);
            for lane in 0..LANES {
                if again.get(lane) {
                    pack.resets[lane] += 1;
                    pack.accumulator[lane] = 0.0;
                    // A reset that itself is not finite is reset once more by the guard.
                    if reset.get(lane) && still_bad.get(lane) {
                        pack.resets[lane] += 1;
                    }
                }
            }
        }
        if fixed {
            self.fixed_output(pack, s, again);
        } else {
            pack.out_rotation.copy_from_slice(&pack.rotation);
        }
        if mode == VrmMode::ThreeVrm {
            self.record_tails(pack, s);
        }
        pack.prev_component = comp;
        pack.needs_reset = [false; LANES];
    }

    #[inline(always)]
    fn place_colliders<T: Lane>(&self, poses: &Poses<T>, placed: &mut [Placed]) {
        let comp = poses.comp;
        for (c, (slot, shape)) in self.plan.colliders.iter().enumerate() {
            let w = comp.mul(&Trs::of(&poses.models[*slot]));
            let zero = V3::splat(Vec3::ZERO);
            let half = T::splat(0.5);
            let (a, b) = match *shape {
                VrmShape::Sphere { offset, .. } => (w.transform_point(V3::splat(offset)), zero),
                VrmShape::Capsule { offset, tail, .. } => (
                    w.transform_point(V3::splat(offset)),
                    w.transform_point(V3::splat(tail)),
                ),
                VrmShape::Plane { offset, normal } => (
                    w.transform_point(V3::splat(offset)),
                    w.r.mul_vec3(V3::splat(normal) / w.s)
                        .normalize_or(V3::splat(Vec3::Y)),
                ),
            };
            let p: Placed<T> = match *shape {
                VrmShape::Capsule { .. } => Placed {
                    a,
                    b,
                    mid: (a + b) * half,
                    half: (b - a).length() * half,
                },
                _ => Placed {
                    a,
                    b,
                    mid: a,
                    half: T::splat(0.0),
                },
            };
            placed[c] = p.f();
        }
    }

    /// The specification's update of every link, one pass in skeleton order (the scalar
    /// job's lazy refresh: a joint's model is recomputed once everything above it is; a
    /// refreshed skeleton root takes its local as its model, as the scalar refresh does).
    /// Only the lanes in `active` keep the new state.
    #[inline(always)]
    fn update<T: Lane>(
        &self,
        pack: &mut Pack,
        poses: &mut Poses<T>,
        placed: &[Placed],
        mode: VrmMode,
        active: T::M,
    ) {
        let plan = self.plan;
        for slot in 0..plan.joints.len() {
            if !plan.affected[slot] {
                continue;
            }
            let parent = match plan.parent[slot] {
                Some(p) => Some(Trs::<T>::of(&poses.models[p])),
                None => None,
            };
            let local = Trs::<T>::of(&poses.locals[slot]);
            match plan.link_at[slot] {
                None => {
                    poses.models[slot] = match parent {
                        Some(p) => p.mul(&local).f(),
                        None => local.f(),
                    }
                }
                Some(i) => {
                    let (rotation, own_t) =
                        self.link(i, pack, poses, placed, parent.as_ref(), mode, active);
                    let model = match parent {
                        // `p * turned`, its translation (`own_t`) already computed.
                        Some(p) => Trs {
                            t: own_t,
                            r: p.r.mul_quat(rotation).normalize(),
                            s: p.s * local.s,
                        },
                        // The scalar job writes a root link's model as its local.
                        None => Trs {
                            r: rotation,
                            ..local
                        },
                    };
                    poses.models[slot] = model.f();
                }
            }
        }
    }

    /// One link: Verlet step, collisions, the joint turned toward the new tail.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn link<T: Lane>(
        &self,
        i: usize,
        pack: &mut Pack,
        poses: &Poses<T>,
        placed: &[Placed],
        parent: Option<&Trs<T>>,
        mode: VrmMode,
        active: T::M,
    ) -> (Q<T>, V3<T>) {
        let lp = &self.plan.links[i];
        let comp = poses.comp;
        let (parent_world, own_t) = match parent {
            Some(p) => (
                comp.mul(p),
                p.transform_point(V3::of(poses.locals[lp.slot].t)),
            ),
            None => (comp, V3::of(poses.models[lp.slot].t)),
        };
        let position = comp.transform_point(own_t);
        let center = match lp.center {
            Some(c) => Some(comp.mul(&Trs::of(&poses.models[c]))),
            None => None,
        };
        let (current_stored, prev_stored) = (
            V3::<T>::of(pack.current_tail[i]),
            V3::<T>::of(pack.prev_tail[i]),
        );
        let (current, prev) = match &center {
            Some(c) => (
                c.transform_point(current_stored),
                c.transform_point(prev_stored),
            ),
            None => (current_stored, prev_stored),
        };
        let rest_dir = parent_world.r.mul_vec3(V3::splat(lp.rest_bone));
        let inertia = (current - prev) * T::splat(lp.keep);
        let stiffness = rest_dir * T::splat(self.stiffness_dt[i]);
        let external = V3::splat(self.external[i]);
        let length = match (mode, lp.tail_slot) {
            (VrmMode::ThreeVrm, Some(_)) => (V3::of(pack.stale_tail[i]) - position).length(),
            _ => T::of(pack.length[i]),
        };
        let next = position
            + (current + inertia + stiffness + external - position).normalize_or(rest_dir) * length;
        let (next, _) = self.collide_tail(
            lp,
            placed,
            position,
            length,
            rest_dir,
            next,
            mode == VrmMode::Fixed,
        );
        let stored = match &center {
            Some(c) => c.inverse_transform_point(next),
            None => next,
        };
        // Turn the joint toward the tail, from its rest frame under the current parent.
        let rotation = self.turn(lp, &parent_world, next);
        pack.prev_tail[i] = V3::select(active, current_stored, prev_stored).f();
        pack.current_tail[i] = V3::select(active, stored, current_stored).f();
        pack.rotation[i] = Q::select(active, rotation, Q::of(pack.rotation[i])).f();
        (rotation, own_t)
    }

    /// The local rotation that points the link's bone at `tail` (world): the rest local
    /// rotation turned from the bone axis to the tail seen from the rest frame.
    #[inline(always)]
    fn turn<T: Lane>(&self, lp: &LinkPlan, parent_world: &Trs<T>, tail: V3<T>) -> Q<T> {
        let rest_world = parent_world.mul(&Trs::splat(&lp.rest_local));
        let to = rest_world
            .inverse_transform_point(tail)
            .normalize_or(V3::splat(lp.bone_axis));
        let arc = rotation_arc_from(lp.arc_from, lp.half_turn, to);
        Q::splat(lp.rest_local.rotation).mul_quat(arc).normalize()
    }

    /// [`collide_tail`] for link `lp` (every lane the same link).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn collide_tail<T: Lane>(
        &self,
        lp: &LinkPlan,
        placed: &[Placed],
        position: V3<T>,
        length: T,
        rest_dir: V3<T>,
        tail: V3<T>,
        exact: bool,
    ) -> (V3<T>, T::M) {
        collide_tail(
            &self.rig.link_colliders[lp.colliders.clone()],
            &self.plan.colliders,
            placed,
            T::splat(lp.hit_radius),
            position,
            length,
            rest_dir,
            tail,
            exact,
        )
    }

    /// Fixed mode: whole steps of `1/step_rate` up to now for the lanes not reset, each
    /// with the animated pose and the character transform interpolated to its time.
    #[inline(always)]
    fn run_fixed<T: Lane>(&self, pack: &mut Pack, s: &mut Scratch, reset: M) {
        let opts = &self.rig.options;
        let h = 1.0 / opts.step_rate;
        let dt = self.dt;
        let mut steps = [0u32; LANES];
        let mut acc_old = [0.0f32; LANES];
        let mut skipped = [0.0f32; LANES];
        let mut most = 0;
        for lane in 0..LANES {
            if reset.get(lane) {
                continue;
            }
            let old = pack.accumulator[lane];
            let mut total = old + dt;
            let mut n = (total / h + 1e-4).floor() as u32;
            if n > opts.max_steps_per_frame {
                // A hitch: drop the time we cannot afford, keep the most recent steps.
                total -= (n - opts.max_steps_per_frame) as f32 * h;
                n = opts.max_steps_per_frame;
            }
            steps[lane] = n;
            acc_old[lane] = old;
            skipped[lane] = old + dt - total;
            pack.accumulator[lane] = (total - n as f32 * h).max(0.0);
            most = most.max(n);
        }
        let Scratch {
            locals,
            step_locals,
            step_models,
            placed,
            ..
        } = s;
        for k in 1..=most {
            let active = M::from_bools(std::array::from_fn(|l| !reset.get(l) && k <= steps[l]));
            let mut w = [1.0f32; LANES];
            let mut comp = Trs::<F>::splat(&Transform::IDENTITY);
            for lane in 0..LANES {
                // Where this step ends between last frame (0) and this frame (1).
                let end = k as f32 * h - acc_old[lane] + skipped[lane];
                if dt > 0.0 {
                    w[lane] = (end / dt).clamp(0.0, 1.0);
                }
                comp.set(lane, &pack.paths[lane].at(w[lane]));
            }
            let w = F(w);
            for slot in 0..self.plan.joints.len() {
                step_locals[slot] = pack.prev_locals[slot].lerp(&locals[slot], w);
                // The scalar step refreshes every joint, a root as its local.
                step_models[slot] = match self.plan.parent[slot] {
                    Some(p) => Trs::<T>::of(&step_models[p])
                        .mul(&Trs::of(&step_locals[slot]))
                        .f(),
                    None => step_locals[slot],
                };
            }
            let mut poses = Poses {
                comp: Trs::<T>::of(&comp),
                locals: step_locals,
                models: step_models,
            };
            self.place_colliders(&poses, placed);
            for i in 0..pack.rotation.len() {
                pack.rotation_before[i] =
                    Q::select(active, pack.rotation[i], pack.rotation_before[i]);
            }
            let active = <T::M as Mask>::of(active);
            self.update(pack, &mut poses, placed, VrmMode::Fixed, active);
        }
    }

    /// Fixed mode's output: the rotations between the last two steps, pushed out of this
    /// frame's colliders; and this frame's pose kept for the next frame's steps.
    #[inline(always)]
    fn fixed_output(&self, pack: &mut Pack, s: &mut Scratch, reset: M) {
        let plan = self.plan;
        let opts = &self.rig.options;
        // Last frame's pose for the next steps: the animated locals, with the rest
        // rotations a reset wrote into the spring joints.
        for slot in 0..plan.joints.len() {
            let mut kept = s.locals[slot];
            if let Some(i) = plan.link_at[slot] {
                kept.r = Q::select(reset, Q::splat(plan.links[i].rest_local.rotation), kept.r);
            }
            pack.prev_locals[slot] = kept;
        }
        // This frame's colliders: from the animated pose (the reset's pose where reset).
        for slot in 0..plan.joints.len() {
            s.step_models[slot] = Trs::select(reset, &s.reset_models[slot], &s.models[slot]);
        }
        let comp = s.component;
        {
            let poses = Poses {
                comp,
                locals: &s.locals,
                models: &mut s.step_models,
            };
            self.place_colliders(&poses, &mut s.placed);
        }
        let mut w = [0.0f32; LANES];
        for lane in 0..LANES {
            w[lane] = (pack.accumulator[lane] * opts.step_rate).clamp(0.0, 1.0);
        }
        let w = F(w);
        let full = F::splat(1.0).le(w);
        for i in 0..pack.rotation.len() {
            let between = pack.rotation_before[i].slerp_shortest(pack.rotation[i], w);
            pack.out_rotation[i] = Q::select(full, pack.rotation[i], between);
        }
        self.output_pose(pack, s);
        if self.rig.link_colliders.is_empty() {
            return;
        }
        // The interpolated pose may cut through a collider between two steps: each tail is
        // pushed out by this frame's colliders, the rotation rewritten (lanes that acted).
        let mut acted_any = M::NONE;
        for slot in 0..plan.joints.len() {
            let parent = match plan.parent[slot] {
                Some(p) => Some(s.models[p]),
                None => None,
            };
            if acted_any.any() {
                // The scalar job's refresh below a changed joint (a root: its local).
                let local = s.step_locals[slot];
                s.models[slot] = match parent {
                    Some(p) => p.mul(&local),
                    None => Trs::select(acted_any, &local, &s.models[slot]),
                };
            }
            let Some(i) = plan.link_at[slot] else {
                continue;
            };
            let lp = &plan.links[i];
            if lp.colliders.is_empty() {
                continue;
            }
            let joint_world = comp.mul(&s.models[slot]);
            let tail = joint_world.transform_point(V3::splat(lp.tail_local));
            let parent_world = match &parent {
                Some(p) => comp.mul(p),
                None => comp,
            };
            let rest_dir = parent_world.r.mul_vec3(V3::splat(lp.rest_bone));
            let (next, acted) = self.collide_tail(
                lp,
                &s.placed,
                joint_world.t,
                pack.length[i],
                rest_dir,
                tail,
                true,
            );
            if !acted.any() {
                continue;
            }
            let rotation = self.turn(lp, &parent_world, next);
            pack.out_rotation[i] = Q::select(acted, rotation, pack.out_rotation[i]);
            let mut local = s.step_locals[slot];
            local.r = pack.out_rotation[i];
            s.step_locals[slot] = local;
            let turned = match parent {
                Some(p) => p.mul(&local),
                None => local,
            };
            s.models[slot] = Trs::select(acted, &turned, &s.models[slot]);
            acted_any = acted_any.or(acted);
        }
    }

    /// The specification's initialisation for the lanes in `lanes`: joints at their rest
    /// rotation, tails where it puts them, no velocity. Returns the lanes whose reset
    /// state is itself not finite.
    #[inline(always)]
    fn reset(&self, pack: &mut Pack, s: &mut Scratch, lanes: M) -> M {
        let plan = self.plan;
        let comp = s.component;
        for slot in 0..plan.joints.len() {
            let mut local = s.locals[slot];
            if let Some(i) = plan.link_at[slot] {
                local.r = Q::splat(plan.links[i].rest_local.rotation);
            }
            // The scalar reset refreshes every joint, a root as its local.
            s.reset_models[slot] = match plan.parent[slot] {
                Some(p) => s.reset_models[p].mul(&local),
                None => local,
            };
        }
        let mut bad = M::NONE;
        for (i, lp) in plan.links.iter().enumerate() {
            let world = comp.mul(&s.reset_models[lp.slot]);
            let tail = world.transform_point(V3::splat(lp.tail_local));
            let length = (tail - world.t).length();
            let stored = match lp.center {
                Some(c) => comp.mul(&s.reset_models[c]).inverse_transform_point(tail),
                None => tail,
            };
            let rest = Q::splat(lp.rest_local.rotation);
            pack.length[i] = F::select(lanes, length, pack.length[i]);
            pack.current_tail[i] = V3::select(lanes, stored, pack.current_tail[i]);
            pack.prev_tail[i] = V3::select(lanes, stored, pack.prev_tail[i]);
            pack.rotation[i] = Q::select(lanes, rest, pack.rotation[i]);
            pack.rotation_before[i] = Q::select(lanes, rest, pack.rotation_before[i]);
            bad = bad.or(stored.finite().not());
        }
        bad
    }

    /// The frame's output pose in `s`: `step_locals` the animated locals with the springs'
    /// output rotations, `models` their model transforms (identity above the roots, as the
    /// frame's last model pass) where a spring can move them; the other slots keep the
    /// animated models already in `models`.
    #[inline(always)]
    fn output_pose(&self, pack: &Pack, s: &mut Scratch) {
        let plan = self.plan;
        for slot in 0..plan.joints.len() {
            let mut local = s.locals[slot];
            if let Some(i) = plan.link_at[slot] {
                local.r = pack.out_rotation[i];
            }
            s.step_locals[slot] = local;
            if plan.affected[slot] {
                s.models[slot] = under(&s.models, plan.parent[slot], &local);
            }
        }
    }

    /// three-vrm mode: where each tail node is at the end of the frame (the output pose).
    #[inline(always)]
    fn record_tails(&self, pack: &mut Pack, s: &mut Scratch) {
        self.output_pose(pack, s);
        let comp = s.component;
        for (i, lp) in self.plan.links.iter().enumerate() {
            pack.stale_tail[i] = match lp.tail_slot {
                Some(t) => comp.transform_point(s.models[t].t),
                None => comp
                    .mul(&s.models[lp.slot])
                    .transform_point(V3::splat(lp.tail_local)),
            };
        }
    }
}
