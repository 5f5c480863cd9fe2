//! Per-character cloth state and the frame job.

use super::compile::{ClothRig, ConstraintKind, Relaxed};
use super::contact::{push_segment, push_triangle_against, Core};
use super::lanes::{self as cloth_lanes, ClothLaneScratch};
use super::spcr::{SpcrFrame, SpcrState};
use crate::collide::PlacedCollider;
use crate::controller::Level;
use crate::dynamics::path::CharacterPath;
use crate::dynamics::world::collide_points;
use crate::error::{Error, Result};
use crate::lanes::{Isa, SimdUse};
use crate::math::{normalize_or, rotation_arc, Transform};
use crate::rng::SplitMix64;
use crate::skeleton::Skeleton;
use glam::{Quat, Vec3};

/// The per-character state of a [`ClothRig`]: point positions (world space) and the
/// previous frame's inputs.
#[derive(Debug, Clone)]
pub struct ClothState {
    pos: Vec<Vec3>,
    prev: Vec<Vec3>,
    dev: Vec<Vec3>,
    dev_before: Vec<Vec3>,
    friction: Vec<f32>,
    targets: Vec<Vec3>,
    step_targets: Vec<Vec3>,
    model_targets: Vec<Vec3>,
    prev_model_targets: Vec<Vec3>,
    /// Colliders placed in the character's space, now and at the last frame's end (the
    /// steps carry them along the character's path).
    colliders_cs: Vec<PlacedCollider>,
    prev_colliders_cs: Vec<PlacedCollider>,
    /// The character's recent transforms: where it was at each step's time.
    path: CharacterPath,
    out_world: Vec<Vec3>,
    out: Vec<Vec3>,
    colliders: Vec<PlacedCollider>,
    step_colliders: Vec<PlacedCollider>,
    sides: Vec<Vec<i8>>,
    prev_component: Transform,
    accumulator: Vec<f32>,
    rng: Vec<SplitMix64>,
    needs_reset: Vec<bool>,
    resets: u64,
    /// Scratch: each of a cloth's colliders as a core segment, slot by slot, for one
    /// `collide` call.
    cores: Vec<Option<Core>>,
    /// Which code runs the contact tests (every choice gives the same bits).
    simd: SimdUse,
    /// Scratch of the contact tests' lanes.
    lanes: ClothLaneScratch,
    /// Per cloth, the state of the `spcr` mode (empty for `fixed` cloths).
    spcr: Vec<SpcrState>,
}

impl ClothState {
    /// Fresh state for `rig`; the first frame starts from the animated pose.
    pub fn new(rig: &ClothRig) -> Self {
        let n = rig.point_count();
        let placed = PlacedCollider {
            shape: crate::collide::Shape::Plane,
            transform: Transform::IDENTITY,
        };
        let m = rig.colliders.len();
        Self {
            pos: vec![Vec3::ZERO; n],
            prev: vec![Vec3::ZERO; n],
            dev: vec![Vec3::ZERO; n],
            dev_before: vec![Vec3::ZERO; n],
            friction: vec![0.0; n],
            targets: vec![Vec3::ZERO; n],
            step_targets: vec![Vec3::ZERO; n],
            model_targets: vec![Vec3::ZERO; n],
            prev_model_targets: vec![Vec3::ZERO; n],
            colliders_cs: vec![placed; m],
            prev_colliders_cs: vec![placed; m],
            path: CharacterPath::default(),
            out_world: vec![Vec3::ZERO; n],
            out: vec![Vec3::ZERO; n],
            colliders: vec![placed; m],
            step_colliders: vec![placed; m],
            sides: rig
                .cloths
                .iter()
                .map(|c| vec![0; c.quads.len() * 2 * c.colliders.len()])
                .collect(),
            prev_component: Transform::IDENTITY,
            accumulator: vec![0.0; rig.cloths.len()],
            rng: rig
                .cloths
                .iter()
                .enumerate()
                .map(|(i, c)| SplitMix64::new(c.settings.wind.seed ^ ((i as u64) << 32)))
                .collect(),
            needs_reset: vec![true; rig.cloths.len()],
            resets: 0,
            cores: Vec::new(),
            simd: SimdUse::default(),
            lanes: ClothLaneScratch::default(),
            spcr: vec![SpcrState::default(); rig.cloths.len()],
        }
    }

