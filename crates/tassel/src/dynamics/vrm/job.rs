//! Per-character spring-bone state and the frame job: the specification's update, run once
//! per frame (`spec`) or at a fixed rate with interpolation (`fixed`).

use super::collide::PlacedVrmCollider;
use super::compile::{VrmLink, VrmRig};
use super::lanes::contact::Placed;
use super::settings::VrmMode;
use crate::dynamics::path::{CharacterPath, FixedClock};
use crate::dynamics::vrm::lanes::springs::{SpringIo, SpringLanes};
use crate::error::{Error, Result};
use crate::lanes::{Isa, SimdUse};
use crate::math::{normalize_or, rotation_arc, Transform};
use crate::skeleton::Skeleton;
use glam::{Quat, Vec3};

/// The small per-character state of a [`VrmRig`]: each link's tail now and one step ago
/// (in world space, or in its spring's centre space) and its last two rotations.
#[derive(Debug, Clone)]
pub struct VrmState {
    /// The character's recent transforms: where it was at each fixed step's time.
    path: CharacterPath,
    current_tail: Vec<Vec3>,
    prev_tail: Vec<Vec3>,
    length: Vec<f32>,
    /// three-vrm mode: each link's tail node (world) at the end of the previous frame.
    stale_tail: Vec<Vec3>,
    rotation: Vec<Quat>,
    /// Fixed mode's output step: the state it starts from, put back after it.
    kept_current: Vec<Vec3>,
    kept_prev: Vec<Vec3>,
    kept_rotation: Vec<Quat>,
    /// The share of a step an update carries the motion (inertia) and the forces
    /// (stiffness, gravity) by: (1, 1) for a step, (`a`, `a`) for fixed mode's output step
    /// of `a` of a step (the spec's stiffness and gravity terms are displacements per step).
    carry: (f32, f32),
    placed: Vec<PlacedVrmCollider>,
    // Fixed mode: last frame's animated input and the scratch pose of a step.
    prev_locals: Vec<Transform>,
    step_locals: Vec<Transform>,
    step_models: Vec<Transform>,
    prev_component: Transform,
    accumulator: f32,
    needs_reset: bool,
    resets: u64,
    /// Scratch of the lane path: each collider as placed for the step, in every lane.
    lane_placed: Vec<Placed>,
    simd: SimdUse,
}

impl VrmState {
    /// Fresh state for `rig`; the first frame initialises it from the pose it is given.
    pub fn new(rig: &VrmRig) -> Self {
        let l = rig.links.len();
        let n = rig.joint_count();
        let none = PlacedVrmCollider::Plane {
            point: Vec3::ZERO,
            normal: Vec3::Y,
        };
        Self {
            path: CharacterPath::default(),
            current_tail: vec![Vec3::ZERO; l],
            prev_tail: vec![Vec3::ZERO; l],
            length: vec![0.0; l],
            stale_tail: vec![Vec3::ZERO; l],
            rotation: vec![Quat::IDENTITY; l],
            kept_current: vec![Vec3::ZERO; l],
            kept_prev: vec![Vec3::ZERO; l],
            kept_rotation: vec![Quat::IDENTITY; l],
            carry: (1.0, 1.0),
            placed: vec![none; rig.colliders.len()],
            prev_locals: vec![Transform::IDENTITY; n],
            step_locals: vec![Transform::IDENTITY; n],
            step_models: vec![Transform::IDENTITY; n],
            prev_component: Transform::IDENTITY,
            accumulator: 0.0,
            needs_reset: true,
            resets: 0,
            lane_placed: vec![Placed::default(); rig.colliders.len()],
            simd: SimdUse::default(),
        }
    }

    /// Which code runs the specification's update and fixed mode's output pass and step
    /// pose: by default several springs (joints) side by side in SIMD lanes (with AVX2
    /// where the CPU has it) where the rig allows it, else the scalar code. Every choice gives the same bits; [`SimdUse::Scalar`] is the
    /// readable reference.
    pub fn set_simd(&mut self, simd: SimdUse) {
        self.simd = simd;
    }

