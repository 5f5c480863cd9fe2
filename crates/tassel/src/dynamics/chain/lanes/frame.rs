//! One frame of a chain lane group ([`Ctx`]): the chain job's frame reorganised for
//! lanes. Per character and in scalar code (the job's own functions): the input checks,
//! the placed colliders, the character's path, the write-back's checks. Per lane group:
//! the model pose, the animated targets, the motion, the solver steps and the output
//! pass ([`super::step`]), where a character's own branches (a reset, a step count, a
//! contact) are lane masks and the narrow phase asks the scalar colliders for the lanes
//! whose point may touch one.

use super::pack::{Pack, Scratch};
use super::step::{output_lanes, step_lanes, Ahead, LaneShape, LaneStep, NO_AHEAD};
use crate::dynamics::chain::compile::{ChainRig, NONE, VIRTUAL};
use crate::dynamics::chain::job::{
    gravity_cs, motion_cs, place_colliders, slerp_angle, wind_cs, ON_STEP,
};
use crate::dynamics::chain::step::gravity_step;
use crate::dynamics::chain::{ChainSettings, ClassicGravity, PlanarAxis, TimeMode};
use crate::error::{Error, Result};
#[cfg(target_arch = "x86_64")]
use crate::lanes::avx::Fa;
#[cfg(target_arch = "x86_64")]
use crate::lanes::avx512::Fz;
use crate::lanes::{rotation_arc, Isa, Lane, Mask, Trs, F, LANES, M, Q, V3};
use crate::math::Transform;
use crate::pose::CrowdPose;
use crate::skeleton::Skeleton;
use glam::{Quat, Vec3};

/// What one frame of a character's twin-chain lanes reads besides the chains' input.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LaneFrame {
    /// The character's world transform this frame.
    pub component: Transform,
    /// Frame time, seconds.
    pub dt: f32,
    /// The lane code that runs it.
    pub isa: Isa,
}

/// What every lane group's frame reads.
pub(crate) struct Ctx<'c> {
    pub(crate) sk: &'c Skeleton,
    pub(crate) rig: &'c ChainRig,
    /// Each rig collider's shape as the lanes see it.
    pub(crate) shapes: &'c [LaneShape],
    /// Some chain has a planar constraint (only such chains read the planar normals).
    pub(crate) planar: bool,
    pub(crate) dt: f32,
    pub(crate) isa: Isa,
}

/// Whether some chain of `rig` has a planar constraint.
pub(crate) fn any_planar(rig: &ChainRig) -> bool {
    rig.chains
        .iter()
        .any(|c| c.settings.planar_constraint != PlanarAxis::None)
}

/// The per-lane inputs of a step that depend on where each character is: its motion since
/// `from` (none when `from` is `None`), gravity's share and the wind, for the `active`
/// lanes.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Motion {
    pub(crate) move_cs: V3,
    pub(crate) rotate_cs: Q,
    pub(crate) gravity_step: V3,
    pub(crate) wind_cs: V3,
    pub(crate) wind_on: M,
}

/// The last [`motion`] computed, with everything it was computed from: the chains of a
/// character mostly step with the same settings between the same transforms, so a lane
/// group's other chains get it again without computing it.
#[derive(Debug, Clone)]
pub(crate) struct MotionMemo {
    /// The settings' fields `motion` reads: gravity in world space, gravity, wind
    /// direction and speed, classic gravity; `None` before the first.
    pub(crate) settings: Option<(bool, Vec3, Vec3, f32, ClassicGravity)>,
    pub(crate) dt: f32,
    pub(crate) fixed: bool,
    pub(crate) from: Option<Trs>,
    pub(crate) to: Trs,
    /// The lanes it was computed for.
    pub(crate) active: M,
    pub(crate) out: Motion,
    /// Calls answered from the memo (for the tests).
    #[cfg(test)]
    pub(crate) hits: usize,
}

impl MotionMemo {
    pub(crate) fn new() -> MotionMemo {
        MotionMemo {
            settings: None,
            dt: 0.0,
            fixed: false,
            from: None,
            to: Trs::splat(&Transform::IDENTITY),
            active: M::NONE,
            out: Motion {
                move_cs: V3::splat(Vec3::ZERO),
                rotate_cs: Q::splat(Quat::IDENTITY),
                gravity_step: V3::splat(Vec3::ZERO),
                wind_cs: V3::splat(Vec3::ZERO),
                wind_on: M::NONE,
            },
            #[cfg(test)]
            hits: 0,
        }
    }
}

/// The fields of `s` that [`motion`] reads.
pub(crate) fn motion_settings(s: &ChainSettings) -> (bool, Vec3, Vec3, f32, ClassicGravity) {
    (
        s.gravity_in_world,
        s.gravity,
        s.wind.direction,
        s.wind.speed,
        s.classic_gravity,
    )
}

/// The ten lane fields of a transform (translation, rotation, scale).
#[inline(always)]
pub(crate) fn fields(a: &Trs) -> [&F; 10] {
    [
        &a.t.x, &a.t.y, &a.t.z, &a.r.x, &a.r.y, &a.r.z, &a.r.w, &a.s.x, &a.s.y, &a.s.z,
    ]
}

/// Whether the lanes `m` of `a` and `b` hold the same bits.
#[inline]
pub(crate) fn same_lanes(a: &Trs, b: &Trs, m: M) -> bool {
    // The differing bits of every field in the lanes of `m`, ORed together (no branch).
    let differ = |x: &F, y: &F| {
        (0..LANES).fold(0, |d, l| {
            d | ((x.0[l].to_bits() ^ y.0[l].to_bits()) & m.0[l])
        })
    };
    let d = fields(a)
        .iter()
        .zip(fields(b))
        .fold(0, |d, (x, y)| d | differ(x, y));
    d == 0
}