    /// Which code runs the contact tests (points, segments and quads against the
    /// colliders) and in which order the constraints are relaxed: lanes and the
    /// dependency-level order by default ([`SimdUse::Auto`]), [`SimdUse::Scalar`] for the
    /// readable reference (scalar tests, the rig's order). Every choice gives the same
    /// bits.
    pub fn set_simd(&mut self, simd: SimdUse) {
        self.simd = simd;
    }

    /// The code chosen by [`ClothState::set_simd`].
    pub fn simd(&self) -> SimdUse {
        self.simd
    }

    /// Makes the next frame start again from the animated pose.
    pub fn reset(&mut self) {
        self.needs_reset.iter_mut().for_each(|r| *r = true);
    }

    /// Output point positions of the last frame, in the character's (model) space.
    pub fn output_positions(&self) -> &[Vec3] {
        &self.out
    }

    /// Animated point positions of the last frame, in the character's (model) space.
    pub fn target_positions(&self) -> &[Vec3] {
        &self.model_targets
    }

    /// Output point positions of the last frame, world space.
    pub fn world_positions(&self) -> &[Vec3] {
        &self.out_world
    }

    /// Colliders as placed for the last frame, world space.
    pub fn placed_colliders(&self) -> &[PlacedCollider] {
        &self.colliders
    }

    /// How many resets (teleports or a non-finite result) happened after the first frame.
    pub fn reset_count(&self) -> u64 {
        self.resets
    }
}

/// One frame of every cloth of a character: reads the animated pose, writes simulated
/// rotations into `locals` and recomputes `models`.
#[derive(Debug)]
pub struct ClothJob<'a> {
    /// The skeleton the rig was compiled for.
    pub skeleton: &'a Skeleton,
    /// The compiled cloths.
    pub rig: &'a ClothRig,
    /// The character's state.
    pub state: &'a mut ClothState,
    /// The character's world transform this frame.
    pub component: Transform,
    /// Frame time, seconds (finite, ≥ 0).
    pub dt: f32,
    /// In: animated local transforms. Out: with simulated rotations.
    pub locals: &'a mut [Transform],
    /// In: model transforms of the locals. Out: recomputed.
    pub models: &'a mut [Transform],
    /// The world the cloths with `world_collision` keep out of (world space), if any.
    pub level: Option<&'a Level>,
}

impl ClothJob<'_> {
    /// Validates, then runs the frame.
    pub fn run(self) -> Result<()> {
        if !(self.dt.is_finite() && self.dt >= 0.0) {
            return Err(Error::InvalidTimeStep(self.dt));
        }
        if !self.component.is_finite() {
            return Err(Error::NonFinite("cloth: character transform".into()));
        }
        let n = self.skeleton.len();
        if self.locals.len() != n || self.models.len() != n {
            return Err(Error::LengthMismatch {
                what: "cloth pose",
                expected: n,
                got: self.locals.len().min(self.models.len()),
            });
        }
        if self.state.pos.len() != self.rig.point_count() {
            return Err(Error::LengthMismatch {
                what: "cloth state",
                expected: self.rig.point_count(),
                got: self.state.pos.len(),
            });
        }
        if self.models.iter().any(|m| !m.is_finite()) {
            return Err(Error::NonFinite("cloth: animated pose".into()));
        }
        let ClothJob {
            skeleton,
            rig,
            state,
            component,
            dt,
            locals,
            models,
            level,
        } = self;
        gather(rig, models, &component, state);
        state.path.push(component, dt);
        for ci in 0..rig.cloths.len() {
            if rig.cloths[ci].spcr.is_some() {
                run_spcr(rig, ci, state, &component, dt, models);
                continue;
            }
            let level = level.filter(|_| rig.cloths[ci].settings.world_collision);
            run_cloth(rig, ci, state, &component, dt, level);
        }
        state
            .prev_model_targets
            .copy_from_slice(&state.model_targets);
        state.prev_colliders_cs.copy_from_slice(&state.colliders_cs);
        state.prev_component = component;
        write_back(skeleton, rig, state, locals, models);
        for (cloth, spcr) in rig.cloths.iter().zip(&mut state.spcr) {
            if let Some(r) = &cloth.spcr {
                let out = &mut state.out;
                spcr.apply(
                    cloth, r, &rig.joint, &component, skeleton, locals, models, out,
                );
            }
        }
        crate::pose::LocalToModelJob {
            skeleton,
            root: Transform::IDENTITY,
            locals,
            models,
        }
        .run()
    }
}