    /// What one update reads and writes (the scalar and the lane path): the pose and this
    /// state's arrays.
    fn spring_io<'a>(
        &'a mut self,
        component: &Transform,
        dt: f32,
        mode: VrmMode,
        locals: &'a mut [Transform],
        models: &'a mut [Transform],
    ) -> SpringIo<'a> {
        SpringIo {
            component: *component,
            dt,
            mode,
            locals,
            models,
            placed: &self.placed,
            lane_placed: &mut self.lane_placed,
            current_tail: &mut self.current_tail,
            prev_tail: &mut self.prev_tail,
            length: &self.length,
            stale_tail: &self.stale_tail,
            rotation: &mut self.rotation,
            carry: self.carry,
        }
    }

    /// The code chosen by [`VrmState::set_simd`].
    pub fn simd(&self) -> SimdUse {
        self.simd
    }

    /// Makes the next frame start again from its pose (the spec's `reset`), wherever the
    /// character was before (its path is forgotten: that frame's time step changes
    /// nothing).
    pub fn reset(&mut self) {
        self.needs_reset = true;
        // Where the character was is no part of where it goes from here.
        self.path = CharacterPath::default();
    }

    /// The character was moved on purpose: start again instead of whipping.
    pub fn teleport(&mut self) {
        self.reset();
    }

    /// Link `link`'s current tail in world space, given the character transform and the
    /// model pose the tails were last computed with; `None` past the last link.
    pub fn tail_world(
        &self,
        rig: &VrmRig,
        link: usize,
        component: &Transform,
        models: &[Transform],
    ) -> Option<Vec3> {
        let l = rig.links.get(link)?;
        let t = *self.current_tail.get(link)?;
        Some(match l.center {
            Some(c) => (*component * *models.get(c)?).transform_point(t),
            None => t,
        })
    }

    /// Each link's current tail in world space, given the character transform and the
    /// model pose the tails were last computed with (allocates; see
    /// [`VrmState::tail_world`] for one link).
    pub fn tails_world(
        &self,
        rig: &VrmRig,
        component: &Transform,
        models: &[Transform],
    ) -> Vec<Vec3> {
        rig.links
            .iter()
            .zip(&self.current_tail)
            .map(|(l, &t)| match l.center {
                Some(c) => (*component * models[c]).transform_point(t),
                None => t,
            })
            .collect()
    }

    /// Bone lengths (joint to tail, world metres) recorded at the last reset.
    pub fn lengths(&self) -> &[f32] {
        &self.length
    }

    /// Colliders as placed for the last step, world space, in the rig's collider order.
    pub fn placed_colliders(&self) -> &[PlacedVrmCollider] {
        &self.placed
    }

    /// How many resets (first frame, teleports, non-finite recoveries) happened so far.
    pub fn reset_count(&self) -> u64 {
        self.resets
    }
}

/// One frame of a character's VRM spring bones.
///
/// Reads the animated pose (`locals` and the `models` computed from them, model space)
/// and the character's world transform; writes the simulated joints' local rotations and
/// recomputes `models`.
#[derive(Debug)]
pub struct VrmJob<'a> {
    /// The skeleton the rig was compiled for.
    pub skeleton: &'a Skeleton,
    /// The compiled springs.
    pub rig: &'a VrmRig,
    /// The character's state.
    pub state: &'a mut VrmState,
    /// The character's world transform this frame.
    pub component: Transform,
    /// Frame time, seconds (finite, ≥ 0).
    pub dt: f32,
    /// In: animated local transforms. Out: with simulated rotations.
    pub locals: &'a mut [Transform],
    /// In: animated model transforms, the model pose of `locals` (as
    /// [`LocalToModelJob`](crate::LocalToModelJob) computes it with the identity above the
    /// roots). Out: the model pose of the new locals (joints no spring moves may keep the
    /// models given).
    pub models: &'a mut [Transform],
}