/// [`motion`], or the memo's when it was computed from the same (bit for bit) for every
/// lane of `active`; the memo then holds this one.
#[allow(clippy::too_many_arguments)]
pub(crate) fn motion_memo(
    memo: &mut MotionMemo,
    s: &ChainSettings,
    from: Option<&Trs>,
    to: &Trs,
    dt: f32,
    fixed: bool,
    active: M,
    shared: bool,
) -> Motion {
    let settings = motion_settings(s);
    let same_settings = memo.settings.is_some_and(|(g, gv, wd, ws, c)| {
        let (g2, gv2, wd2, ws2, c2) = settings;
        g == g2
            && crate::math::same_bits(gv, gv2)
            && crate::math::same_bits(wd, wd2)
            && ws.to_bits() == ws2.to_bits()
            && c == c2
    });
    let hit = same_settings
        && memo.dt.to_bits() == dt.to_bits()
        && memo.fixed == fixed
        && active.and(memo.active.not()) == M::NONE
        && match (from, &memo.from) {
            (None, None) => true,
            (Some(a), Some(b)) => same_lanes(a, b, active),
            _ => false,
        }
        && same_lanes(to, &memo.to, active);
    if !hit {
        memo.out = motion(s, from, to, dt, fixed, active, shared);
        memo.settings = Some(settings);
        memo.dt = dt;
        memo.fixed = fixed;
        memo.from = from.copied();
        memo.to = *to;
        memo.active = active;
    }
    #[cfg(test)]
    {
        memo.hits += usize::from(hit);
    }
    memo.out
}

pub(crate) fn motion(
    s: &ChainSettings,
    from: Option<&Trs>,
    to: &Trs,
    dt: f32,
    fixed: bool,
    active: M,
    shared: bool,
) -> Motion {
    let mut out = Motion {
        move_cs: V3::splat(Vec3::ZERO),
        rotate_cs: Q::splat(Quat::IDENTITY),
        gravity_step: V3::splat(Vec3::ZERO),
        wind_cs: V3::splat(Vec3::ZERO),
        wind_on: M::NONE,
    };
    let mut wind = [false; LANES];
    // One character in every lane, every active lane between the same transforms (bit
    // for bit) as the first: that lane's motion is every lane's (the same function of
    // the same values).
    if let Some(k) = (0..LANES).find(|&l| active.0[l] != 0).filter(|&k| {
        // `same_lanes` against lane `k` in every lane.
        let as_k = |a: &Trs| same_lanes(a, &Trs::splat(&a.get(k)), active);
        shared && as_k(to) && from.is_none_or(as_k)
    }) {
        let b = to.get(k);
        let (m, r) = match from {
            Some(a) => motion_cs(&a.get(k), &b),
            None => (Vec3::ZERO, Quat::IDENTITY),
        };
        let g = gravity_step(s, gravity_cs(s, &b), dt, fixed);
        let w = wind_cs(s, &b);
        let on = s.wind.speed > 0.0 && w != Vec3::ZERO;
        let pick = |v: Vec3, rest: &V3| V3::select(active, V3::splat(v), *rest);
        out.move_cs = pick(m, &out.move_cs);
        out.rotate_cs = Q::select(active, Q::splat(r), out.rotate_cs);
        out.gravity_step = pick(g, &out.gravity_step);
        out.wind_cs = pick(w, &out.wind_cs);
        out.wind_on = if on { active } else { M::NONE };
        return out;
    }
    let mut last: Option<usize> = None;
    for l in 0..LANES {
        if active.0[l] == 0 {
            continue;
        }
        let b = to.get(l);
        // One character in every lane: a lane whose transforms have the bits of the last
        // lane computed gets that lane's motion.
        if let Some(k) = last.filter(|&k| {
            shared
                && same_bits(&to.get(k), &b)
                && from.is_none_or(|a| same_bits(&a.get(k), &a.get(l)))
        }) {
            out.move_cs.set(l, out.move_cs.get(k));
            out.rotate_cs.set(l, out.rotate_cs.get(k));
            out.gravity_step.set(l, out.gravity_step.get(k));
            out.wind_cs.set(l, out.wind_cs.get(k));
            wind[l] = wind[k];
            continue;
        }
        last = Some(l);
        let wind = &mut wind[l];
        if let Some(a) = from {
            let (m, r) = motion_cs(&a.get(l), &b);
            out.move_cs.set(l, m);
            out.rotate_cs.set(l, r);
        }
        out.gravity_step
            .set(l, gravity_step(s, gravity_cs(s, &b), dt, fixed));
        let w = wind_cs(s, &b);
        out.wind_cs.set(l, w);
        *wind = s.wind.speed > 0.0 && w != Vec3::ZERO;
    }
    out.wind_on = M::from_bools(wind);
    out
}

/// Whether two transforms are the same bits.
pub(crate) fn same_bits(a: &Transform, b: &Transform) -> bool {
    let q = |x: Quat| x.to_array().map(f32::to_bits);
    crate::math::same_bits(a.translation, b.translation)
        && q(a.rotation) == q(b.rotation)
        && crate::math::same_bits(a.scale, b.scale)
}

/// Checks one character's input: the pose's length, finite unit-rotation locals within
/// the limits, a finite transform within them.
pub(crate) fn check_pose(sk: &Skeleton, i: usize, pose: &CrowdPose) -> Result<()> {
    let n = sk.len();
    if pose.locals.len() != n {
        return Err(Error::LengthMismatch {
            what: "crowd character's animated pose",
            expected: n,
            got: pose.locals.len(),
        });
    }
    check_locals(sk, i, pose.locals)?;
    if !pose.transform.within_limits() {
        return Err(Error::NonFinite(format!(
            "crowd character {i}: transform is not finite or lies beyond {:e}",
            crate::limits::MAX_COORDINATE
        )));
    }
    Ok(())
}

/// [`check_pose`]'s check of the animated locals (of the skeleton's length).
pub(crate) fn check_locals(sk: &Skeleton, i: usize, locals: &[Transform]) -> Result<()> {
    if let Some(j) = locals.iter().position(|t| !t.within_limits()) {
        return Err(Error::NonFinite(format!(
            "crowd character {i}: animated pose of joint '{}' is not finite, not a unit \
             rotation, or lies beyond {:e}",
            sk.name(j),
            crate::limits::MAX_COORDINATE
        )));
    }
    Ok(())
}