fn gather(rig: &ClothRig, models: &[Transform], component: &Transform, state: &mut ClothState) {
    for p in 0..rig.point_count() {
        let m = match (rig.joint[p], rig.tip_of[p]) {
            (Some(j), _) => models[j].translation,
            (None, Some((last, before, len))) => {
                let b = models[last].translation;
                let a = models[before].translation;
                b + normalize_or(b - a, models[last].rotation * Vec3::Y) * len
            }
            _ => Vec3::ZERO,
        };
        state.model_targets[p] = m;
        state.targets[p] = component.transform_point(m);
    }
    let frame = Transform::from_translation_rotation(component.translation, component.rotation);
    for ((placed, cs), c) in state
        .colliders
        .iter_mut()
        .zip(state.colliders_cs.iter_mut())
        .zip(&rig.colliders)
    {
        *placed = c.place(models, Some(&frame));
        *cs = c.place(models, None);
    }
}

fn reset_cloth(rig: &ClothRig, ci: usize, state: &mut ClothState) {
    for p in rig.cloths[ci].points.clone() {
        state.pos[p] = state.targets[p];
        state.prev[p] = state.targets[p];
        state.prev_model_targets[p] = state.model_targets[p];
        state.dev[p] = Vec3::ZERO;
        state.dev_before[p] = Vec3::ZERO;
        state.friction[p] = 0.0;
    }
    state.prev_colliders_cs.copy_from_slice(&state.colliders_cs);
    state.sides[ci].iter_mut().for_each(|s| *s = 0);
    state.accumulator[ci] = 0.0;
    state.needs_reset[ci] = false;
}

fn run_cloth(
    rig: &ClothRig,
    ci: usize,
    state: &mut ClothState,
    component: &Transform,
    dt: f32,
    level: Option<&Level>,
) {
    let cloth = &rig.cloths[ci];
    let s = &cloth.settings;
    check_teleport(s, ci, state, component);
    if state.needs_reset[ci] {
        reset_cloth(rig, ci, state);
        state.path.reset(*component);
    }
    let h = 1.0 / s.step_rate;
    let start = state.accumulator[ci];
    let mut total = start + dt;
    let mut steps = (total / h + 1e-4).floor() as u32;
    if steps > s.max_steps_per_frame {
        total -= (steps - s.max_steps_per_frame) as f32 * h;
        steps = s.max_steps_per_frame;
    }
    for k in 1..=steps {
        // Where this step's end lies in the frame: 0 = last frame's end, 1 = this one's.
        let w = if dt > 0.0 {
            ((k as f32 * h - start) / (total - start).max(h * 1e-3)).clamp(0.0, 1.0)
        } else {
            1.0
        };
        // The animated pose and the colliders (character space) interpolated to the
        // step's time, carried along the character's path.
        let comp = state.path.at(w);
        for p in cloth.points.clone() {
            state.step_targets[p] =
                comp.transform_point(state.prev_model_targets[p].lerp(state.model_targets[p], w));
        }
        for i in 0..state.colliders.len() {
            let cs = state.prev_colliders_cs[i].lerp(&state.colliders_cs[i], w);
            state.step_colliders[i] = PlacedCollider {
                shape: cs.shape,
                transform: comp * cs.transform,
            };
        }
        step(rig, ci, state, h, level);
        let bad = cloth.points.clone().any(|p| !state.pos[p].is_finite());
        if bad {
            state.resets += 1;
            reset_cloth(rig, ci, state);
            break;
        }
        for p in cloth.points.clone() {
            state.dev_before[p] = state.dev[p];
            state.dev[p] = state.pos[p] - state.step_targets[p];
        }
    }
    state.accumulator[ci] = (total - steps as f32 * h).max(0.0);
    // Output: the deviation from the animated pose interpolated between the last two
    // steps, carried onto this frame's pose, then made to respect lengths and the
    // colliders where they are now.
    let w = (state.accumulator[ci] / h).clamp(0.0, 1.0);
    for p in cloth.points.clone() {
        state.out_world[p] = if rig.fixed[p] {
            state.targets[p]
        } else {
            state.targets[p] + state.dev_before[p].lerp(state.dev[p], w)
        };
    }
    if s.force_length_limit {
        limit_lengths(rig, ci, &mut state.out_world, None);
    }
    for _ in 0..3 {
        let mut touched = collide_with(
            state.simd,
            rig,
            ci,
            &state.colliders,
            &mut state.out_world,
            None,
            None,
            false,
            (&mut state.cores, &mut state.lanes),
        );
        if let Some(level) = level {
            let (free, radius) = (|p: usize| !rig.fixed[p], |p: usize| rig.radius[p]);
            let (out, points) = (&mut state.out_world, cloth.points.clone());
            collide_points(level, out, None, points, free, radius, |_, _| {
                touched = true
            });
        }
        if !touched {
            break;
        }
    }
    let inv = component.inverse();
    for p in cloth.points.clone() {
        state.out[p] = inv.transform_point(state.out_world[p]);
    }
}

