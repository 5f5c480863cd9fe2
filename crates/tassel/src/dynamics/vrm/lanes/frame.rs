//! One frame of a VRM lane group of characters ([`Ctx`]): the spring-bone frame of
//! [`crate::dynamics::vrm::VrmJob`] (every mode), reorganised for lanes: the rig's links
//! are sorted by joint (ancestors first), so its lazy model refresh is one pass over the
//! joints in skeleton order, and every branch that depends only on the rig (shape kinds,
//! centres, tails) is the same for all lanes. Branches that depend on a character's state
//! (a contact, a fallback, a reset) are computed for every lane and selected per lane.

use super::contact::{collide_tail, limit_lanes, Placed};
use super::pack::{LinkPlan, Pack, Plan, Scratch};
use crate::dynamics::path::FixedClock;
use crate::dynamics::vrm::{VrmMode, VrmRig, VrmShape};
use crate::error::Error;
#[cfg(target_arch = "x86_64")]
use crate::lanes::avx::Fa;
#[cfg(target_arch = "x86_64")]
use crate::lanes::avx512::Fz;
use crate::lanes::{rotation_arc_from, Isa, Lane, Mask, Trs, F, LANES, M, Q, V3};
use crate::math::Transform;
use crate::pose::CrowdPose;
use crate::skeleton::Skeleton;
use glam::Vec3;

/// What every lane group's step reads.
pub(crate) struct Ctx<'c> {
    pub(crate) sk: &'c Skeleton,
    pub(crate) rig: &'c VrmRig,
    pub(crate) plan: &'c Plan,
    pub(crate) stiffness_dt: &'c [f32],
    pub(crate) external: &'c [Vec3],
    pub(crate) dt: f32,
    pub(crate) isa: Isa,
}