/// The model pose of the first `count` lanes from their animated `locals`, into
/// `s.lane_models`:
/// [`crate::pose::local_to_model_into`] for [`LANES`] characters at once. [`Trs::mul`] is
/// [`Transform::mul_transform`] operation for operation, so each lane gets the bits the
/// scalar job gives (the identity above the roots, as there).
/// Returns the lanes with a non-finite model transform, and the lanes whose locals may
/// not all lie within the input limits ([`Transform::within_limits`]: every coordinate
/// checked exactly, the rotation's squared norm with a margin far above its rounding;
/// [`check_locals`] decides for these).
#[inline(always)]
pub(crate) fn model_pose_lanes<T: Lane>(
    sk: &Skeleton,
    locals: &[&[Transform]; LANES],
    s: &mut Scratch,
    count: usize,
) -> (M, M) {
    let n = sk.len();
    let mut bad = <T::M as Mask>::NONE;
    let mut sure = <T::M as Mask>::ALL;
    let max = T::splat(crate::limits::MAX_COORDINATE);
    for j in 0..n {
        let lane_locals = std::array::from_fn(|l| match l < count {
            true => &locals[l][j],
            false => &Transform::IDENTITY,
        });
        let local = T::transforms(&lane_locals);
        s.lane_local_rotations[j] = local.r.f();
        let (t, sc) = (local.t.abs(), local.s.abs());
        let unit = (local.r.dot(local.r) - T::splat(1.0))
            .abs()
            .le(T::splat(0.2));
        sure = sure.and(unit).and(within(t, max)).and(within(sc, max));
        let model = match sk.parent(j) {
            Some(p) => Trs::<T>::of(&s.lane_models[p]).mul(&local),
            None => Trs::<T>::splat(&Transform::IDENTITY).mul(&local),
        };
        bad = bad.or(model
            .t
            .finite()
            .and(model.r.finite())
            .and(model.s.finite())
            .not());
        s.lane_models[j] = model.f();
    }
    (bad.m(), sure.not().m())
}

/// Every coordinate of `v` at most `max`, per lane. (A function, not a closure: see
/// `collide::lanes::select_max`.)
#[inline(always)]
pub(crate) fn within<T: Lane>(v: V3<T>, max: T) -> T::M {
    v.x.le(max).and(v.y.le(max)).and(v.z.le(max))
}

/// `gather_targets`' animated targets and planar normals per point (the normals of chains
/// with a planar constraint only), for every lane at once from the lane pose, by its
/// operations (each lane gets the scalar function's bits).
#[inline(always)]
pub(crate) fn targets_lanes<T: Lane>(sk: &Skeleton, rig: &ChainRig, s: &mut Scratch) {
    let models = &s.lane_models;
    let y = V3::<T>::splat(Vec3::Y);
    for (p, axis) in rig.points_and_planar_axes() {
        let j = rig.joint[p];
        let parent = rig.parent[p];
        s.targets[p] = if j == VIRTUAL {
            let leaf = rig.joint[parent as usize] as usize;
            let m = Trs::<T>::of(&models[leaf]);
            let up = m.r.mul_vec3(y);
            let dir = match sk.parent(leaf) {
                Some(q) => (m.t - V3::<T>::of(models[q].t)).normalize_or(up),
                None => up,
            };
            (m.t + dir * T::splat(rig.dummy_length[p])).f()
        } else {
            models[j as usize].t
        };
        // The planar normal only where a step reads it (its chain's constraint is on).
        if let (true, Some(axis)) = (parent != NONE, axis) {
            let pj = rig.joint[parent as usize] as usize;
            let axis = V3::splat(axis);
            s.normals[p] = Q::<T>::of(models[pj].r).mul_vec3(axis).f();
        }
    }
}