impl VrmJob<'_> {
    /// Checks sizes and that the inputs are finite.
    pub fn validate(&self) -> Result<()> {
        let n = self.skeleton.len();
        for (what, got) in [
            ("VRM rig joints", self.rig.joint_count()),
            ("locals", self.locals.len()),
            ("models", self.models.len()),
        ] {
            if got != n {
                return Err(Error::LengthMismatch {
                    what,
                    expected: n,
                    got,
                });
            }
        }
        if !(self.dt.is_finite() && self.dt >= 0.0) {
            return Err(Error::InvalidTimeStep(self.dt));
        }
        if !self.component.is_finite() {
            return Err(Error::NonFinite("character transform".into()));
        }
        if let Some(i) = self.locals.iter().position(|m| !m.is_finite()) {
            return Err(Error::NonFinite(format!(
                "animated pose of joint '{}'",
                self.skeleton.name(i)
            )));
        }
        Ok(())
    }

    /// Validates, then runs the frame. Never allocates.
    pub fn run(self) -> Result<()> {
        self.validate()?;
        self.run_validated();
        Ok(())
    }

    /// Runs the frame on inputs the caller has checked as [`VrmJob::validate`] does
    /// ([`crate::CharacterSim`] checks its input before any job runs).
    pub(crate) fn run_validated(self) {
        let VrmJob {
            skeleton,
            rig,
            state,
            component,
            dt,
            locals,
            models,
        } = self;
        // Node constraints first: the springs see the constrained pose.
        if !rig.constraints.list.is_empty() {
            rig.constraints.apply(skeleton, &component, locals, models);
        }
        if rig.links.is_empty() {
            if !rig.constraints.list.is_empty() {
                // The constraints' refresh takes a root's local as its model; the output
                // is the model pose as `LocalToModelJob` computes it.
                crate::pose::local_to_model_into(skeleton, locals, models);
            }
            return;
        }
        state.path.push(component, dt);
        let opts = &rig.options;
        if !state.needs_reset && opts.teleport_distance > 0.0 {
            let moved = (component.translation - state.prev_component.translation).length();
            if moved > opts.teleport_distance {
                state.needs_reset = true;
            }
        }
        // Whether the lane path updated every link's model (then only the joints below
        // the links need their models recomputed at the end).
        let mut lanes_ran = false;
        // Whether `models` is the model pose of the animated `locals` as given (node
        // constraints write it with the lazy refresh's root rule).
        let models_given = rig.constraints.list.is_empty();
        // Fixed mode: whether this frame's last step ended on the frame, on its pose and
        // colliders (then its rotations are the output, pushed out already).
        let mut on_frame = false;
        // Whether `prev_locals` holds this frame's animated pose already (fixed mode's
        // on-frame step took it before turning the links in place).
        let mut prev_taken = false;
        // Whether a reset wrote `models` (its lazy refresh's root rule: the output pose is
        // composed again whole).
        let mut was_reset = state.needs_reset;
        if state.needs_reset {
            reset(skeleton, rig, state, &component, locals, models);
        } else {
            match opts.mode {
                VrmMode::Spec | VrmMode::ThreeVrm => {
                    if dt > 0.0 {
                        place_colliders(rig, state, &component, models);
                        lanes_ran = update(
                            skeleton, rig, state, &component, dt, opts.mode, locals, models,
                        );
                    }
                }
                VrmMode::Fixed => {
                    on_frame = run_fixed(skeleton, rig, state, dt, locals, models, models_given);
                    prev_taken = on_frame;
                }
            }
        }
        // Guard: never let a non-finite value out; start again from the pose instead.
        if state.current_tail.iter().any(|t| !t.is_finite())
            || state.rotation.iter().any(|q| !q.is_finite())
        {
            reset(skeleton, rig, state, &component, locals, models);
            lanes_ran = false;
            on_frame = false;
            was_reset = true;
            prev_taken = false;
        }
        // A last step on this frame's own pose, in place, in lanes wrote the output's
        // models of the links (the joints below them are left to `refresh_below`, as in
        // the spec modes). The scalar step's models are its lazy refresh's, which takes a
        // root link's local as its model: the whole pose is composed again below.
        if on_frame && lane_plan(rig, state).is_some() {
            lanes_ran = true;
        }
        if !prev_taken {
            state.prev_locals.copy_from_slice(locals);
        }
        state.prev_component = component;
        // Output: the last step's rotations; in fixed mode, unless that step ended on
        // this frame, an output step: the springs carried from the last step to the
        // frame's time (`a` of a step) on the frame's pose and colliders, not kept.
        if opts.mode == VrmMode::Fixed && !on_frame {
            let a = (state.accumulator * opts.step_rate).clamp(0.0, 1.0);
            lanes_ran =
                output_step(skeleton, rig, state, &component, a, locals, models) && !was_reset;
        } else {
            for (i, l) in rig.links.iter().enumerate() {
                locals[l.joint].rotation = state.rotation[i];
            }
        }
        match (&rig.lanes, lanes_ran && rig.constraints.list.is_empty()) {
            // The links' models are those of their new rotations already (the lane path
            // composes them as this pass would), the joints no link moves keep the models
            // given: only the joints below the links are left.
            (Some(lanes), true) => lanes.refresh_below(skeleton, locals, models),
            _ => crate::pose::local_to_model_into(skeleton, locals, models),
        }
        if opts.mode == VrmMode::ThreeVrm {
            // Where each tail node ends this frame: next frame's bone length measures to it.
            record_tails(rig, state, &component, models);
        }
    }
}