/// Marks cloth `ci` for a reset when the character moved or turned farther than its
/// teleport thresholds since the last frame.
fn check_teleport(
    s: &super::ClothSettings,
    ci: usize,
    state: &mut ClothState,
    component: &Transform,
) {
    if state.needs_reset[ci] {
        return;
    }
    let moved = (component.translation - state.prev_component.translation).length();
    let turned = component
        .rotation
        .angle_between(state.prev_component.rotation)
        .to_degrees();
    if (s.teleport_distance > 0.0 && moved > s.teleport_distance)
        || (s.teleport_angle > 0.0 && turned > s.teleport_angle)
    {
        state.needs_reset[ci] = true;
        state.resets += 1;
    }
}

/// One frame of cloth `ci` in the `spcr` mode ([`super::spcr`]): a reset (the first
/// frame, a teleport, a non-finite point) rebuilds it on this frame's pose, as SPCR's
/// `OnResetAll`.
fn run_spcr(
    rig: &ClothRig,
    ci: usize,
    state: &mut ClothState,
    component: &Transform,
    dt: f32,
    models: &[Transform],
) {
    let cloth = &rig.cloths[ci];
    let Some(spcr) = &cloth.spcr else { return };
    check_teleport(&cloth.settings, ci, state, component);
    let frame = SpcrFrame {
        cloth,
        spcr,
        targets: &state.targets,
        joint: &rig.joint,
        models,
        component,
        colliders: &state.colliders,
        dt,
    };
    let sim = &mut state.spcr[ci];
    if state.needs_reset[ci] {
        sim.reset(&frame);
        sim.rest = 0.0;
        state.needs_reset[ci] = false;
    }
    sim.frame(&frame, &mut state.rng[ci]);
    if sim.pos.iter().any(|p| !p.is_finite()) {
        state.resets += 1;
        sim.reset(&frame);
        sim.rest = 0.0;
    }
    for p in cloth.points.clone() {
        state.out_world[p] = sim.pos[p - spcr.first].as_vec3();
    }
}