impl Ctx<'_> {
    /// Checks the group's input and computes its animated targets and colliders into
    /// `scratch`. Touches no state.
    pub(crate) fn gather<'a, I>(
        &self,
        pack: &Pack,
        scratch: &mut Scratch,
        base: usize,
        input: &I,
    ) -> std::result::Result<(), (usize, Error)>
    where
        I: Fn(usize) -> CrowdPose<'a> + Sync,
    {
        let (sk, rig) = (self.sk, self.rig);
        let n = sk.len();
        let m = rig.colliders.len();
        // First each lane's input, checked and copied, up to the first bad one; then the
        // model pose, targets and normals of those lanes at once; then per lane, in
        // order, the model pose's check (so the error named is the one the lane-by-lane
        // order meets first) and the colliders.
        // (The locals' limits are checked in lanes with the model pose, and lane by lane
        // only where the lanes are unsure; a lane's errors still come in `check_pose`'s
        // order, and the first lane's with one is the one reported.)
        let mut first_bad = None;
        let mut locals: [&[Transform]; LANES] = [&[]; LANES];
        for lane in 0..pack.count {
            let i = base + lane;
            let pose = input(i);
            if pose.locals.len() != n || !pose.transform.within_limits() {
                if let Err(e) = check_pose(sk, i, &pose) {
                    first_bad = Some((lane, e));
                    break;
                }
            }
            scratch.component.set(lane, &pose.transform);
            locals[lane] = pose.locals;
        }
        let good = first_bad.as_ref().map_or(pack.count, |(lane, _)| *lane);
        let (not_finite, unsure) = self.model_pose(&locals, scratch, good);
        for lane in 0..good {
            let i = base + lane;
            if unsure.get(lane) {
                check_locals(sk, i, locals[lane]).map_err(|e| (lane, e))?;
            }
            let lane_models = &scratch.lane_models;
            let first_not_finite = || (0..n).position(|j| !lane_models[j].get(lane).is_finite());
            if let Some(j) = not_finite.get(lane).then(first_not_finite).flatten() {
                return Err((
                    lane,
                    Error::NonFinite(format!(
                        "crowd character {i}: animated pose of joint '{}'",
                        sk.name(j)
                    )),
                ));
            }
            // The colliders' bones' models out of the lanes (no other joint is read).
            let models = &mut scratch.models[lane * n..(lane + 1) * n];
            for c in &rig.colliders {
                models[c.bone] = scratch.lane_models[c.bone].get(lane);
            }
            let colliders = &mut scratch.colliders[lane * m..(lane + 1) * m];
            place_colliders(rig, models, colliders);
            for (b, c) in scratch.bounds.iter_mut().zip(colliders.iter()) {
                b.set(lane, c);
            }
        }
        match first_bad {
            Some(bad) => Err(bad),
            None => Ok(()),
        }
    }

    /// [`model_pose_lanes`] and [`targets_lanes`] with AVX2 where the CPU has it (as
    /// [`Ctx::step`]): the lanes with a non-finite model transform, and the lanes whose
    /// locals the lanes could not vouch for (as `model_pose_lanes`).
    pub(crate) fn model_pose(
        &self,
        locals: &[&[Transform]; LANES],
        s: &mut Scratch,
        count: usize,
    ) -> (M, M) {
        // SAFETY (both): the function only requires the instructions of its lane type,
        // and `Isa::of` chose that type because the CPU has them.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        match self.isa {
            Isa::Avx512 => return unsafe { self.model_pose_avx512(locals, s, count) },
            Isa::Avx2 => return unsafe { self.model_pose_avx2(locals, s, count) },
            Isa::Portable => {}
        }
        // (Only the x86-64 lane types need the choice.)
        #[cfg(not(target_arch = "x86_64"))]
        let _ = self.isa;
        self.model_pose_in::<F>(locals, s, count)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    pub(crate) fn model_pose_avx2(
        &self,
        locals: &[&[Transform]; LANES],
        s: &mut Scratch,
        count: usize,
    ) -> (M, M) {
        // The explicit AVX2 lane type, only here after the CPU was found to have AVX2.
        self.model_pose_in::<Fa>(locals, s, count)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
    pub(crate) fn model_pose_avx512(
        &self,
        locals: &[&[Transform]; LANES],
        s: &mut Scratch,
        count: usize,
    ) -> (M, M) {
        // The explicit AVX-512 lane type, only here after the CPU was found to have it.
        self.model_pose_in::<Fz>(locals, s, count)
    }

    #[inline(always)]
    pub(crate) fn model_pose_in<T: Lane>(
        &self,
        locals: &[&[Transform]; LANES],
        s: &mut Scratch,
        count: usize,
    ) -> (M, M) {
        let bad = model_pose_lanes::<T>(self.sk, locals, s, count);
        targets_lanes::<T>(self.sk, self.rig, s);
        bad
    }

    /// One frame of one lane group whose input is in `s`, in the lane type `self.isa`
    /// chose (the explicit AVX-512 or AVX2 type, `lanes/avx512.rs`, `lanes/avx.rs`, else
    /// [`F`] with the baseline SSE2). Every lane operation of each is IEEE-exact, so all
    /// give the same bits.
    /// `write_back`: also the rotators' rotations per lane (a crowd's characters; twin
    /// chains have their own write-back).
    pub(crate) fn step(
        &self,
        pack: &mut Pack,
        s: &mut Scratch,
        write_back: bool,
        next: Option<&Pack>,
    ) {
        // SAFETY (both): the function only requires the instructions of its lane type,
        // and `Isa::of` chose that type because the CPU has them.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        match self.isa {
            Isa::Avx512 => return unsafe { self.step_avx512(pack, s, write_back, next) },
            Isa::Avx2 => return unsafe { self.step_avx2(pack, s, write_back, next) },
            Isa::Portable => {}
        }
        self.step_lanes::<F>(pack, s, write_back, next)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    pub(crate) fn step_avx2(
        &self,
        pack: &mut Pack,
        s: &mut Scratch,
        write_back: bool,
        next: Option<&Pack>,
    ) {
        // The explicit AVX2 lane type, only here after the CPU was found to have AVX2.
        self.step_lanes::<Fa>(pack, s, write_back, next)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
    pub(crate) fn step_avx512(
        &self,
        pack: &mut Pack,
        s: &mut Scratch,
        write_back: bool,
        next: Option<&Pack>,
    ) {
        // The explicit AVX-512 lane type, only here after the CPU was found to have it.
        self.step_lanes::<Fz>(pack, s, write_back, next)
    }

    /// One frame of one lane group whose input is in `scratch`; the solver steps
    /// computed in the lane type `T`.
    #[inline(always)]
    pub(crate) fn step_lanes<T: Lane>(
        &self,
        pack: &mut Pack,
        s: &mut Scratch,
        write_back: bool,
        next: Option<&Pack>,
    ) {
        self.run_chains::<T>(pack, s, next.map_or(NO_AHEAD, Pack::ahead));
        if write_back {
            self.write_back(pack, s, next);
        }
    }

    /// Every chain of the rig for the group's lanes, up to their output points (no
    /// write-back).
    #[inline(always)]
    pub(crate) fn run_chains<T: Lane>(&self, pack: &mut Pack, s: &mut Scratch, ahead: Ahead) {
        let rig = self.rig;
        let live = M::from_bools(std::array::from_fn(|l| l < pack.count));
        for l in 0..pack.count {
            pack.paths[l].push(s.component.get(l), self.dt);
        }
        s.step_placed_at.fill(f32::NAN);
        s.path_w = [f32::NAN; LANES];
        // The teleport test's measures, once per lane (every chain compares them with its
        // own thresholds).
        for l in 0..pack.count {
            let (a, b) = (pack.prev_component.get(l), s.component.get(l));
            let moved = (b.translation - a.translation).length();
            let turned = slerp_angle(a.rotation, b.rotation).to_degrees();
            s.jump[l] = (moved, turned);
        }
        for ci in 0..rig.chains.len() {
            self.run_chain::<T>(ci, pack, s, live, ahead);
        }
        pack.prev_targets.copy_from_slice(&s.targets);
        // The normals are read only by chains with a planar constraint.
        if self.planar {
            pack.prev_normals.copy_from_slice(&s.normals);
        }
        let kept = match pack.shared {
            true => pack.prev_colliders.len() / LANES,
            false => pack.prev_colliders.len(),
        };
        pack.prev_colliders[..kept].copy_from_slice(&s.colliders[..kept]);
        pack.prev_component = s.component;
    }

    /// The chain job's `write_back` per lane: each rotator joint turned toward its
    /// simulated children (mean direction) on top of its animated rotation; its local
    /// rotation is kept per lane.
    #[inline(always)]
    pub(crate) fn write_back(&self, pack: &mut Pack, s: &mut Scratch, next: Option<&Pack>) {
        let (sk, rig) = (self.sk, self.rig);
        // The animated model rotations (in the lanes not in use: of identity locals,
        // never read).
        for &(j, _, _) in &rig.rotators {
            let j = j as usize;
            for k in std::iter::once(j).chain(sk.parent(j)) {
                s.rotations[k] = s.lane_models[k].r;
            }
        }
        let zero = V3::splat(Vec3::ZERO);
        let tiny = F::splat(1e-12);
        // Two passes: first every rotator's new model rotation (each reads only its own
        // joint's animated one, so the processor overlaps the rotators' long chains of
        // roots and divisions), then every local rotation, which reads its parent's new
        // model rotation. The same operations on the same values.
        for (k, ((joint, point, kids), turn)) in
            rig.rotators.iter().zip(&mut s.new_rotations).enumerate()
        {
            // The next group's rotation of this rotator, on its way (as `Ahead`).
            if let Some(next) = next {
                crate::lanes::prefetch(&next.out_rotation[k..k + 1]);
            }
            let (j, p) = (*joint as usize, *point as usize);
            let (mut anim, mut sim) = (zero, zero);
            for &c in &rig.rotator_children[kids.start as usize..kids.end as usize] {
                let c = c as usize;
                anim = anim + (s.targets[c] - s.targets[p]).normalize_or(zero);
                sim = sim + (pack.out[c] - pack.out[p]).normalize_or(zero);
            }
            let skip = anim.dot(anim).lt(tiny).or(sim.dot(sim).lt(tiny));
            let new_rot = rotation_arc(anim, sim).mul_quat(s.rotations[j]).normalize();
            *turn = (new_rot, skip);
        }
        for (k, (joint, _, _)) in rig.rotators.iter().enumerate() {
            let j = *joint as usize;
            let (new_rot, skip) = s.new_rotations[k];
            let parent_rot = match sk.parent(j) {
                Some(q) => s.rotations[q],
                None => Q::splat(Quat::IDENTITY),
            };
            let local = parent_rot.conjugate().mul_quat(new_rot).normalize();
            let animated = s.lane_local_rotations[j];
            pack.out_rotation[k] = Q::select(skip, animated, local);
            s.rotations[j] = Q::select(skip, s.rotations[j], new_rot);
        }
    }

    #[inline(always)]
    pub(crate) fn run_chain<T: Lane>(
        &self,
        ci: usize,
        pack: &mut Pack,
        s: &mut Scratch,
        live: M,
        ahead: Ahead,
    ) {
        let rig = self.rig;
        let set = &rig.chains[ci].settings;
        let points = rig.chains[ci].points.clone();
        // Teleport detection on each character's own motion this frame.
        for l in 0..pack.count {
            if pack.needs_reset[ci][l] {
                continue;
            }
            let (moved, turned) = s.jump[l];
            if (set.teleport_distance > 0.0 && moved > set.teleport_distance)
                || (set.teleport_rotation > 0.0 && turned > set.teleport_rotation)
            {
                pack.needs_reset[ci][l] = true;
                pack.teleports[l] += 1;
            }
        }
        let reset = M::from_bools(pack.needs_reset[ci]).and(live);
        if reset.any() {
            self.reset_chain::<T>(ci, pack, s, reset);
        }
        let run = live.and(reset.not());
        if run.any() {
            match set.mode {
                TimeMode::Classic => self.run_classic::<T>(ci, pack, s, run, ahead),
                TimeMode::Fixed => self.run_fixed::<T>(ci, pack, s, run, ahead),
                // `kawaii` chains step per character (`CompiledChain::scalar_only`): the
                // lanes never hold one.
                TimeMode::Kawaii => {
                    debug_assert!(false, "a kawaii chain in lanes");
                    self.run_classic::<T>(ci, pack, s, run, ahead)
                }
            }
        }
        // Guard: never let a non-finite value out; start again from the pose instead.
        let mut bad = M::NONE;
        for p in points.clone() {
            bad = bad.or(pack.pos[p].finite().not());
        }
        let bad = bad.and(live);
        if bad.any() {
            for l in 0..LANES {
                if bad.0[l] != 0 {
                    pack.teleports[l] += 1;
                }
            }
            self.reset_chain::<T>(ci, pack, s, bad);
        }
        // The lanes the output pass writes: every live one, but in fixed mode with an
        // alpha of 1 only those that started again this frame (as the chain job's
        // `output_chain`).
        let mut pass = live;
        if set.mode == TimeMode::Fixed {
            // `out` holds the points at the frame's end, as the chain job's `output_step`
            // puts them there; the output pass blends them by alpha.
            self.output_step::<T>(ci, pack, s, live);
            if set.alpha == 1.0 {
                pass = reset.or(bad);
                if !pass.any() {
                    return;
                }
            }
            for p in points {
                let d = pack.out[p] - s.targets[p];
                pack.dev[p] = d;
                pack.dev_before[p] = d;
            }
        }
        output_lanes::<T>(
            rig,
            ci,
            F::splat(1.0),
            &s.targets,
            &pack.dev_before,
            &pack.dev,
            &s.colliders,
            pack.collider_stride(),
            &s.bounds,
            self.shapes,
            &mut pack.out,
            pass,
            &mut s.near,
        );
    }

    /// The chain job's `output_step` for the `live` lanes: each lane's points at the
    /// frame's end in `out`, its last step's, or the share of one more step its time
    /// left over makes, on the frame's targets and colliders, not kept.
    #[inline(always)]
    pub(crate) fn output_step<T: Lane>(
        &self,
        ci: usize,
        pack: &mut Pack,
        s: &mut Scratch,
        live: M,
    ) {
        let rig = self.rig;
        let set = &rig.chains[ci].settings;
        let points = rig.chains[ci].points.clone();
        pack.out[points.clone()].copy_from_slice(&pack.pos[points.clone()]);
        let h = 1.0 / set.target_framerate;
        let left = pack.accumulator[ci];
        let on = M::from_bools(std::array::from_fn(|l| {
            live.0[l] != 0 && left.0[l] > ON_STEP * h
        }));
        if !on.any() {
            return;
        }
        s.keep_prev[points.clone()].copy_from_slice(&pack.prev[points]);
        // Each lane's part of a step, and gravity's part of it.
        let part = F(std::array::from_fn(|l| {
            if on.0[l] != 0 {
                left.0[l] / h
            } else {
                1.0
            }
        }));
        let mut mo = motion(
            set,
            Some(&pack.last_step_component[ci]),
            &s.component,
            h,
            true,
            on,
            pack.shared,
        );
        for l in 0..LANES {
            if on.0[l] != 0 {
                mo.gravity_step.set(l, mo.gravity_step.get(l) * part.0[l]);
            }
        }
        let input = LaneStep {
            targets: &s.targets,
            normals: &s.normals,
            colliders: &s.colliders,
            stride: pack.collider_stride(),
            bounds: &s.bounds,
            shapes: self.shapes,
            move_cs: mo.move_cs,
            rotate_cs: mo.rotate_cs,
            gravity_step: mo.gravity_step,
            wind_cs: mo.wind_cs,
            wind_on: mo.wind_on,
            dt: h,
            dt_old: F::splat(h),
            part: Some(part),
            active: on,
            ahead: NO_AHEAD,
        };
        let mut rng = pack.rng[ci];
        step_lanes::<T>(
            rig,
            ci,
            &input,
            &mut pack.out,
            &mut s.keep_prev,
            &mut rng,
            &mut s.near,
        );
    }

    /// The chain job's `reset_chain` for the lanes `m`.
    #[inline(always)]
    pub(crate) fn reset_chain<T: Lane>(&self, ci: usize, pack: &mut Pack, s: &mut Scratch, m: M) {
        let rig = self.rig;
        let set = &rig.chains[ci].settings;
        let points = rig.chains[ci].points.clone();
        let zero = V3::splat(Vec3::ZERO);
        for p in points.clone() {
            let t = s.targets[p];
            pack.pos[p] = V3::select(m, t, pack.pos[p]);
            pack.prev[p] = V3::select(m, t, pack.prev[p]);
            pack.dev[p] = V3::select(m, zero, pack.dev[p]);
            pack.dev_before[p] = V3::select(m, zero, pack.dev_before[p]);
            pack.prev_targets[p] = V3::select(m, t, pack.prev_targets[p]);
            pack.prev_normals[p] = V3::select(m, s.normals[p], pack.prev_normals[p]);
        }
        pack.accumulator[ci] = F::select(m, F::splat(0.0), pack.accumulator[ci]);
        pack.last_step_component[ci] = Trs::select(m, &s.component, &pack.last_step_component[ci]);
        let h = 1.0 / set.target_framerate;
        pack.dt_old[ci] = F::select(m, F::splat(h), pack.dt_old[ci]);
        // Warm-up: settle in place with the current targets and no character motion.
        let fixed = set.mode == TimeMode::Fixed;
        if set.warmup_steps > 0 {
            let mo = motion_memo(
                &mut s.motion,
                set,
                None,
                &s.component,
                h,
                fixed,
                m,
                pack.shared,
            );
            for _ in 0..set.warmup_steps {
                let input = LaneStep {
                    targets: &s.targets,
                    normals: &s.normals,
                    colliders: &s.colliders,
                    stride: pack.collider_stride(),
                    bounds: &s.bounds,
                    shapes: self.shapes,
                    move_cs: mo.move_cs,
                    rotate_cs: mo.rotate_cs,
                    gravity_step: mo.gravity_step,
                    wind_cs: mo.wind_cs,
                    wind_on: mo.wind_on,
                    dt: h,
                    dt_old: F::splat(h),
                    part: None,
                    active: m,
                    ahead: NO_AHEAD,
                };
                step_lanes::<T>(
                    rig,
                    ci,
                    &input,
                    &mut pack.pos,
                    &mut pack.prev,
                    &mut pack.rng[ci],
                    &mut s.near,
                );
            }
        }
        for p in points {
            let d = pack.pos[p] - s.targets[p];
            pack.dev[p] = V3::select(m, d, pack.dev[p]);
            pack.dev_before[p] = V3::select(m, d, pack.dev_before[p]);
        }
        for l in 0..LANES {
            if m.0[l] != 0 {
                pack.needs_reset[ci][l] = false;
            }
        }
    }

    #[inline(always)]
    pub(crate) fn run_classic<T: Lane>(
        &self,
        ci: usize,
        pack: &mut Pack,
        s: &mut Scratch,
        run: M,
        ahead: Ahead,
    ) {
        let rig = self.rig;
        let set = &rig.chains[ci].settings;
        let dt = self.dt.min(set.max_delta_time);
        if dt > 0.0 {
            let mo = motion_memo(
                &mut s.motion,
                set,
                Some(&pack.prev_component),
                &s.component,
                dt,
                false,
                run,
                pack.shared,
            );
            let input = LaneStep {
                targets: &s.targets,
                normals: &s.normals,
                colliders: &s.colliders,
                stride: pack.collider_stride(),
                bounds: &s.bounds,
                shapes: self.shapes,
                move_cs: mo.move_cs,
                rotate_cs: mo.rotate_cs,
                gravity_step: mo.gravity_step,
                wind_cs: mo.wind_cs,
                wind_on: mo.wind_on,
                dt,
                dt_old: pack.dt_old[ci],
                part: None,
                active: run,
                ahead,
            };
            step_lanes::<T>(
                rig,
                ci,
                &input,
                &mut pack.pos,
                &mut pack.prev,
                &mut pack.rng[ci],
                &mut s.near,
            );
            pack.dt_old[ci] = F::select(run, F::splat(dt), pack.dt_old[ci]);
        }
        for p in rig.chains[ci].points.clone() {
            let d = pack.pos[p] - s.targets[p];
            pack.dev[p] = V3::select(run, d, pack.dev[p]);
            pack.dev_before[p] = V3::select(run, d, pack.dev_before[p]);
        }
    }

    #[inline(always)]
    pub(crate) fn run_fixed<T: Lane>(
        &self,
        ci: usize,
        pack: &mut Pack,
        s: &mut Scratch,
        run: M,
        ahead: Ahead,
    ) {
        let rig = self.rig;
        let chain = &rig.chains[ci];
        let set = &chain.settings;
        let dt = self.dt;
        let h = 1.0 / set.target_framerate;
        let k_all = rig.colliders.len();
        // Each lane's step count and skipped time, as the job's `run_fixed`.
        let acc_old = pack.accumulator[ci];
        let mut total = [0.0f32; LANES];
        let mut steps = [0u32; LANES];
        let mut skipped = [0.0f32; LANES];
        let mut most = 0;
        for l in 0..LANES {
            if run.0[l] == 0 {
                continue;
            }
            let a = acc_old.0[l];
            total[l] = a + dt;
            steps[l] = (total[l] / h + 1e-4).floor() as u32;
            if steps[l] > set.max_steps_per_frame {
                total[l] -= (steps[l] - set.max_steps_per_frame) as f32 * h;
                steps[l] = set.max_steps_per_frame;
            }
            skipped[l] = a + dt - total[l];
            most = most.max(steps[l]);
        }
        for k in 1..=most {
            let active = M::from_bools(std::array::from_fn(|l| run.0[l] != 0 && k <= steps[l]));
            let w = F(std::array::from_fn(|l| {
                let end = k as f32 * h - acc_old.0[l] + skipped[l];
                if dt > 0.0 {
                    (end / dt).clamp(0.0, 1.0)
                } else {
                    1.0
                }
            }));
            for p in chain.points.clone() {
                s.step_targets[p] = pack.prev_targets[p].lerp(s.targets[p], w);
            }
            // The normals only where the step reads them.
            if set.planar_constraint != PlanarAxis::None {
                for p in chain.points.clone() {
                    s.step_normals[p] = pack.prev_normals[p]
                        .lerp(s.normals[p], w)
                        .normalize_or(s.normals[p]);
                }
            }
            // With one character in every lane, a lane at the same share of the frame as
            // the last lane placed gets that lane's placement.
            let same = |l: usize, last: Option<usize>| {
                last.filter(|&k| pack.shared && w.0[k].to_bits() == w.0[l].to_bits())
            };
            // Where every active lane's step ends with the frame (the usual case), the step
            // reads the frame's own placement (`PlacedCollider::lerp` from 1 on) and bounds
            // as they are; else each lane's placement at its share of the frame.
            let all_end = (0..LANES).all(|l| active.0[l] == 0 || w.0[l] >= 1.0);
            let stride = pack.collider_stride();
            let placed_per_lane = if all_end {
                &[][..]
            } else {
                &chain.colliders[..]
            };
            for &c in placed_per_lane {
                let mut last = None;
                for l in 0..LANES {
                    let (at, frame_at) = (l * k_all + c, l * stride + c);
                    if active.0[l] != 0 && s.step_placed_at[at].to_bits() != w.0[l].to_bits() {
                        if w.0[l] >= 1.0 {
                            s.step_colliders[at] = s.colliders[frame_at];
                            s.step_bounds[c].set_lane_from(l, &s.bounds[c]);
                            s.step_placed_at[at] = w.0[l];
                            continue;
                        }
                        match same(l, last) {
                            Some(k) => {
                                s.step_colliders[at] = s.step_colliders[k * k_all + c];
                                s.step_bounds[c].copy_lane(k, l);
                            }
                            None => {
                                s.step_colliders[at] = pack.prev_colliders[frame_at]
                                    .lerp(&s.colliders[frame_at], w.0[l]);
                                s.step_bounds[c].set(l, &s.step_colliders[at]);
                                last = Some(l);
                            }
                        }
                        s.step_placed_at[at] = w.0[l];
                    }
                }
            }
            let mut last = None;
            for l in 0..LANES {
                if active.0[l] != 0 && s.path_w[l].to_bits() != w.0[l].to_bits() {
                    let at = match same(l, last) {
                        Some(k) => s.path_at.get(k),
                        None => {
                            last = Some(l);
                            pack.paths[l].at(w.0[l])
                        }
                    };
                    s.path_at.set(l, &at);
                    s.path_w[l] = w.0[l];
                }
            }
            let comp_b = Trs::select(active, &s.path_at, &Trs::splat(&Transform::IDENTITY));
            let mo = motion_memo(
                &mut s.motion,
                set,
                Some(&pack.last_step_component[ci]),
                &comp_b,
                h,
                true,
                active,
                pack.shared,
            );
            let (colliders, stride, bounds) = match all_end {
                true => (&s.colliders, stride, &s.bounds),
                false => (&s.step_colliders, k_all, &s.step_bounds),
            };
            let input = LaneStep {
                targets: &s.step_targets,
                normals: &s.step_normals,
                colliders,
                stride,
                bounds,
                shapes: self.shapes,
                move_cs: mo.move_cs,
                rotate_cs: mo.rotate_cs,
                gravity_step: mo.gravity_step,
                wind_cs: mo.wind_cs,
                wind_on: mo.wind_on,
                dt: h,
                dt_old: F::splat(h),
                part: None,
                active,
                ahead,
            };
            step_lanes::<T>(
                rig,
                ci,
                &input,
                &mut pack.pos,
                &mut pack.prev,
                &mut pack.rng[ci],
                &mut s.near,
            );
            pack.last_step_component[ci] =
                Trs::select(active, &comp_b, &pack.last_step_component[ci]);
        }
        let mut acc = pack.accumulator[ci];
        for l in 0..LANES {
            if run.0[l] != 0 {
                acc.0[l] = (total[l] - steps[l] as f32 * h).max(0.0);
            }
        }
        pack.accumulator[ci] = acc;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// Lane `l` of a motion, as bits.
    #[allow(clippy::type_complexity)]
    fn motion_bits(m: &Motion, l: usize) -> ([u32; 3], [u32; 4], [u32; 3], [u32; 3], u32) {
        let v = |v: Vec3| v.to_array().map(f32::to_bits);
        (
            v(m.move_cs.get(l)),
            m.rotate_cs.get(l).to_array().map(f32::to_bits),
            v(m.gravity_step.get(l)),
            v(m.wind_cs.get(l)),
            m.wind_on.0[l],
        )
    }

    /// The memo answers as [`motion`] computed afresh, bit for bit, in the lanes asked,
    /// over calls that repeat or change each of its inputs (settings, time, mode, either
    /// transform in one lane, the lanes asked); and it is used (calls it answers itself,
    /// counted by the memo).
    #[test]
    fn the_motion_memo_answers_as_motion() {
        let mut rng = SplitMix64::new(3);
        let mut u = |lo: f32, hi: f32| rng.range_f32(lo, hi);
        let mut memo = MotionMemo::new();
        let mut settings = ChainSettings::default();
        let transform = |u: &mut dyn FnMut(f32, f32) -> f32| {
            Transform::from_translation_rotation(
                Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)),
                Quat::from_euler(glam::EulerRot::XYZ, u(-3.0, 3.0), u(-3.0, 3.0), 0.0),
            )
        };
        let mut from = Trs::splat(&transform(&mut u));
        let mut to = Trs::splat(&transform(&mut u));
        let (mut dt, mut fixed, mut has_from) = (1.0 / 60.0, true, true);
        let mut active = M::ALL;
        for round in 0..4000 {
            let l = (u(0.0, 8.0) as usize).min(LANES - 1);
            match round % 11 {
                0 => from.set(l, &transform(&mut u)),
                1 => to.set(l, &transform(&mut u)),
                2 => settings.gravity = Vec3::new(0.0, u(-10.0, 0.0), 0.0),
                3 => settings.gravity_in_world = !settings.gravity_in_world,
                4 => settings.wind.direction = Vec3::new(u(-1.0, 1.0), 0.0, u(-1.0, 1.0)),
                5 => dt = [1.0 / 60.0, 1.0 / 30.0][(round / 11) % 2],
                6 => fixed = !fixed,
                7 => has_from = !has_from,
                8 => settings.wind.speed = [0.0, 0.5][(round / 11) % 2],
                9 => {
                    settings.classic_gravity = [
                        ClassicGravity::DtSquared,
                        ClassicGravity::PerFrame,
                        ClassicGravity::HalfDtSquared,
                    ][(round / 11) % 3]
                }
                _ => {
                    active = M(std::array::from_fn(
                        |_| if u(0.0, 1.0) < 0.8 { !0 } else { 0 },
                    ))
                }
            }
            // Often nothing changed since the last call (as for a character's next chain).
            let calls = 1 + usize::from(u(0.0, 1.0) < 0.5);
            for _ in 0..calls {
                let f = has_from.then_some(&from);
                let got = motion_memo(&mut memo, &settings, f, &to, dt, fixed, active, false);
                let want = motion(&settings, f, &to, dt, fixed, active, false);
                for l in 0..LANES {
                    if active.0[l] != 0 {
                        assert_eq!(
                            motion_bits(&got, l),
                            motion_bits(&want, l),
                            "round {round} lane {l}"
                        );
                    }
                }
            }
        }
        assert!(memo.hits > 1000, "{}", memo.hits);
    }

    /// With one character in every lane (`shared`), the motion is each lane's own, computed
    /// lane by lane without sharing, in every lane (the inactive ones keep the empty
    /// motion): whether every active lane stepped between the same transforms (one lane's
    /// motion for all) or one differs, by a transform or by a single bit.
    #[test]
    fn shared_motion_is_each_lanes_own() {
        let mut rng = SplitMix64::new(5);
        let mut u = |lo: f32, hi: f32| rng.range_f32(lo, hi);
        let mut settings = ChainSettings::default();
        settings.wind.speed = 0.5;
        settings.wind.direction = Vec3::X;
        let (mut all_same, mut one_differs) = (0, 0);
        for round in 0..3000 {
            let mut t = || {
                Transform::from_translation_rotation(
                    Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)),
                    Quat::from_euler(glam::EulerRot::XYZ, u(-3.0, 3.0), u(-3.0, 3.0), 0.0),
                )
            };
            let (a, b, other) = (t(), t(), t());
            let mut from = Trs::splat(&a);
            let mut to = Trs::splat(&b);
            let l = (u(0.0, 8.0) as usize).min(LANES - 1);
            match round % 4 {
                0 => {}
                1 => from.set(l, &other),
                2 => to.set(l, &other),
                _ => {
                    // One bit of one lane's rotation.
                    let mut r = b;
                    r.rotation = Quat::from_xyzw(
                        f32::from_bits(r.rotation.x.to_bits() ^ 1),
                        r.rotation.y,
                        r.rotation.z,
                        r.rotation.w,
                    );
                    to.set(l, &r);
                }
            }
            let active = M(std::array::from_fn(|k| {
                if k == l || u(0.0, 1.0) < 0.7 {
                    !0
                } else {
                    0
                }
            }));
            let has_from = round % 8 < 6;
            let f = has_from.then_some(&from);
            let differs = round % 4 != 0
                && (round % 4 != 1 || has_from)
                && (0..LANES).any(|k| k != l && active.0[k] != 0);
            if differs {
                one_differs += 1;
            } else {
                all_same += 1;
            }
            let got = motion(&settings, f, &to, 1.0 / 60.0, true, active, true);
            let want = motion(&settings, f, &to, 1.0 / 60.0, true, active, false);
            for k in 0..LANES {
                assert_eq!(
                    motion_bits(&got, k),
                    motion_bits(&want, k),
                    "round {round} lane {k}"
                );
            }
        }
        assert!(
            all_same > 500 && one_differs > 1500,
            "{all_same} {one_differs}"
        );
    }
}