/// The lane plan when this state runs it (the rig allows it and `SimdUse` is not
/// `Scalar`): the one condition of every lane path of the job.
fn lane_plan<'a>(rig: &'a VrmRig, state: &VrmState) -> Option<&'a SpringLanes> {
    rig.lanes.as_ref().filter(|l| l.runs_with(state.simd))
}

/// Fixed mode's output step: one update of `a` (0..=1) of a step from the last step's
/// state, on this frame's pose (`locals`, `models`: its model pose) and colliders, with
/// the inertia and the stiffness and gravity terms all scaled by `a` (`state.carry`: at
/// `a = 1` a whole step, at 0 the last step's tails held in place), pushed out of the
/// colliders and limited as a step is. It writes the links' output rotations and models;
/// the state is put back as it was. Returns whether the lane path ran (as [`update`]).
fn output_step(
    sk: &Skeleton,
    rig: &VrmRig,
    state: &mut VrmState,
    component: &Transform,
    a: f32,
    locals: &mut [Transform],
    models: &mut [Transform],
) -> bool {
    let h = 1.0 / rig.options.step_rate;
    place_colliders(rig, state, component, models);
    state.kept_current.copy_from_slice(&state.current_tail);
    state.kept_prev.copy_from_slice(&state.prev_tail);
    state.kept_rotation.copy_from_slice(&state.rotation);
    state.carry = (a, a);
    let lanes_ran = update(sk, rig, state, component, h, VrmMode::Fixed, locals, models);
    state.carry = (1.0, 1.0);
    std::mem::swap(&mut state.current_tail, &mut state.kept_current);
    std::mem::swap(&mut state.prev_tail, &mut state.kept_prev);
    std::mem::swap(&mut state.rotation, &mut state.kept_rotation);
    lanes_ran
}

/// The spec's initialisation from the given pose: joints at their rest rotation, tails
/// where the rest rotation puts them, no velocity.
fn reset(
    sk: &Skeleton,
    rig: &VrmRig,
    state: &mut VrmState,
    component: &Transform,
    locals: &mut [Transform],
    models: &mut [Transform],
) {
    for l in &rig.links {
        locals[l.joint].rotation = l.rest_local.rotation;
    }
    refresh(sk, locals, models, 0, sk.len() - 1);
    for (i, l) in rig.links.iter().enumerate() {
        let world = *component * models[l.joint];
        let tail = world.transform_point(l.tail_local);
        state.length[i] = (tail - world.translation).length();
        let stored = match l.center {
            Some(c) => (*component * models[c]).inverse_transform_point(tail),
            None => tail,
        };
        state.current_tail[i] = stored;
        state.prev_tail[i] = stored;
        state.rotation[i] = l.rest_local.rotation;
    }
    record_tails(rig, state, component, models);
    state.accumulator = 0.0;
    state.needs_reset = false;
    state.resets += 1;
}

