//! [`VrmCrowd`]: the VRM spring-bone update of [`crate::dynamics::vrm::VrmJob`] for many
//! characters of one rig, [`LANES`] characters per lane group.
//!
//! The frame is the scalar job's, reorganised for lanes: the rig's links are sorted by
//! joint (ancestors first), so its lazy model refresh is one pass over the joints in
//! skeleton order, and every branch that depends only on the rig (shape kinds, centres,
//! tails) is the same for all lanes. Branches that depend on a character's state (a
//! contact, a fallback, a reset) are computed for every lane and selected per lane.

use super::lanes::{rotation_arc_from, Trs, F, LANES, M, Q, V3};
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
        let colliders = rig
            .colliders
            .iter()
            .map(|&(j, shape)| (slot_of[j], shape))
            .collect();
        Ok(Plan {
            joints,
            parent,
            link_at,
            affected,
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
    prev_component: Trs,
    needs_reset: [bool; LANES],
    resets: [u64; LANES],
    /// The first bad input of the last frame (lane, error): the group was not stepped.
    error: Option<(usize, Error)>,
}

impl Pack {
    fn new(links: usize) -> Pack {
        let zero = V3::splat(Vec3::ZERO);
        Pack {
            count: 0,
            current_tail: vec![zero; links],
            prev_tail: vec![zero; links],
            length: vec![F::splat(0.0); links],
            stale_tail: vec![zero; links],
            rotation: vec![Q::splat(Quat::IDENTITY); links],
            prev_component: Trs::splat(&Transform::IDENTITY),
            needs_reset: [true; LANES],
            resets: [0; LANES],
            error: None,
        }
    }
}

/// A collider placed in world space, per lane: `a` (centre, capsule head, plane point) and
/// `b` (capsule tail, plane normal), with a bounding sphere for the quick rejection: every
/// point of a sphere or capsule's axis lies within `half` of `mid`.
#[derive(Debug, Clone, Copy)]
struct Placed {
    a: V3,
    b: V3,
    mid: V3,
    half: F,
}

/// One thread's working buffers.
#[derive(Debug, Clone)]
struct Scratch {
    locals: Vec<Trs>,
    models: Vec<Trs>,
    reset_models: Vec<Trs>,
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
/// bit, and do not depend on the number of threads. Modes: `spec` and `three-vrm`
/// (`fixed` is refused by [`VrmCrowd::new`] for now).
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
    avx2: bool,
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
        if rig.options.mode == VrmMode::Fixed {
            return Err(Error::InvalidParameter(
                "crowd: VRM fixed mode is not supported by VrmCrowd yet; use spec or three-vrm, \
                 or CharacterSim per character"
                    .into(),
            ));
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
            avx2: true,
        })
    }

    /// Adds a character; returns its index. It starts from its pose on its first frame.
    pub fn add(&mut self) -> usize {
        if self.len % LANES == 0 {
            self.packs.push(Pack::new(self.rig.links.len()));
        }
        let i = self.len;
        let pack = &mut self.packs[i / LANES];
        pack.count += 1;
        pack.needs_reset[i % LANES] = true;
        self.len += 1;
        i
    }

    /// Allows (the default) or forbids the AVX2 code path on CPUs that have it. The results
    /// are the same bits either way; forbidding it is for measuring and testing the
    /// baseline (SSE2) path.
    pub fn set_avx2(&mut self, allow: bool) {
        self.avx2 = allow;
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
        Some(self.packs[i / LANES].rotation[link].get(i % LANES))
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
            locals[l.joint].rotation = pack.rotation[k].get(i % LANES);
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
        for (k, l) in self.rig.links.iter().enumerate() {
            self.stiffness_dt[k] = l.stiffness * dt;
            self.external[k] = l.gravity * dt;
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
            avx2: self.avx2,
        };
        let input = &input;
        self.packs
            .par_chunks_mut(chunk)
            .zip(self.scratch[..chunks].par_iter_mut())
            .enumerate()
            .for_each(|(c, (packs, scratch))| {
                for (k, pack) in packs.iter_mut().enumerate() {
                    let base = (c * chunk + k) * LANES;
                    pack.error = ctx.gather(pack, scratch, base, input).err();
                    if pack.error.is_none() {
                        ctx.step(pack, scratch);
                    }
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
    avx2: bool,
}

impl Ctx<'_> {
    /// Checks the group's input and loads it into `scratch.locals` and
    /// `scratch.component`; unused lanes get the rest pose. Touches no state.
    fn gather<'a, I>(
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

/// The model transform of a slot from its parent's (`None`: a skeleton root, under the
/// identity as [`LocalToModelJob`] puts it).
#[inline(always)]
fn under(parent: Option<&Trs>, local: &Trs) -> Trs {
    match parent {
        Some(p) => p.mul(local),
        None => Trs::splat(&Transform::IDENTITY).mul(local),
    }
}

/// The specification's collision query per lane
/// ([`crate::dynamics::vrm::PlacedVrmCollider::collision`]): `None` when no lane can be in
/// contact, else the push direction, the signed distance (negative in contact) and the
/// lanes in contact.
///
/// The early `None` compares squared distances against a bound rounded outward, so it
/// only ever skips what the exact test would find out of contact: the results keep the
/// scalar bits. The direction (three divisions and a square root) is computed only when a
/// lane is in contact, since no other lane reads it.
#[inline(always)]
fn contact(shape: &VrmShape, placed: &Placed, p: V3, r: f32) -> Option<(V3, F, M)> {
    let zero = F::splat(0.0);
    let (radius, inside) = match *shape {
        VrmShape::Sphere { radius, inside, .. } | VrmShape::Capsule { radius, inside, .. } => {
            (radius, inside)
        }
        VrmShape::Plane { .. } => {
            let dist = (p - placed.a).dot(placed.b) - F::splat(r);
            let hit = dist.lt(zero);
            return if hit.any() {
                Some((placed.b, dist, hit))
            } else {
                None
            };
        }
    };
    if !inside {
        // Certainly out of reach: farther from the bounding sphere's centre than its
        // radius plus the contact distance, with 1e-4 to spare for the rounding of
        // these few operations (so that no lane the exact test would push is skipped).
        let reach = (placed.half + F::splat(radius + r)) * F::splat(1.0001) + F::splat(1e-6);
        let far = (p - placed.mid).dot(p - placed.mid).gt(reach * reach);
        if far == M::ALL {
            return None;
        }
    }
    // The exact query, as the scalar code computes it.
    let delta = match *shape {
        VrmShape::Capsule { .. } => {
            let (a, b) = (placed.a, placed.b);
            let axis = b - a;
            let delta = p - a;
            let dot = axis.dot(delta);
            let len2 = axis.dot(axis);
            let beyond = delta - axis;
            let along = delta - axis * (dot / len2);
            V3::select(dot.le(zero), delta, V3::select(len2.le(dot), beyond, along))
        }
        _ => p - placed.a,
    };
    let len = delta.length();
    let dist = if inside {
        F::splat(radius - r) - len
    } else {
        len - F::splat(radius + r)
    };
    let hit = dist.lt(zero);
    // (No closures in the hot path: they would not inherit the AVX2 code generation.)
    if hit.any() {
        let dir = delta.normalize_or(V3::splat(Vec3::ZERO));
        Some((if inside { -dir } else { dir }, dist, hit))
    } else {
        None
    }
}

// `match` rather than `Option::map` in the hot path: a closure is a function of its own,
// compiled without the AVX2 code generation of the function it is called from.
#[allow(clippy::manual_map)]
impl Ctx<'_> {
    /// One frame of one lane group whose input is in `s`: with AVX2 where the CPU has it
    /// (twice the lanes per instruction: 1.8× faster measured on `tassel bench --crowd`),
    /// else with the baseline SSE2. Both compile the same code, whose every operation is
    /// IEEE-exact per lane, so both give the same bits.
    fn step(&self, pack: &mut Pack, s: &mut Scratch) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 && std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: `step_avx2` only requires the AVX2 instructions, and the CPU was
            // just checked to have them.
            #[allow(unsafe_code)]
            unsafe {
                return self.step_avx2(pack, s);
            }
        }
        self.step_lanes(pack, s)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn step_avx2(&self, pack: &mut Pack, s: &mut Scratch) {
        self.step_lanes(pack, s)
    }

    #[inline(always)]
    fn step_lanes(&self, pack: &mut Pack, s: &mut Scratch) {
        let plan = self.plan;
        let opts = &self.rig.options;
        let three = opts.mode == VrmMode::ThreeVrm;
        let comp = s.component;
        let mut reset = M::from_bools(pack.needs_reset);
        if opts.teleport_distance > 0.0 {
            let moved = (comp.t - pack.prev_component.t).length();
            reset = reset.or(moved.gt(F::splat(opts.teleport_distance)));
        }
        // The animated model pose.
        for k in 0..plan.joints.len() {
            let m = match plan.parent[k] {
                Some(p) => under(Some(&s.models[p]), &s.locals[k]),
                None => under(None, &s.locals[k]),
            };
            s.models[k] = m;
        }
        if self.dt > 0.0 && reset != M::ALL {
            self.place_colliders(s);
            self.update(pack, s, three);
        }
        // (three-vrm's tails are recorded from the output pose below, as the scalar job
        // records them after its reset too.)
        // Guard: a non-finite state starts again from the pose.
        let mut bad = M::NONE;
        for i in 0..self.rig.links.len() {
            bad = bad.or(pack.current_tail[i]
                .finite()
                .and(pack.rotation[i].finite())
                .not());
        }
        let again = reset.or(bad);
        if again.any() {
            let still_bad = self.reset(pack, s, again);
            for lane in 0..LANES {
                if again.get(lane) {
                    pack.resets[lane] += 1;
                    // A reset that itself is not finite is reset once more by the guard.
                    if reset.get(lane) && still_bad.get(lane) {
                        pack.resets[lane] += 1;
                    }
                }
            }
        }
        if three {
            self.record_tails(pack, s);
        }
        pack.prev_component = comp;
        pack.needs_reset = [false; LANES];
    }

    #[inline(always)]
    fn place_colliders(&self, s: &mut Scratch) {
        let comp = s.component;
        for (c, (slot, shape)) in self.plan.colliders.iter().enumerate() {
            let w = comp.mul(&s.models[*slot]);
            let zero = V3::splat(Vec3::ZERO);
            let half = F::splat(0.5);
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
            s.placed[c] = match *shape {
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
                    half: F::splat(0.0),
                },
            };
        }
    }

    /// The specification's update of every link, one pass in skeleton order (the scalar
    /// job's lazy refresh: a joint's model is recomputed once everything above it is).
    #[inline(always)]
    fn update(&self, pack: &mut Pack, s: &mut Scratch, three: bool) {
        let plan = self.plan;
        for slot in 0..plan.joints.len() {
            if !plan.affected[slot] {
                continue;
            }
            let parent = match plan.parent[slot] {
                Some(p) => Some(s.models[p]),
                None => None,
            };
            let local = s.locals[slot];
            match plan.link_at[slot] {
                None => s.models[slot] = under(parent.as_ref(), &local),
                Some(i) => {
                    let (rotation, own_t) = self.link(i, pack, s, parent.as_ref(), three);
                    s.models[slot] = match parent {
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
                }
            }
        }
    }

    /// One link: Verlet step, collisions, the joint turned toward the new tail.
    #[inline(always)]
    fn link(
        &self,
        i: usize,
        pack: &mut Pack,
        s: &Scratch,
        parent: Option<&Trs>,
        three: bool,
    ) -> (Q, V3) {
        let lp = &self.plan.links[i];
        let comp = s.component;
        let (parent_world, own_t) = match parent {
            Some(p) => (comp.mul(p), p.transform_point(s.locals[lp.slot].t)),
            None => (comp, s.models[lp.slot].t),
        };
        let position = comp.transform_point(own_t);
        let center = match lp.center {
            Some(c) => Some(comp.mul(&s.models[c])),
            None => None,
        };
        let (current, prev) = match &center {
            Some(c) => (
                c.transform_point(pack.current_tail[i]),
                c.transform_point(pack.prev_tail[i]),
            ),
            None => (pack.current_tail[i], pack.prev_tail[i]),
        };
        let rest_dir = parent_world.r.mul_vec3(V3::splat(lp.rest_bone));
        let inertia = (current - prev) * F::splat(lp.keep);
        let stiffness = rest_dir * F::splat(self.stiffness_dt[i]);
        let external = V3::splat(self.external[i]);
        let length = match (three, lp.tail_slot) {
            (true, Some(_)) => (pack.stale_tail[i] - position).length(),
            _ => pack.length[i],
        };
        let mut next = position
            + (current + inertia + stiffness + external - position).normalize_or(rest_dir) * length;
        for &c in &self.rig.link_colliders[lp.colliders.clone()] {
            let shape = &self.plan.colliders[c].1;
            if let Some((dir, dist, hit)) = contact(shape, &s.placed[c], next, lp.hit_radius) {
                let pushed =
                    position + (next - dir * dist - position).normalize_or(rest_dir) * length;
                next = V3::select(hit, pushed, next);
            }
        }
        pack.prev_tail[i] = pack.current_tail[i];
        pack.current_tail[i] = match &center {
            Some(c) => c.inverse_transform_point(next),
            None => next,
        };
        // Turn the joint toward the tail, from its rest frame under the current parent.
        let rest_world = parent_world.mul(&Trs::splat(&lp.rest_local));
        let to = rest_world
            .inverse_transform_point(next)
            .normalize_or(V3::splat(lp.bone_axis));
        let arc = rotation_arc_from(lp.arc_from, lp.half_turn, to);
        let rotation = Q::splat(lp.rest_local.rotation).mul_quat(arc).normalize();
        pack.rotation[i] = rotation;
        (rotation, own_t)
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
            bad = bad.or(stored.finite().not());
        }
        bad
    }

    /// three-vrm mode: where each tail node is at the end of the frame (the output pose).
    #[inline(always)]
    fn record_tails(&self, pack: &mut Pack, s: &mut Scratch) {
        let plan = self.plan;
        let comp = s.component;
        for slot in 0..plan.joints.len() {
            if !plan.affected[slot] {
                continue;
            }
            let mut local = s.locals[slot];
            if let Some(i) = plan.link_at[slot] {
                local.r = pack.rotation[i];
            }
            let m = match plan.parent[slot] {
                Some(p) => under(Some(&s.models[p]), &local),
                None => under(None, &local),
            };
            s.models[slot] = m;
        }
        for (i, lp) in plan.links.iter().enumerate() {
            pack.stale_tail[i] = match lp.tail_slot {
                Some(t) => comp.transform_point(s.models[t].t),
                None => comp
                    .mul(&s.models[lp.slot])
                    .transform_point(V3::splat(lp.tail_local)),
            };
        }
    }
}