/// One fixed step of cloth `ci` with `state.step_targets` and `state.step_colliders`.
fn step(rig: &ClothRig, ci: usize, state: &mut ClothState, h: f32, level: Option<&Level>) {
    let cloth = &rig.cloths[ci];
    let s = &cloth.settings;
    let g_dir = normalize_or(s.gravity, Vec3::NEG_Y);
    for p in cloth.points.clone() {
        if rig.fixed[p] {
            state.pos[p] = state.step_targets[p];
            state.prev[p] = state.step_targets[p];
            continue;
        }
        let mut v = state.pos[p] - state.prev[p];
        if s.max_speed > 0.0 && v.length() > s.max_speed * h {
            v = v.normalize() * (s.max_speed * h);
        }
        let gust = if s.wind.gust > 0.0 {
            state.rng[ci].range_f32(1.0 - s.wind.gust, 1.0 + s.wind.gust)
        } else {
            1.0
        };
        let accel = s.gravity * rig.gravity_scale[p] + s.wind.acceleration * gust;
        let mut d = (v * (1.0 - rig.resistance[p]) + accel * (h * h)) * (1.0 - state.friction[p]);
        state.friction[p] = 0.0;
        let speed = d.length() / h;
        if speed > 1e-9 {
            let dir = d / (speed * h);
            if rig.drag[p] > 0.0 {
                let lose = (rig.drag[p] * speed * speed * h).min(speed);
                d -= dir * (lose * h);
            }
            if rig.lift[p] > 0.0 {
                // Across the motion, in the plane of motion and gravity, away from gravity.
                let lift_dir = normalize_or(dir.cross(dir.cross(g_dir)), Vec3::ZERO);
                d += lift_dir * (rig.lift[p] * speed * h * h);
            }
        }
        state.prev[p] = state.pos[p];
        state.pos[p] += d;
        let hard = rig.hardness[p];
        if hard > 0.0 {
            let pull = (state.step_targets[p] - state.pos[p]) * hard;
            state.pos[p] += pull;
        }
    }
    for it in 0..s.iterations {
        if state.simd == SimdUse::Scalar {
            // The readable reference: the rig's order.
            for c in &rig.constraints[cloth.constraints.clone()] {
                relax(&Relaxed::of(c, &rig.fixed), &mut state.pos);
            }
        } else {
            // The same constraints by dependency level (`compile::dependency_levels`):
            // the same bits, the independent ones side by side.
            for c in &cloth.relaxed {
                relax(c, &mut state.pos);
            }
        }
        let ClothState {
            pos,
            prev,
            step_colliders,
            sides,
            friction,
            cores,
            simd,
            lanes,
            ..
        } = &mut *state;
        collide_with(
            *simd,
            rig,
            ci,
            step_colliders,
            pos,
            Some(prev),
            Some((friction, &mut sides[ci])),
            // Quads (the costly test) once per step, in the last iteration.
            it + 1 == s.iterations,
            (cores, lanes),
        );
    }
    if s.limit_angle > 0.0 {
        match state.simd {
            SimdUse::Scalar => limit_angles(rig, ci, &state.step_targets, &mut state.pos),
            SimdUse::Portable | SimdUse::Avx2 | SimdUse::Auto => cloth_lanes::limit_angles(
                Isa::of(state.simd),
                rig,
                ci,
                &state.step_targets,
                &mut state.pos,
            ),
        }
    }
    // Every step (not every frame, which would make the look depend on the frame rate):
    // no chain segment longer than at rest, without adding velocity.
    if s.force_length_limit {
        limit_lengths(rig, ci, &mut state.pos, Some(&mut state.prev));
    }
    // The world has the last word of the step: swept from where each point started it,
    // sliding; a point that touched loses the cloth's friction on the next step.
    if let Some(level) = level {
        let ClothState {
            pos,
            prev,
            friction,
            ..
        } = &mut *state;
        collide_points(
            level,
            pos,
            Some(prev),
            cloth.points.clone(),
            |p| !rig.fixed[p],
            |p| rig.radius[p],
            |p, _| friction[p] = friction[p].max(rig.friction[p]),
        );
    }
}

/// One distance constraint relaxed once: its length error corrected by the share its
/// strength says, split between its movable ends.
#[inline(always)]
fn relax(c: &Relaxed, pos: &mut [Vec3]) {
    let (a, b) = (c.a as usize, c.b as usize);
    let d = pos[b] - pos[a];
    let len = d.length();
    if len < 1e-9 {
        return;
    }
    let diff = len - c.length;
    let strength = if diff > 0.0 { c.stretch } else { c.shrink };
    if strength <= 0.0 {
        return;
    }
    let corr = d * (diff / len * strength * c.share);
    pos[a] += corr * c.wa;
    pos[b] -= corr * c.wb;
}