/// Each link's tail (world) from the written pose: its tail node, or the virtual tail.
fn record_tails(rig: &VrmRig, state: &mut VrmState, component: &Transform, models: &[Transform]) {
    for (i, l) in rig.links.iter().enumerate() {
        state.stale_tail[i] = match l.tail_joint {
            Some(t) => (*component * models[t]).translation,
            None => (*component * models[l.joint]).transform_point(l.tail_local),
        };
    }
}

fn place_colliders(
    rig: &VrmRig,
    state: &mut VrmState,
    component: &Transform,
    models: &[Transform],
) {
    for (placed, (joint, shape)) in state.placed.iter_mut().zip(&rig.colliders) {
        *placed = PlacedVrmCollider::place(shape, &(*component * models[*joint]));
    }
}

/// One update of every link with time step `dt` (the specification's procedure; in fixed
/// mode with the settling after the pushes; in three-vrm mode with the bone length to the
/// tail's place at the end of the last frame): `models` must be the model pose of
/// `locals`; both are updated as rotations are written. Returns whether the lane path ran
/// (then only the links' models are updated; the joints below them are left stale).
#[allow(clippy::too_many_arguments)]
fn update(
    sk: &Skeleton,
    rig: &VrmRig,
    state: &mut VrmState,
    component: &Transform,
    dt: f32,
    mode: VrmMode,
    locals: &mut [Transform],
    models: &mut [Transform],
) -> bool {
    if let Some(lanes) = lane_plan(rig, state) {
        // The same results, several springs at a time (`dynamics/vrm/lanes/springs.rs`); the
        // models of joints that are not links are left stale: every caller recomputes
        // the whole model pose before reading them.
        let isa = Isa::of(state.simd);
        let mut io = state.spring_io(component, dt, mode, locals, models);
        lanes.update(rig, &mut io, isa);
        return true;
    }
    // Model transforms at or above this index are stale (a rotation above them changed).
    let mut stale_from = sk.len();
    let mut io = state.spring_io(component, dt, mode, locals, models);
    for (i, l) in rig.links.iter().enumerate() {
        if stale_from <= l.joint {
            refresh(sk, io.locals, io.models, stale_from, l.joint);
        }
        update_link(rig, &mut io, i);
        stale_from = l.joint + 1;
    }
    if stale_from < sk.len() {
        refresh(sk, io.locals, io.models, stale_from, sk.len() - 1);
    }
    false
}

/// The update of link `i` (the specification's procedure, as [`update`] describes it):
/// its model in `io.models` must be fresh, and its parent's. Writes its tails, its
/// rotation, its local rotation and its model. The scalar update runs every link through
/// it; the lane update the links of the rows where lanes lose.
pub(crate) fn update_link(rig: &VrmRig, io: &mut SpringIo<'_>, i: usize) {
    let l = &rig.links[i];
    let component = io.component;
    let parent_world = parent_world(l, &component, io.models);
    let position = (component * io.models[l.joint]).translation;
    let center = l.center.map(|c| component * io.models[c]);
    let to_world = |t: Vec3| center.map_or(t, |c| c.transform_point(t));
    let current = to_world(io.current_tail[i]);
    let prev = to_world(io.prev_tail[i]);

    // Verlet: inertia, stiffness toward the rest direction under the current parent,
    // gravity; then back to the bone length.
    let rest_dir = rest_dir(l, &parent_world);
    let (carry_motion, carry_force) = io.carry;
    let dt = io.dt;
    let inertia = (current - prev) * (1.0 - l.drag_force) * carry_motion;
    let stiffness = rest_dir * (l.stiffness * dt) * carry_force;
    let external = l.gravity * dt * carry_force;
    let length = match (io.mode, l.tail_joint) {
        // three-vrm re-measures the bone against the tail node's world matrix, which
        // still holds the end of the last frame.
        (VrmMode::ThreeVrm, Some(_)) => (io.stale_tail[i] - position).length(),
        _ => io.length[i],
    };
    let next = position
        + normalize_or(
            current + inertia + stiffness + external - position,
            rest_dir,
        ) * length;
    // The draft limit (`VRMC_springBone_limit`): after inertia, and after each push.
    let next = limited(l, parent_world.rotation, position, next, length);
    let (next, _) = collide_tail(
        rig,
        io.placed,
        l,
        parent_world.rotation,
        position,
        length,
        rest_dir,
        next,
        io.mode == VrmMode::Fixed,
    );

    let to_stored = |t: Vec3| center.map_or(t, |c| c.inverse_transform_point(t));
    io.prev_tail[i] = io.current_tail[i];
    io.current_tail[i] = to_stored(next);
    io.rotation[i] = turn_toward(l, &parent_world, next, io.locals, io.models);
}