impl Ctx<'_> {
    /// Loads, checks and steps one lane group in the lane type `self.isa` chose: the
    /// explicit AVX-512 or AVX2 type (`lanes/avx512.rs`, `lanes/avx.rs`; AVX2's was 1.2x
    /// faster than the same code over `F` compiled for AVX2, which was 1.5x faster than
    /// SSE2: `tassel bench --crowd 200 --vrm spec`), else over `F` with the baseline
    /// SSE2. Every lane operation of each is IEEE-exact, so all give the same bits.
    pub(crate) fn run<'a, I>(
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
        // (Only the x86-64 lane types need the choice.)
        #[cfg(not(target_arch = "x86_64"))]
        let _ = self.isa;
        self.gather::<F, I>(pack, scratch, base, input)?;
        self.step_baseline(pack, scratch);
        Ok(())
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    pub(crate) fn run_avx2<'a, I>(
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
    pub(crate) fn run_avx512<'a, I>(
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
    pub(crate) fn step_baseline(&self, pack: &mut Pack, s: &mut Scratch) {
        self.step_lanes::<F>(pack, s)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline(never)]
    pub(crate) fn step_avx2(&self, pack: &mut Pack, s: &mut Scratch) {
        self.step_lanes::<Fa>(pack, s)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
    #[inline(never)]
    pub(crate) fn step_avx512(&self, pack: &mut Pack, s: &mut Scratch) {
        self.step_lanes::<Fz>(pack, s)
    }

    /// Asks the caches for the animated poses `pack`'s next gather reads (group `base`),
    /// unless it will reuse its kept pose ([`crate::crowd::VrmCrowd::mark_pose_unchanged`]).
    /// A hint only: changes no value.
    pub(crate) fn prefetch_input<'a, I>(&self, pack: &Pack, base: usize, input: &I)
    where
        I: Fn(usize) -> CrowdPose<'a> + Sync,
    {
        if self.reuses(pack) {
            return;
        }
        for lane in 0..pack.count.min(LANES) {
            crate::lanes::prefetch(input(base + lane).locals);
        }
    }

    /// Whether `pack`'s gather will take its kept pose instead of its input: `fixed` mode,
    /// the pose kept as it came, every character marked unchanged.
    fn reuses(&self, pack: &Pack) -> bool {
        let used = pack.count.min(LANES);
        self.rig.options.mode == VrmMode::Fixed
            && self.rig.constraints.list.is_empty()
            && pack.prev_is_input
            && pack.unchanged[..used].iter().all(|&u| u)
    }

    /// [`Ctx::gather_checked`]'s result, faster where the input is good and no
    /// constraint applies: the poses are transposed into lanes first and checked there,
    /// eight characters per operation. Any failed check (or constraints) runs
    /// `gather_checked` itself, so the error is the same.
    #[inline(always)]
    pub(crate) fn gather<'a, T: Lane, I>(
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
        scratch.reused = false;
        if !self.rig.constraints.list.is_empty() {
            return self.gather_checked(pack, scratch, base, input);
        }
        let used = pack.count.min(LANES);
        if self.reuses(pack) {
            // Every character's locals are last frame's, which the group kept as they
            // came (checked then): only the transforms are read. One copy of the kept
            // pose, in order, instead of a transposition of every character's input.
            let mut component = Trs::splat(&Transform::IDENTITY);
            for lane in 0..used {
                let pose = input(base + lane);
                if pose.locals.len() != n || !pose.transform.within_limits() {
                    return self.gather_checked(pack, scratch, base, input);
                }
                component.set(lane, &pose.transform);
            }
            scratch.locals.copy_from_slice(&pack.prev_locals);
            scratch.component = component;
            scratch.reused = true;
            return Ok(());
        }
        let rest: &[Transform] = sk.rest();
        let mut poses = [rest; LANES];
        let mut component = Trs::splat(&Transform::IDENTITY);
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
    pub(crate) fn gather_checked<'a, I>(
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
pub(crate) fn within_limits<T: Lane>(t: &Trs<T>) -> T::M {
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
pub(crate) fn under<T: Lane>(models: &[Trs], parent: Option<usize>, local: &Trs) -> Trs<T> {
    let local = Trs::<T>::of(local);
    match parent {
        Some(p) => Trs::<T>::of(&models[p]).mul(&local),
        None => Trs::<T>::splat(&Transform::IDENTITY).mul(&local),
    }
}

/// The joints a frame (or a step) works on: the character transform, locals, models.
pub(crate) struct Poses<'p, T = F> {
    pub(crate) comp: Trs<T>,
    pub(crate) locals: &'p [Trs],
    pub(crate) models: &'p mut [Trs],
    /// The share of a step the update carries the motion and the forces by, per lane (the
    /// scalar job's `carry`: 1 and 1 but in fixed mode's output step).
    pub(crate) carry: (T, T),
}

impl<'p, T: Lane> Poses<'p, T> {
    /// The poses of a whole step (carrying the motion and the forces in full).
    #[inline(always)]
    fn step(comp: &Trs, locals: &'p [Trs], models: &'p mut [Trs]) -> Self {
        Poses {
            comp: Trs::<T>::of(comp),
            locals,
            models,
            carry: (T::splat(1.0), T::splat(1.0)),
        }
    }
}

// `match` rather than `Option::map` in the hot path: a closure is a function of its own,
// compiled without the AVX2 code generation of the function it is called from.
#[allow(clippy::manual_map)]
impl Ctx<'_> {
    /// One frame of one lane group, its hot part (the model pose, the colliders, the
    /// specification's update) computed in the lane type `T`.
    #[inline(always)]
    pub(crate) fn step_lanes<T: Lane>(&self, pack: &mut Pack, s: &mut Scratch) {
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
        // specification's update runs (fixed mode: on every frame), only of the slots it
        // reads before writing them: fixed mode's steps and output step also compose the
        // slots the springs move before reading them.
        let updates = (fixed || self.dt > 0.0) && reset != M::ALL;
        for k in 0..plan.joints.len() {
            if updates && !plan.read_animated[k] {
                continue;
            }
            s.models[k] = under::<T>(&s.models, plan.parent[k], &s.locals[k]).f();
        }
        // Fixed mode: the lanes whose last step ended on this frame.
        let mut on_frame = M::NONE;
        if reset != M::ALL {
            if fixed {
                on_frame = self.run_fixed::<T>(pack, s, reset);
            } else if self.dt > 0.0 {
                let Scratch {
                    locals,
                    models,
                    placed,
                    ..
                } = s;
                let mut poses = Poses::<T>::step(&comp, locals, models);
                self.step_on(pack, &mut poses, placed, mode, M::ALL);
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
        let on_frame = on_frame.and(again.not());
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
            self.fixed_output::<T>(pack, s, again, on_frame);
        } else {
            pack.out_rotation.copy_from_slice(&pack.rotation);
        }
        if mode == VrmMode::ThreeVrm {
            self.record_tails(pack, s);
        }
        pack.prev_component = comp;
        pack.needs_reset = [false; LANES];
        pack.unchanged = [false; LANES];
    }

    /// One update of the lanes in `active` on `poses`, its colliders placed from them.
    #[inline(always)]
    fn step_on<T: Lane>(
        &self,
        pack: &mut Pack,
        poses: &mut Poses<T>,
        placed: &mut [Placed],
        mode: VrmMode,
        active: M,
    ) {
        self.place_colliders(poses, placed);
        self.update(pack, poses, placed, mode, <T::M as Mask>::of(active));
    }

    #[inline(always)]
    pub(crate) fn place_colliders<T: Lane>(&self, poses: &Poses<T>, placed: &mut [Placed]) {
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
    pub(crate) fn update<T: Lane>(
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
    pub(crate) fn link<T: Lane>(
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
        let (carry_motion, carry_force) = poses.carry;
        let inertia = (current - prev) * T::splat(lp.keep) * carry_motion;
        let stiffness = rest_dir * T::splat(self.stiffness_dt[i]) * carry_force;
        let external = V3::<T>::splat(self.external[i]) * carry_force;
        let length = match (mode, lp.tail_slot) {
            (VrmMode::ThreeVrm, Some(_)) => (V3::of(pack.stale_tail[i]) - position).length(),
            _ => T::of(pack.length[i]),
        };
        let next = position
            + (current + inertia + stiffness + external - position).normalize_or(rest_dir) * length;
        // The draft limit after inertia (every lane: those not active are dropped below).
        let next = match &lp.limit {
            Some(lim) => {
                let every = <T::M as Mask>::NONE.not();
                limit_lanes(lim, parent_world.r, position, next, length, every)
            }
            None => next,
        };
        let (next, _) = self.collide_tail(
            lp,
            placed,
            parent_world.r,
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
    pub(crate) fn turn<T: Lane>(&self, lp: &LinkPlan, parent_world: &Trs<T>, tail: V3<T>) -> Q<T> {
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
    pub(crate) fn collide_tail<T: Lane>(
        &self,
        lp: &LinkPlan,
        placed: &[Placed],
        parent_r: Q<T>,
        position: V3<T>,
        length: T,
        rest_dir: V3<T>,
        tail: V3<T>,
        exact: bool,
    ) -> (V3<T>, T::M) {
        collide_tail(
            &self.rig.link_colliders[lp.colliders.clone()],
            None,
            &self.plan.colliders,
            placed,
            T::splat(lp.hit_radius),
            position,
            length,
            rest_dir,
            tail,
            exact,
            lp.limit.as_ref().map(|lim| (lim, parent_r)),
        )
    }

    /// Fixed mode: whole steps of `1/step_rate` up to now for the lanes not reset, each
    /// with the animated pose and the character transform interpolated to its time (a
    /// last step that ends on the frame on the frame's own pose). Returns the lanes whose
    /// last step ended on the frame, when the rig has no node constraints (the scalar
    /// job's `on_frame`).
    #[inline(always)]
    pub(crate) fn run_fixed<T: Lane>(&self, pack: &mut Pack, s: &mut Scratch, reset: M) -> M {
        let opts = &self.rig.options;
        let h = 1.0 / opts.step_rate;
        let dt = self.dt;
        let mut clocks = [None; LANES];
        let mut most = 0;
        for lane in 0..LANES {
            if reset.get(lane) {
                continue;
            }
            let clock = FixedClock::new(pack.accumulator[lane], dt, h, opts.max_steps_per_frame);
            pack.accumulator[lane] = clock.left;
            most = most.max(clock.steps);
            clocks[lane] = Some(clock);
        }
        let Scratch {
            locals,
            models,
            step_locals,
            step_models,
            placed,
            ..
        } = s;
        for k in 1..=most {
            let active = M::from_bools(std::array::from_fn(|l| {
                clocks[l].is_some_and(|c| k <= c.steps)
            }));
            let mut w = [1.0f32; LANES];
            let mut comp = Trs::<F>::splat(&Transform::IDENTITY);
            for lane in 0..LANES {
                // Where this step ends between last frame (0) and this frame (1).
                if let Some(c) = clocks[lane].filter(|c| k <= c.steps) {
                    w[lane] = c.end(k);
                }
                comp.set(lane, &pack.paths[lane].at(w[lane]));
            }
            let frame_pose = w.iter().all(|&w| w >= 1.0);
            if frame_pose && active == M::ALL && self.rig.constraints.list.is_empty() {
                // Every lane's last step ends on the frame: it steps on the frame's pose
                // itself. (Only a lane the guard resets runs an output step after it, on
                // the reset's models; the slots this update writes are not read again.)
                let mut poses = Poses::<T>::step(&comp, locals, models);
                self.step_on(pack, &mut poses, placed, VrmMode::Fixed, active);
                continue;
            }
            if frame_pose {
                // Some lanes' step ends on the frame: its pose is the frame's.
                step_locals.copy_from_slice(locals);
                step_models.copy_from_slice(models);
            } else {
                let w = F(w);
                let whole = F::splat(1.0).le(w);
                for slot in 0..self.plan.joints.len() {
                    let between = pack.prev_locals[slot].lerp(&locals[slot], w);
                    step_locals[slot] = Trs::select(whole, &locals[slot], &between);
                    // The scalar step refreshes every joint, a root as its local.
                    step_models[slot] = match self.plan.parent[slot] {
                        Some(p) => Trs::<T>::of(&step_models[p])
                            .mul(&Trs::of(&step_locals[slot]))
                            .f(),
                        None => step_locals[slot],
                    };
                }
            }
            let mut poses = Poses::<T>::step(&comp, step_locals, step_models);
            self.step_on(pack, &mut poses, placed, VrmMode::Fixed, active);
        }
        if !self.rig.constraints.list.is_empty() {
            return M::NONE;
        }
        M::from_bools(std::array::from_fn(|l| {
            clocks[l].is_some_and(|c| c.on_frame())
        }))
    }

    /// Fixed mode's output: the last step's rotations in the lanes `on_frame` (whose last
    /// step ended on this frame, on its pose and colliders), else those of an output step
    /// (the scalar job's `output_step`: `a` of a step from the last step's state on this
    /// frame's pose and colliders, not kept); and this frame's pose kept for the next
    /// frame's steps.
    #[inline(always)]
    pub(crate) fn fixed_output<T: Lane>(
        &self,
        pack: &mut Pack,
        s: &mut Scratch,
        reset: M,
        on_frame: M,
    ) {
        let plan = self.plan;
        let opts = &self.rig.options;
        let pass = on_frame.not();
        if pass == M::NONE {
            pack.out_rotation.copy_from_slice(&pack.rotation);
            self.keep_locals(pack, s, reset);
            return;
        }
        let mut a = [0.0f32; LANES];
        for lane in 0..LANES {
            a[lane] = (pack.accumulator[lane] * opts.step_rate).clamp(0.0, 1.0);
        }
        let a = T::of(F(a));
        // This frame's pose (the reset's where reset) and colliders.
        for slot in 0..plan.joints.len() {
            s.step_models[slot] = Trs::select(reset, &s.reset_models[slot], &s.models[slot]);
        }
        s.kept_current.copy_from_slice(&pack.current_tail);
        s.kept_prev.copy_from_slice(&pack.prev_tail);
        s.kept_rotation.copy_from_slice(&pack.rotation);
        let comp = s.component;
        let Scratch {
            locals,
            step_models,
            placed,
            ..
        } = s;
        let mut poses = Poses {
            carry: (a, a),
            ..Poses::<T>::step(&comp, locals, step_models)
        };
        self.step_on(pack, &mut poses, placed, VrmMode::Fixed, pass);
        pack.out_rotation.copy_from_slice(&pack.rotation);
        std::mem::swap(&mut pack.current_tail, &mut s.kept_current);
        std::mem::swap(&mut pack.prev_tail, &mut s.kept_prev);
        std::mem::swap(&mut pack.rotation, &mut s.kept_rotation);
        self.keep_locals(pack, s, reset);
    }

    /// This frame's pose kept for the next frame's steps (`pack.prev_locals`): the
    /// animated locals, with the rest rotations a reset wrote into the spring joints. The
    /// scratch's buffer is taken, not copied (a whole pose of lanes per group and frame):
    /// the scratch gets the old one, which the next group's gather fills again. So the
    /// last use of `s.locals` in a group's frame.
    #[inline(always)]
    fn keep_locals(&self, pack: &mut Pack, s: &mut Scratch, reset: M) {
        let plan = self.plan;
        let reset_any = reset.any();
        // A rig with node constraints keeps the constrained pose, not its input.
        pack.prev_is_input = !reset_any && self.rig.constraints.list.is_empty();
        if s.reused && !reset_any {
            // The kept pose is this frame's already.
            return;
        }
        if reset_any {
            for slot in 0..plan.joints.len() {
                if let Some(i) = plan.link_at[slot] {
                    let kept = &mut s.locals[slot];
                    kept.r = Q::select(reset, Q::splat(plan.links[i].rest_local.rotation), kept.r);
                }
            }
        }
        std::mem::swap(&mut pack.prev_locals, &mut s.locals);
    }

    /// The specification's initialisation for the lanes in `lanes`: joints at their rest
    /// rotation, tails where it puts them, no velocity. Returns the lanes whose reset
    /// state is itself not finite.
    #[inline(always)]
    pub(crate) fn reset(&self, pack: &mut Pack, s: &mut Scratch, lanes: M) -> M {
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

    /// The frame's output pose in `s`: `step_locals` the animated locals with the springs'
    /// output rotations, `models` their model transforms (identity above the roots, as the
    /// frame's last model pass) where a spring can move them; the other slots keep the
    /// animated models already in `models`.
    #[inline(always)]
    pub(crate) fn output_pose(&self, pack: &Pack, s: &mut Scratch) {
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
    pub(crate) fn record_tails(&self, pack: &mut Pack, s: &mut Scratch) {
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