/// [`collide`] by the code `simd` chooses: the scalar reference itself, or the same
/// tests in lanes (`dynamics/cloth/lanes.rs`), which give its bits.
#[allow(clippy::too_many_arguments)]
fn collide_with(
    simd: SimdUse,
    rig: &ClothRig,
    ci: usize,
    colliders: &[PlacedCollider],
    pos: &mut [Vec3],
    prev: Option<&[Vec3]>,
    contact: Option<(&mut [f32], &mut [i8])>,
    surfaces: bool,
    (cores, lanes): (&mut Vec<Option<Core>>, &mut ClothLaneScratch),
) -> bool {
    match simd {
        SimdUse::Scalar => collide(rig, ci, colliders, pos, prev, contact, surfaces, cores),
        SimdUse::Portable | SimdUse::Avx2 | SimdUse::Auto => cloth_lanes::collide(
            Isa::of(simd),
            rig,
            ci,
            colliders,
            pos,
            prev,
            contact,
            surfaces,
            cores,
            lanes,
        ),
    }
}

/// Keeps every free point, structural segment (if on) and quad (if on) out of the cloth's
/// colliders. With `prev`, a point that passed through a collider during the step is
/// caught too. With `contact`, touching points get the cloth's friction and quads use the
/// side memory. Returns whether anything touched. `cores` is scratch.
#[allow(clippy::too_many_arguments)]
fn collide(
    rig: &ClothRig,
    ci: usize,
    colliders: &[PlacedCollider],
    pos: &mut [Vec3],
    prev: Option<&[Vec3]>,
    mut contact: Option<(&mut [f32], &mut [i8])>,
    surfaces: bool,
    cores: &mut Vec<Option<Core>>,
) -> bool {
    let cloth = &rig.cloths[ci];
    let s = &cloth.settings;
    let mut touched = false;
    for &k in &cloth.colliders {
        let col = &colliders[k];
        for p in cloth.points.clone() {
            if rig.fixed[p] {
                continue;
            }
            let before = pos[p];
            let from = prev.map_or(before, |pr| pr[p]);
            let after = col.resolve(before, from, rig.radius[p]);
            if after != before {
                pos[p] = after;
                touched = true;
                if let Some((friction, _)) = contact.as_mut() {
                    friction[p] = rig.friction[p];
                }
            }
        }
    }
    // The colliders' cores (and their boxes) once for the segments and quads below, not
    // once per pair: the colliders do not move during the call.
    cores.clear();
    cores.extend(cloth.colliders.iter().map(|&k| Core::of(&colliders[k])));
    if s.segment_collision {
        for c in &rig.constraints[cloth.constraints.clone()] {
            if !matches!(
                c.kind,
                ConstraintKind::StructuralVertical | ConstraintKind::StructuralHorizontal
            ) {
                continue;
            }
            let (a, b) = (c.a as usize, c.b as usize);
            let r = 0.5 * (rig.radius[a] + rig.radius[b]);
            let (lo, hi) = (pos[a].min(pos[b]), pos[a].max(pos[b]));
            for core in cores.iter().flatten() {
                // Quick rejection, exact: boxes around the two segments farther apart
                // on some axis than the contact distance (with 1e-4 m to spare for
                // rounding) mean the exact test below finds no contact either.
                let reach = core.radius + r + 1e-4;
                let gap = (lo - core.hi).max(core.lo - hi);
                if gap.max_element() > reach {
                    continue;
                }
                let (mut pa, mut pb) = (pos[a], pos[b]);
                if push_segment(
                    &mut pa,
                    &mut pb,
                    [!rig.fixed[a], !rig.fixed[b]],
                    (core.e0, core.e1, core.radius + r),
                ) {
                    pos[a] = pa;
                    pos[b] = pb;
                    touched = true;
                }
            }
        }
    }
    if let (true, Some((_, sides))) = (surfaces, contact.as_mut()) {
        let m = cloth.colliders.len();
        for (qi, quad) in cloth.quads.iter().enumerate() {
            let [q00, q10, q11, q01] = quad.map(|i| i as usize);
            for (ti, [i0, i1, i2]) in [[q00, q10, q11], [q00, q11, q01]].into_iter().enumerate() {
                let r = (rig.radius[i0] + rig.radius[i1] + rig.radius[i2]) / 3.0;
                let (after, moved) = push_triangle_against(
                    [pos[i0], pos[i1], pos[i2]],
                    [!rig.fixed[i0], !rig.fixed[i1], !rig.fixed[i2]],
                    r,
                    cores,
                    s.surface_collision,
                    &mut sides[(qi * 2 + ti) * m..(qi * 2 + ti + 1) * m],
                );
                touched |= moved;
                [pos[i0], pos[i1], pos[i2]] = after;
            }
        }
    }
    touched
}