/// The world transform of the link's parent (the character's at a skeleton root).
fn parent_world(l: &VrmLink, component: &Transform, models: &[Transform]) -> Transform {
    match l.parent {
        Some(p) => *component * models[p],
        None => *component,
    }
}

/// The rest bone direction under the current parent: the spec's stiffness direction.
fn rest_dir(l: &VrmLink, parent_world: &Transform) -> Vec3 {
    parent_world.rotation * (l.rest_local.rotation * l.bone_axis)
}

/// The spec's collision: for each collider of the link, one push and the projection back
/// to the bone length; with `exact`, what that leaves inside is then settled. Returns the
/// tail and whether any collider acted.
#[allow(clippy::too_many_arguments)]
fn collide_tail(
    rig: &VrmRig,
    placed: &[PlacedVrmCollider],
    l: &VrmLink,
    parent_rotation: Quat,
    position: Vec3,
    length: f32,
    rest_dir: Vec3,
    mut tail: Vec3,
    exact: bool,
) -> (Vec3, bool) {
    let mut acted = false;
    for &c in &rig.link_colliders[l.colliders.clone()] {
        let (dir, dist) = placed[c].collision(tail, l.hit_radius);
        if dist < 0.0 {
            tail = position + normalize_or(tail - dir * dist - position, rest_dir) * length;
            tail = limited(l, parent_rotation, position, tail, length);
            acted = true;
        }
    }
    if exact {
        let mut settled = settle(rig, placed, l, position, length, tail);
        if settled != tail {
            settled = limited(l, parent_rotation, position, settled, length);
            acted = true;
        }
        tail = settled;
    }
    (tail, acted)
}

/// The tail kept within the link's limit, if it has one (`VRMC_springBone_limit`).
#[inline]
fn limited(l: &VrmLink, parent_rotation: Quat, position: Vec3, tail: Vec3, length: f32) -> Vec3 {
    match &l.limit {
        Some(limit) => limit.apply(parent_rotation, position, tail, length),
        None => tail,
    }
}

/// Turns the link's joint so that its bone points at `tail` (world): the rest local
/// rotation turned from the bone axis to the tail as seen from the joint's rest frame
/// under its current parent. Writes the local rotation and the joint's model transform.
fn turn_toward(
    l: &VrmLink,
    parent_world: &Transform,
    tail: Vec3,
    locals: &mut [Transform],
    models: &mut [Transform],
) -> Quat {
    let rest_world = *parent_world * l.rest_local;
    let to = normalize_or(rest_world.inverse_transform_point(tail), l.bone_axis);
    let rotation = (l.rest_local.rotation * rotation_arc(l.bone_axis, to)).normalize();
    locals[l.joint].rotation = rotation;
    models[l.joint] = match l.parent {
        Some(p) => models[p] * locals[l.joint],
        None => locals[l.joint],
    };
    rotation
}

/// Fixed mode: what the spec's single push leaves inside a collider (the length
/// projection can undo a push) is resolved exactly on the bone sphere, two passes over the
/// link's colliders.
fn settle(
    rig: &VrmRig,
    placed: &[PlacedVrmCollider],
    l: &VrmLink,
    position: Vec3,
    length: f32,
    mut tail: Vec3,
) -> Vec3 {
    for _ in 0..2 {
        let mut changed = false;
        for &c in &rig.link_colliders[l.colliders.clone()] {
            let collider = &placed[c];
            let before = collider.penetration(tail, l.hit_radius);
            if before > 0.0 {
                let t = collider.settle(position, length, tail, l.hit_radius);
                // Only ever an improvement (a capsule's cone is taken about the axis point
                // nearest the tail, which can mislead when the joint sits on the axis).
                if collider.penetration(t, l.hit_radius) < before {
                    changed |= t != tail;
                    tail = t;
                }
            }
        }
        if !changed {
            break;
        }
    }
    tail
}

/// Model transforms `from..=to` recomputed from their parents' and their locals.
fn refresh(sk: &Skeleton, locals: &[Transform], models: &mut [Transform], from: usize, to: usize) {
    if from == 0 && to + 1 == sk.len() {
        // The whole pose: by depth, as `LocalToModelJob` does (the same values), a root
        // taking its local as its model.
        crate::pose::compose_by_depth(sk, None, locals, models);
        return;
    }
    for k in from..=to {
        models[k] = match sk.parent(k) {
            Some(p) => models[p] * locals[k],
            None => locals[k],
        };
    }
}

/// Fixed mode: whole steps of `1/step_rate` up to now, each with the animated pose and the
/// character transform interpolated to its time. Time left over within [`ON_FRAME`](crate::dynamics::path::ON_FRAME) of a step is
/// dropped, and a last step that then ends on the frame takes the frame's own pose
/// (`locals`, and `models` when `models_given` says it is their model pose), stepping on
/// them in place after keeping `locals` as `prev_locals`: returns whether it did, so that
/// its rotations (written into `locals` already, with the links' models) are the frame's
/// output as they are.
fn run_fixed(
    sk: &Skeleton,
    rig: &VrmRig,
    state: &mut VrmState,
    dt: f32,
    locals: &mut [Transform],
    models: &mut [Transform],
    models_given: bool,
) -> bool {
    let opts = &rig.options;
    let h = 1.0 / opts.step_rate;
    let clock = FixedClock::new(state.accumulator, dt, h, opts.max_steps_per_frame);
    for k in 1..=clock.steps {
        let w = clock.end(k);
        let comp = state.path.at(w);
        if k == clock.steps && clock.on_frame() && models_given {
            // The last step ends on the frame: it steps on the frame's own pose as given,
            // in place (it turns the links and writes their models, as the output would),
            // after this frame's animated pose is kept for the next frame's steps. The
            // same values as a step on copies, without the three copies.
            state.prev_locals.copy_from_slice(locals);
            place_colliders(rig, state, &comp, models);
            update(sk, rig, state, &comp, h, VrmMode::Fixed, locals, models);
            break;
        }
        let mut step_locals = std::mem::take(&mut state.step_locals);
        let mut step_models = std::mem::take(&mut state.step_models);
        if w >= 1.0 && models_given {
            // The frame's own pose, as given (the same values as the lerp's and the
            // refresh's would be only nearly).
            step_locals.copy_from_slice(locals);
            step_models.copy_from_slice(models);
        } else {
            match lane_plan(rig, state) {
                Some(lanes) => {
                    // Only what the lane update and the colliders read of the step's pose
                    // (the same values where they read it).
                    let isa = Isa::of(state.simd);
                    let frames = (&state.prev_locals[..], &*locals);
                    lanes.step_pose(sk, frames, w, &mut step_locals, &mut step_models, isa);
                }
                None => {
                    for (s, (a, b)) in step_locals
                        .iter_mut()
                        .zip(state.prev_locals.iter().zip(locals.iter()))
                    {
                        *s = if w >= 1.0 { *b } else { a.lerp(b, w) };
                    }
                    refresh(sk, &step_locals, &mut step_models, 0, sk.len() - 1);
                }
            }
        }
        place_colliders(rig, state, &comp, &step_models);
        update(
            sk,
            rig,
            state,
            &comp,
            h,
            VrmMode::Fixed,
            &mut step_locals,
            &mut step_models,
        );
        state.step_locals = step_locals;
        state.step_models = step_models;
    }
    state.accumulator = clock.left;
    clock.on_frame() && models_given
}