/// No chain segment longer than its rest length: walk each chain from its root. With
/// `prev`, a moved point's previous position moves along, so that the clamp adds no
/// velocity (a follow-the-leader projection otherwise pumps energy into the cloth).
fn limit_lengths(rig: &ClothRig, ci: usize, pos: &mut [Vec3], mut prev: Option<&mut [Vec3]>) {
    let cloth = &rig.cloths[ci];
    for c in &rig.constraints[cloth.constraints.clone()] {
        if c.kind != ConstraintKind::StructuralVertical {
            continue;
        }
        // Chains are stored root first, so constraints along a chain come in order.
        let (a, b) = (c.a as usize, c.b as usize);
        if rig.fixed[b] {
            continue;
        }
        let d = pos[b] - pos[a];
        let len = d.length();
        if len > c.length {
            let to = pos[a] + d * (c.length / len);
            if let Some(prev) = prev.as_mut() {
                prev[b] += to - pos[b];
            }
            pos[b] = to;
        }
    }
}

/// Limits the angle between each segment and the direction its animated segment would
/// have after its parent segment's swing.
fn limit_angles(rig: &ClothRig, ci: usize, targets: &[Vec3], pos: &mut [Vec3]) {
    let cloth = &rig.cloths[ci];
    let limit = cloth.settings.limit_angle.to_radians();
    for ch in &cloth.chains {
        for p in ch.start + 1..ch.end {
            if rig.fixed[p] {
                continue;
            }
            let parent = p - 1;
            let anim = targets[p] - targets[parent];
            let expected = if parent > ch.start {
                let grand = parent - 1;
                rotation_arc(targets[parent] - targets[grand], pos[parent] - pos[grand]) * anim
            } else {
                anim
            };
            let sim = pos[p] - pos[parent];
            let angle = expected.angle_between(sim);
            if angle.is_nan() || angle <= limit {
                continue;
            }
            let axis = normalize_or(expected.cross(sim), expected.any_orthonormal_vector());
            let dir = Quat::from_axis_angle(axis, limit) * normalize_or(expected, Vec3::NEG_Y);
            pos[p] = pos[parent] + dir * sim.length();
        }
    }
}

/// Turns each cloth bone toward its simulated successor, on top of its animated rotation.
fn write_back(
    sk: &Skeleton,
    rig: &ClothRig,
    state: &ClothState,
    locals: &mut [Transform],
    models: &mut [Transform],
) {
    for cloth in rig.cloths.iter().filter(|c| c.spcr.is_none()) {
        for ch in &cloth.chains {
            for p in ch.start..ch.end.saturating_sub(1) {
                let Some(j) = rig.joint[p] else { continue };
                if rig.fixed[p + 1] {
                    continue;
                }
                let anim = state.model_targets[p + 1] - state.model_targets[p];
                let sim = state.out[p + 1] - state.out[p];
                if anim.length_squared() < 1e-12 || sim.length_squared() < 1e-12 {
                    continue;
                }
                let new_rot = (rotation_arc(anim, sim) * models[j].rotation).normalize();
                let parent_rot = sk.parent(j).map_or(Quat::IDENTITY, |q| models[q].rotation);
                locals[j].rotation = (parent_rot.inverse() * new_rot).normalize();
                models[j].rotation = new_rot;
            }
        }
    }
}
