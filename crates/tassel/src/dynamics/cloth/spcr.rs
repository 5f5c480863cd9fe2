//! The `spcr` cloth mode: SPCRJointDynamicsUE4's update as its code runs it
//! (`Plugins/5.4/.../AnimNode_SPCRJointDynamics.cpp`, `EvaluateSkeletalControl_AnyThread`).
//!
//! One frame: the frame time is added to a rest; every whole step of `1/step_rate` in it
//! is run (the time bookkeeping in f64, as SPCR's `float`); each step puts the fixed
//! points on this frame's pose and moves the others (`UpdateControlPoints`), then per
//! iteration sweeps the colliders from last frame's place to this frame's
//! (`UpdateColliders`), relaxes the constraints in SPCR's order (`UpdateConstraints`) and,
//! on every `collision_lod`-th step counted back from the frame's last, pushes the
//! collision constraints' points and segments (`UpdateCollision`) and the quads
//! (`UpdateSurfaceCollision`) out; then the angle lock. After the steps: the length limit
//! on every constraint (`ForceFixConstraints`), and the bones are moved to the points and
//! turned toward their child (`ApplyToBone`).
//!
//! Where SPCR divides by zero (a push out of a collider whose centre the point or
//! segment sits on), this mode skips the push instead; SPCR's lengths in centimetres
//! (its tolerances) are converted to metres. Everything else, including what looks
//! accidental (the virtual tip's hardness target is its end bone mirrored, the final
//! length limit moves fixed points, the quads push fixed points), is SPCR's: see
//! `docs/cloth.md`.

use super::compile::CompiledCloth;
use super::settings::{ClothSettings, CollisionSwitches, ConstraintSwitches, SurfaceCollision};
use crate::collide::{PlacedCollider, Shape};
use crate::math::Transform;
use crate::rng::SplitMix64;
use glam::{DQuat, DVec3, Vec3};
use std::ops::Range;

/// SPCR's `SPCR_EPSILON` (1e-4) on squared centimetres, in square metres.
const EPS_SQ: f64 = 1e-8;
/// SPCR's 0.001 cm² below which a capsule's radial push is skipped, in square metres.
const CAPSULE_EPS_SQ: f64 = 1e-7;
/// Unreal's `SMALL_NUMBER` (1e-8) on squared centimetres (`GetSafeNormal`), in m².
const SAFE_SQ: f64 = 1e-12;
/// A capsule shorter than this (SPCR_EPSILON cm) is a sphere, as SPCR's `bCapsule`.
const CAPSULE_MIN_HEIGHT: f64 = 1e-6;
/// A ray that enters a triangle's plane nearer than this (0.001 cm) misses it.
const ENTER_MIN: f64 = 1e-5;

/// SPCR wraps its wind phase at this written-out π, not at `std::f64::consts::PI`.
#[allow(clippy::approx_constant)]
const SPCR_PI: f64 = 3.141592;

/// Unreal's `FMath::Clamp`: `x < lo ? lo : x < hi ? x : hi` (NaN gives `hi`).
#[inline]
fn ue_clamp(x: f64, lo: f64, hi: f64) -> f64 {
    if x < lo {
        lo
    } else if x < hi {
        x
    } else {
        hi
    }
}

/// Unreal's `GetSafeNormal`: zero below its tolerance.
#[inline]
fn safe_normal(v: DVec3) -> DVec3 {
    let sq = v.length_squared();
    if sq == 1.0 {
        v
    } else if sq < SAFE_SQ {
        DVec3::ZERO
    } else {
        v / sq.sqrt()
    }
}

/// Unreal's `FVector::Normalize`: unchanged below its tolerance.
#[inline]
fn normalized(v: DVec3) -> DVec3 {
    let sq = v.length_squared();
    if sq > SAFE_SQ {
        v / sq.sqrt()
    } else {
        v
    }
}

/// Unreal's `FMath::Lerp`.
#[inline]
fn lerp(a: DVec3, b: DVec3, t: f64) -> DVec3 {
    a + (b - a) * t
}

/// Unreal's `FQuat::FindBetweenNormals`.
pub(crate) fn find_between_normals(a: DVec3, b: DVec3) -> DQuat {
    let w = 1.0 + a.dot(b);
    let q = if w >= 1e-6 {
        let c = a.cross(b);
        glam::DVec4::new(c.x, c.y, c.z, w)
    } else if a.x.abs() > a.y.abs() {
        glam::DVec4::new(-a.z, 0.0, a.x, 0.0)
    } else {
        glam::DVec4::new(0.0, -a.z, a.y, 0.0)
    };
    let len_sq = q.length_squared();
    if len_sq > 1e-8 {
        DQuat::from_vec4(q / len_sq.sqrt())
    } else {
        DQuat::IDENTITY
    }
}

/// One SPCR constraint: its ends (global point indices), its strengths where it is
/// longer than at reset (SPCR's `Shrink`, Tassel's `stretch`) and shorter, and whether it
/// collides.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SpcrConstraint {
    pub a: u32,
    pub b: u32,
    pub long: f64,
    pub short: f64,
    pub collide: bool,
}

/// A cloth's SPCR topology and per-point values, from the rig only.
#[derive(Debug, Clone, Default)]
pub(crate) struct SpcrRig {
    /// Per point (global index − the cloth's first point).
    pub weight: Vec<f64>,
    pub resist: Vec<f64>,
    pub gravity: Vec<f64>,
    pub hardness: Vec<f64>,
    /// SPCR's drag coefficient per metre of a step's displacement.
    pub drag: Vec<f64>,
    /// SPCR's lift, metres per step.
    pub lift: Vec<f64>,
    pub radius: Vec<f64>,
    pub friction: Vec<f64>,
    pub parent: Vec<Option<u32>>,
    pub child: Vec<Option<u32>>,
    pub constraints: Vec<SpcrConstraint>,
    /// SPCR's surface constraints `[A, B, BC, AC]` (global indices).
    pub quads: Vec<[u32; 4]>,
    pub first: usize,
    pub collision_lod: u32,
    pub sub_iterations: u32,
    pub limit_from_root: bool,
    pub wind_speed: f64,
}

impl SpcrRig {
    /// The SPCR topology of a cloth whose chains (global point ranges) are `chains`;
    /// `virtual_tip[p]` says a point is a virtual tip and `fixed[p]` that it follows the
    /// animation.
    pub(crate) fn build(
        s: &ClothSettings,
        chains: &[Range<usize>],
        virtual_tip: &[bool],
        fixed: &[bool],
    ) -> SpcrRig {
        let first = chains.first().map_or(0, |c| c.start);
        let last = chains.last().map_or(0, |c| c.end);
        let n = last - first;
        let h = f64::from(1.0f32 / s.step_rate);
        let mut r = SpcrRig {
            first,
            weight: vec![0.0; n],
            resist: vec![0.0; n],
            gravity: vec![0.0; n],
            hardness: vec![0.0; n],
            drag: vec![0.0; n],
            lift: vec![0.0; n],
            radius: vec![0.0; n],
            friction: vec![0.0; n],
            parent: vec![None; n],
            child: vec![None; n],
            collision_lod: s.collision_lod.unwrap_or(2),
            sub_iterations: s.collision_sub_iterations.unwrap_or(1),
            limit_from_root: s.limit_from_root.unwrap_or(false),
            wind_speed: f64::from(s.wind.speed.unwrap_or(1.0)),
            ..SpcrRig::default()
        };
        let mut order = vec![0.0f32; n];
        let c = &s.curves;
        for ch in chains {
            let has_tip = ch.clone().any(|p| virtual_tip[p]);
            let reals = ch.len() - usize::from(has_tip);
            for (k, p) in ch.clone().enumerate() {
                let i = p - first;
                // SPCR's `OrderRate`.
                order[i] = if virtual_tip[p] {
                    1.0
                } else {
                    let den = if has_tip {
                        reals
                    } else {
                        reals.saturating_sub(1)
                    };
                    if den == 0 {
                        0.0
                    } else {
                        k as f32 / den as f32
                    }
                };
                let x = order[i];
                r.weight[i] = if fixed[p] { 0.0 } else { 1.0 };
                let v = |x: f32| f64::from(x);
                r.resist[i] = 1.0 - v((s.resistance * c.resistance.eval(x)).clamp(0.0, 1.0));
                r.gravity[i] = v(s.gravity_scale * c.gravity_scale.eval(x));
                r.hardness[i] = v((s.hardness * c.hardness.eval(x)).clamp(0.0, 1.0));
                r.drag[i] = v((2.0 * s.drag * c.drag.eval(x)).clamp(0.0, 100.0));
                r.lift[i] = v(s.lift * c.lift.eval(x).clamp(0.0, 1.0)) * h * h;
                r.radius[i] = v((s.radius * c.radius.eval(x)).max(0.0));
                r.friction[i] = v((s.friction * c.friction.eval(x)).clamp(0.0, 1.0));
                r.parent[i] = (p > ch.start).then(|| (p - 1) as u32);
                r.child[i] = (p + 1 < ch.end).then(|| (p + 1) as u32);
            }
        }
        let sw: &ConstraintSwitches = &s.constraints;
        let col: CollisionSwitches = s.collision.unwrap_or_default();
        let pick = |curves: &super::StrengthCurves, kind: usize, x: f32| -> f64 {
            f64::from(match kind {
                0 => curves.structural_vertical.eval(x),
                1 => curves.structural_horizontal.eval(x),
                2 => curves.shear.eval(x),
                3 => curves.bending_vertical.eval(x),
                _ => curves.bending_horizontal.eval(x),
            })
        };
        let add = |out: &mut Vec<SpcrConstraint>, a: usize, b: usize, kind: usize, collide| {
            if fixed[a] && fixed[b] {
                return;
            }
            let x = (order[a - first] + order[b - first]) * 0.5;
            out.push(SpcrConstraint {
                a: a as u32,
                b: b as u32,
                long: pick(&s.stretch, kind, x),
                short: pick(&s.shrink, kind, x),
                collide,
            });
        };
        let count = chains.len();
        // Pairs of chains `gap` apart, as SPCR's `CreateConstraint…Horizontal` and
        // `…Shear` take them (wrapping with `bJointLoop`).
        let pairs = |gap: usize| -> Vec<(usize, usize)> {
            if count < 2 {
                Vec::new()
            } else if s.loop_chains {
                (0..count).map(|i| (i, (i + gap) % count)).collect()
            } else {
                (0..count.saturating_sub(gap))
                    .map(|i| (i, i + gap))
                    .collect()
            }
        };
        let at = |ch: &Range<usize>, k: usize| ch.start + k.min(ch.len() - 1);
        let mut cons = Vec::new();
        if sw.bending_horizontal {
            for (i, j) in pairs(2) {
                let (a, b) = (&chains[i], &chains[j]);
                for k in 0..a.len().max(b.len()) {
                    add(&mut cons, at(a, k), at(b, k), 4, false);
                }
            }
        }
        if sw.bending_vertical {
            for ch in chains {
                for k in 0..ch.len().saturating_sub(2) {
                    add(&mut cons, ch.start + k, ch.start + k + 2, 3, false);
                }
            }
        }
        if sw.shear {
            for (i, j) in pairs(1) {
                let (a, b) = (&chains[i], &chains[j]);
                let m = a.len().max(b.len());
                for k in 0..m {
                    add(&mut cons, at(a, k + 1), at(b, k), 2, col.shear);
                }
                for k in 0..m {
                    add(&mut cons, at(a, k), at(b, k + 1), 2, col.shear);
                }
            }
        }
        if sw.structural_horizontal {
            for (i, j) in pairs(1) {
                let (a, b) = (&chains[i], &chains[j]);
                for k in 0..a.len().max(b.len()) {
                    add(&mut cons, at(a, k), at(b, k), 1, col.structural_horizontal);
                }
            }
        }
        if sw.structural_vertical {
            for _ in 0..s.structural_vertical_step_count.unwrap_or(1) {
                for ch in chains {
                    for k in 0..ch.len().saturating_sub(1) {
                        add(
                            &mut cons,
                            ch.start + k,
                            ch.start + k + 1,
                            0,
                            col.structural_vertical,
                        );
                    }
                }
            }
        }
        r.constraints = cons;
        // `CreateSurfaceConstraints`: neighbouring chains, never wrapping.
        for i in 0..count.saturating_sub(1) {
            let (a, b) = (&chains[i], &chains[i + 1]);
            for k in 0..a.len().max(b.len()) {
                let q = [at(a, k), at(b, k), at(b, k + 1), at(a, k + 1)];
                if q.iter().any(|&p| !fixed[p]) {
                    r.quads.push(q.map(|p| p as u32));
                }
            }
        }
        r
    }
}

/// A collider as SPCR keeps it: a sphere, or a capsule from its −Y end along its full
/// axis, each with its place at the last frame's end, before this iteration and now.
/// Other shapes act on points only, where they are this frame.
#[derive(Debug, Clone, Copy)]
pub(crate) enum SpcrCollider {
    Round {
        capsule: bool,
        radius: f64,
        height: f64,
        pos: DVec3,
        dir: DVec3,
        pos_prev: DVec3,
        dir_prev: DVec3,
        pos_frame: DVec3,
        dir_frame: DVec3,
    },
    Other(PlacedCollider),
}

impl SpcrCollider {
    /// SPCR's place of `col` this frame: (capsule, radius, height, position, direction).
    fn target(col: &PlacedCollider) -> Option<(bool, f64, f64, DVec3, DVec3)> {
        match col.shape {
            Shape::Sphere {
                radius,
                inside: false,
            } => Some((
                false,
                radius.into(),
                0.0,
                d3(col.transform.translation),
                DVec3::ZERO,
            )),
            Shape::Capsule { radius, length } if f64::from(length) > CAPSULE_MIN_HEIGHT => {
                let (a, b) = col.capsule_ends(length);
                let (a, b) = (d3(a), d3(b));
                Some((true, radius.into(), length.into(), a, b - a))
            }
            Shape::Capsule { radius, .. } => Some((
                false,
                radius.into(),
                0.0,
                d3(col.transform.translation),
                DVec3::ZERO,
            )),
            _ => None,
        }
    }

    /// At reset (`InitializeColliderPositionOld`): everything at this frame's place.
    fn reset(col: &PlacedCollider) -> SpcrCollider {
        match Self::target(col) {
            Some((capsule, radius, height, p, d)) => SpcrCollider::Round {
                capsule,
                radius,
                height,
                pos: p,
                dir: d,
                pos_prev: p,
                dir_prev: d,
                pos_frame: p,
                dir_frame: d,
            },
            None => SpcrCollider::Other(*col),
        }
    }

    /// `UpdateColliders`: a share `delta` of the way from the last frame's place to this
    /// frame's, the place before kept for the sub-iterations.
    fn sweep(&mut self, col: &PlacedCollider, delta: f64) {
        match (Self::target(col), &mut *self) {
            (
                Some((capsule, r, h, p, d)),
                SpcrCollider::Round {
                    capsule: c,
                    radius,
                    height,
                    pos,
                    dir,
                    pos_prev,
                    dir_prev,
                    pos_frame,
                    dir_frame,
                },
            ) => {
                *c = capsule;
                *radius = r;
                *height = h;
                *pos_prev = *pos;
                *pos = lerp(*pos_frame, p, delta);
                if capsule {
                    *dir_prev = *dir;
                    *dir = lerp(*dir_frame, d, delta);
                }
            }
            _ => *self = SpcrCollider::reset(col),
        }
    }

    /// `UpdateColliderInfoAtEnd`.
    fn end_frame(&mut self, col: &PlacedCollider) {
        match self {
            SpcrCollider::Round {
                pos,
                dir,
                pos_frame,
                dir_frame,
                ..
            } => {
                *pos_frame = *pos;
                *dir_frame = *dir;
            }
            SpcrCollider::Other(c) => *c = *col,
        }
    }
}

/// A cloth's SPCR state.
#[derive(Debug, Clone, Default)]
pub(crate) struct SpcrState {
    pub pos: Vec<DVec3>,
    pub prev: Vec<DVec3>,
    pub friction: Vec<f64>,
    pub initial: Vec<DVec3>,
    /// Per point whose child is a virtual tip: SPCR's `CSBoneDirection`.
    pub tip_dir: Vec<DVec3>,
    pub length: Vec<f64>,
    pub colliders: Vec<SpcrCollider>,
    /// Scratch: the points in the character's space.
    pub cs: Vec<DVec3>,
    /// SPCR's `_RestDeltaTime` (a `float`).
    pub rest: f32,
    pub wind_phase: f64,
}

/// What one frame of an SPCR cloth reads.
pub(crate) struct SpcrFrame<'a> {
    pub cloth: &'a CompiledCloth,
    pub spcr: &'a SpcrRig,
    /// World positions of the points on this frame's pose (virtual tips Tassel's way,
    /// used at reset only).
    pub targets: &'a [Vec3],
    /// Joint of each point (`None` for a virtual tip).
    pub joint: &'a [Option<usize>],
    pub models: &'a [Transform],
    pub component: &'a Transform,
    /// This frame's colliders (world), by rig collider index.
    pub colliders: &'a [PlacedCollider],
    pub dt: f32,
}

/// A transform in f64 (SPCR on Unreal 5 works in doubles).
#[derive(Clone, Copy)]
struct Placed {
    t: DVec3,
    r: DQuat,
    s: DVec3,
}

impl Placed {
    fn transform_point(&self, p: DVec3) -> DVec3 {
        self.t + self.r * (self.s * p)
    }
}

#[inline]
fn d3(v: Vec3) -> DVec3 {
    v.as_dvec3()
}

impl SpcrFrame<'_> {
    /// Bone `j`'s component-space rotation, in f64.
    fn rotation(&self, j: usize) -> DQuat {
        self.models[j].rotation.as_dquat()
    }

    /// Bone `j`'s world transform (`BoneCSTransform * ComponentTransform`), in f64.
    fn world(&self, j: usize) -> Placed {
        let (c, m) = (self.component, &self.models[j]);
        let (cr, cs) = (c.rotation.as_dquat(), d3(c.scale));
        Placed {
            t: d3(c.translation) + cr * (cs * d3(m.translation)),
            r: cr * m.rotation.as_dquat(),
            s: cs * d3(m.scale),
        }
    }
}

impl SpcrState {
    /// `OnResetAll`: the points on this frame's pose, the constraints' lengths, the tips'
    /// directions, the colliders at their place.
    pub(crate) fn reset(&mut self, f: &SpcrFrame) {
        let r = f.spcr;
        let n = r.weight.len();
        self.pos = vec![DVec3::ZERO; n];
        self.tip_dir = vec![DVec3::ZERO; n];
        for ch in &f.cloth.chains {
            for p in ch.clone() {
                let i = p - r.first;
                self.pos[i] = match f.joint[p] {
                    Some(j) => f.world(j).t,
                    // A chain of one bone and its tip has no segment before the tip
                    // (SPCR reads before its table there): Tassel's tip place.
                    None if p < ch.start + 2 => d3(f.targets[p]),
                    None => {
                        // SPCR: past the end bone along the last segment; the end bone
                        // keeps the tip's direction in its component-space frame.
                        let (p0, p1) = (self.pos[i - 2], self.pos[i - 1]);
                        let len = f64::from(f.cloth.settings.virtual_bone_length);
                        let tip = p1 + safe_normal(p1 - p0) * len;
                        if let Some(j) = f.joint[p - 1] {
                            self.tip_dir[i - 1] = f.rotation(j).inverse() * (p1 - tip);
                        }
                        tip
                    }
                };
            }
        }
        self.prev = self.pos.clone();
        self.initial = self.pos.clone();
        self.friction = vec![0.0; n];
        self.length = r
            .constraints
            .iter()
            .map(|c| (self.at(r, c.a) - self.at(r, c.b)).length())
            .collect();
        self.colliders = f
            .cloth
            .colliders
            .iter()
            .map(|&i| SpcrCollider::reset(&f.colliders[i]))
            .collect();
    }

    #[inline]
    fn at(&self, r: &SpcrRig, p: u32) -> DVec3 {
        self.pos[p as usize - r.first]
    }

    /// One frame; returns the number of steps taken.
    pub(crate) fn frame(&mut self, f: &SpcrFrame, rng: &mut SplitMix64) -> u32 {
        let s = &f.cloth.settings;
        let h = 1.0f32 / s.step_rate;
        self.rest += f.dt;
        let mut loops = (self.rest / h) as i64;
        let cap = i64::from(s.max_steps_per_frame);
        if loops > cap {
            self.rest -= (loops - cap) as f32 * h;
            loops = cap;
        }
        for i in (0..loops).rev() {
            self.rest -= h;
            let mut wind = DVec3::ZERO;
            if f.spcr.wind_speed > 0.0 {
                self.wind_phase += f64::from(h) * f.spcr.wind_speed;
                if self.wind_phase.abs() > 1e6 {
                    // SPCR's loops below would not end (a turn is lost in the rounding).
                    self.wind_phase %= SPCR_PI * 2.0;
                }
                while self.wind_phase > SPCR_PI {
                    self.wind_phase -= SPCR_PI * 2.0;
                }
                while self.wind_phase < -SPCR_PI {
                    self.wind_phase += SPCR_PI * 2.0;
                }
                wind = d3(s.wind.acceleration) * (self.wind_phase.sin() * 0.5 + 0.5);
            }
            self.control_points(f, wind, f64::from(h), rng);
            let iterations = s.iterations;
            for relax in 1..=iterations {
                let delta = relax as f64 / iterations as f64;
                for (c, &k) in self.colliders.iter_mut().zip(&f.cloth.colliders) {
                    c.sweep(&f.colliders[k], delta);
                }
                self.constraints(f.spcr);
                if i % i64::from(f.spcr.collision_lod) == 0 {
                    let subs = f.spcr.sub_iterations;
                    for sub in 1..=subs {
                        let sub_delta = sub as f64 / subs as f64;
                        self.collision(f, sub_delta);
                        if s.surface_collision != SurfaceCollision::Off {
                            self.surface_collision(f, sub_delta);
                        }
                    }
                }
            }
            if s.limit_angle > 0.0 {
                self.lock_angles(f);
            }
        }
        if s.force_length_limit {
            self.force_lengths(f.spcr);
        }
        for (c, &k) in self.colliders.iter_mut().zip(&f.cloth.colliders) {
            c.end_frame(&f.colliders[k]);
        }
        loops as u32
    }

    /// `UpdateControlPoints`.
    fn control_points(&mut self, f: &SpcrFrame, wind: DVec3, h: f64, rng: &mut SplitMix64) {
        let r = f.spcr;
        let s = &f.cloth.settings;
        // SPCR's `StepTime_x2_Half` is a `float`.
        let half_h2 = f64::from((h * h * 0.5) as f32);
        let gravity = d3(s.gravity);
        let g_dir = safe_normal(gravity);
        for ch in &f.cloth.chains {
            for p in ch.clone() {
                let i = p - r.first;
                if r.weight[i] == 0.0 {
                    // SPCR's fixed points are the first `FixedPointIndex + 1` of a chain.
                    let here = match f.joint[p] {
                        Some(j) => f.world(j).t,
                        None => d3(f.targets[p]),
                    };
                    self.pos[i] = here;
                    self.prev[i] = here;
                    continue;
                }
                let gust = if s.wind.gust > 0.0 {
                    f64::from(rng.range_f32(1.0 - s.wind.gust, 1.0 + s.wind.gust))
                } else {
                    1.0
                };
                let mut d = gravity * r.gravity[i];
                d += wind * gust;
                d *= half_h2;
                d += self.pos[i] - self.prev[i];
                d *= r.resist[i];
                d *= 1.0 - self.friction[i].clamp(0.0, 1.0);
                if r.drag[i] > 0.0 {
                    let speed_sq = d.length_squared();
                    let n = safe_normal(d);
                    d += -((n * (r.drag[i] * speed_sq)) / 2.0);
                }
                if r.lift[i] > 0.0 {
                    let motion = safe_normal(d);
                    let side = motion.cross(g_dir);
                    d += motion.cross(side) * r.lift[i];
                }
                self.prev[i] = self.pos[i];
                self.pos[i] += d;
                self.friction[i] = 0.0;
                if r.hardness[i] > 0.0 {
                    let target = match f.joint[p] {
                        Some(j) => f.world(j).t,
                        None => {
                            // SPCR's `Parent.CSBoneDirection` (the way from the tip to
                            // its bone) put through the bone's transform: the tip's
                            // place mirrored through the bone.
                            let parent = p - 1;
                            match f.joint[parent] {
                                Some(j) => f.world(j).transform_point(self.tip_dir[i - 1]),
                                None => d3(f.targets[p]),
                            }
                        }
                    };
                    let here = self.pos[i];
                    self.pos[i] = here + (target - here) * r.hardness[i];
                }
            }
        }
    }

    /// `UpdateConstraints`.
    fn constraints(&mut self, r: &SpcrRig) {
        for (c, &length) in r.constraints.iter().zip(&self.length) {
            let (a, b) = (c.a as usize - r.first, c.b as usize - r.first);
            let (wa, wb) = (r.weight[a], r.weight[b]);
            if wa + wb < 0.001 {
                continue;
            }
            let dir = self.pos[b] - self.pos[a];
            let force = dir.length() - length;
            let power = if force >= 0.0 { c.long } else { c.short };
            if power > 0.0 {
                let d = safe_normal(dir) * (force * power);
                let w = wa + wb;
                self.pos[a] += d * wa / w;
                self.pos[b] -= d * wb / w;
            }
        }
    }

    /// `UpdateCollision`: per collision constraint, its free ends pushed out of every
    /// collider, then its segment.
    fn collision(&mut self, f: &SpcrFrame, delta: f64) {
        let r = f.spcr;
        let segments = f.cloth.settings.segment_collision;
        for c in r.constraints.iter().filter(|c| c.collide) {
            let (a, b) = (c.a as usize - r.first, c.b as usize - r.first);
            let (wa, wb) = (r.weight[a], r.weight[b]);
            if wa + wb < 0.001 {
                continue;
            }
            for col in &self.colliders {
                if wa > 0.0 {
                    self.pos[a] = push_point(col, self.pos[a], r.radius[a], delta);
                }
                if wb > 0.0 {
                    self.pos[b] = push_point(col, self.pos[b], r.radius[b], delta);
                }
            }
            if !segments {
                continue;
            }
            let mut friction = 0.0f64;
            let extra = (r.radius[a] + r.radius[b]) * 0.5;
            for col in &self.colliders {
                let (pa, pb) = (self.pos[a], self.pos[b]);
                let Some((on_line, on_col, radius)) = segment_contact(col, pa, pb, extra, delta)
                else {
                    continue;
                };
                let push = on_line - on_col;
                let dist = push.length();
                let half = (pb - pa).length() * 0.5;
                let rate1 = ue_clamp((on_line - pa).length() / half, 0.0, 1.0);
                let rate2 = ue_clamp((on_line - pb).length() / half, 0.0, 1.0);
                if dist > 0.0 {
                    let out = push / dist * (radius - dist).max(0.0);
                    if wa > 0.0 {
                        self.pos[a] += out * rate2;
                    }
                    if wb > 0.0 {
                        self.pos[b] += out * rate1;
                    }
                }
                let dot = DVec3::Y.dot(safe_normal(push));
                friction = friction.max(ue_clamp(dot.abs(), 0.0, 1.0));
            }
            self.friction[a] = (friction * r.friction[a]).max(self.friction[a]);
            self.friction[b] = (friction * r.friction[b]).max(self.friction[b]);
        }
    }

    /// `UpdateSurfaceCollision`: each quad's two triangles against every round collider.
    fn surface_collision(&mut self, f: &SpcrFrame, delta: f64) {
        let r = f.spcr;
        let pull = f.cloth.settings.surface_collision == SurfaceCollision::PushPull;
        for q in &r.quads {
            let [a, b, c, d] = q.map(|p| p as usize - r.first);
            for col in &self.colliders {
                for tri in [[a, b, c], [c, d, a]] {
                    let extra = (r.radius[tri[0]] + r.radius[tri[1]] + r.radius[tri[2]]) / 3.0;
                    let corners = tri.map(|p| self.pos[p]);
                    let Some((hit, push, radius)) =
                        surface_contact(col, corners, extra, pull, delta)
                    else {
                        continue;
                    };
                    let centre = triangle_centre(corners);
                    let magnitude = push.length();
                    let dir = normalized(push);
                    for &p in &tri {
                        let rate = (self.pos[p] - centre).length() / (self.pos[p] - hit).length();
                        let rate = ue_clamp(rate.abs(), 0.0, 1.0);
                        self.pos[p] += dir * (radius - magnitude) * rate;
                    }
                }
            }
        }
    }

    /// `UpdateLockAngles`: every bone point's segment within `limit_angle` of its parent
    /// segment (of its direction at reset, for a segment from a root or with
    /// `limit_from_root`).
    fn lock_angles(&mut self, f: &SpcrFrame) {
        let r = f.spcr;
        let limit = f.cloth.settings.limit_angle;
        for ch in &f.cloth.chains {
            for p in ch.clone() {
                if f.joint[p].is_none() {
                    continue;
                }
                let i = p - r.first;
                let Some(parent) = r.parent[i] else { continue };
                let pi = parent as usize - r.first;
                let grand = r.parent[pi].map_or(self.pos[pi], |g| self.pos[g as usize - r.first]);
                let bone = self.pos[i] - self.pos[pi];
                let mut parent_dir = self.pos[pi] - grand;
                if parent_dir.length() == 0.0 || r.limit_from_root {
                    parent_dir = self.initial[i] - self.initial[pi];
                }
                let cos = safe_normal(parent_dir).dot(safe_normal(bone));
                let angle = cos.acos().to_degrees();
                let over = angle - f64::from(limit);
                if over > 0.0 {
                    let axis = safe_normal(parent_dir.cross(bone));
                    self.pos[i] = self.pos[pi] + rotate_angle_axis(bone, -over, axis);
                }
            }
        }
    }

    /// `ForceFixConstraints`: no constraint longer than at reset, its second end moved.
    fn force_lengths(&mut self, r: &SpcrRig) {
        for (c, &length) in r.constraints.iter().zip(&self.length) {
            let (a, b) = (c.a as usize - r.first, c.b as usize - r.first);
            let dir = self.pos[b] - self.pos[a];
            if dir.length() > length {
                self.pos[b] = self.pos[a] + safe_normal(dir) * length;
            }
        }
    }

    /// `ApplyToBone`: each bone moved to its point and turned by the arc from its animated
    /// direction to its child to the simulated one. Writes `locals` and `models` of the
    /// cloth's bones (parents before children) and the points in the character's space
    /// into `out`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn apply(
        &mut self,
        cloth: &CompiledCloth,
        r: &SpcrRig,
        joint: &[Option<usize>],
        component: &Transform,
        sk: &crate::skeleton::Skeleton,
        locals: &mut [Transform],
        models: &mut [Transform],
        out: &mut [Vec3],
    ) {
        // `CompT.InverseTransformPosition`, in f64.
        let (ct, cr, cs) = (
            d3(component.translation),
            component.rotation.as_dquat().inverse(),
            d3(component.scale),
        );
        self.cs.clear();
        self.cs
            .extend(self.pos.iter().map(|&p| (cr * (p - ct)) / cs));
        for p in cloth.points.clone() {
            out[p] = self.cs[p - r.first].as_vec3();
        }
        for ch in &cloth.chains {
            for p in ch.clone() {
                let Some(j) = joint[p] else { continue };
                let i = p - r.first;
                let anim = models[j];
                let anim_rot = anim.rotation.as_dquat();
                let mut rotation = anim.rotation;
                if let Some(child) = r.child[i] {
                    let c = child as usize;
                    let to_target = self.cs[i] - self.cs[c - r.first];
                    let to_current = match joint[c] {
                        None => anim_rot * self.tip_dir[i],
                        Some(cj) => d3(anim.translation) - d3(models[cj].translation),
                    };
                    let add = find_between_normals(safe_normal(to_current), safe_normal(to_target));
                    rotation = (add * anim_rot).normalize().as_quat();
                }
                let model = Transform {
                    translation: out[p],
                    rotation,
                    scale: anim.scale,
                };
                let parent = sk.parent(j).map_or(Transform::IDENTITY, |q| models[q]);
                locals[j] = parent.inverse() * model;
                models[j] = model;
            }
        }
    }
}

/// Unreal's `FVector::RotateAngleAxis` (degrees).
fn rotate_angle_axis(v: DVec3, degrees: f64, axis: DVec3) -> DVec3 {
    let (s, c) = degrees.to_radians().sin_cos();
    let (x, y, z) = (axis.x, axis.y, axis.z);
    let omc = 1.0 - c;
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let (xy, yz, zx) = (x * y, y * z, z * x);
    let (xs, ys, zs) = (x * s, y * s, z * s);
    DVec3::new(
        (omc * xx + c) * v.x + (omc * xy - zs) * v.y + (omc * zx + ys) * v.z,
        (omc * xy + zs) * v.x + (omc * yy + c) * v.y + (omc * yz - xs) * v.z,
        (omc * zx - ys) * v.x + (omc * yz + xs) * v.y + (omc * zz + c) * v.z,
    )
}

fn triangle_centre([a, b, c]: [DVec3; 3]) -> DVec3 {
    let ab = lerp(a, b, 0.5);
    let ac = lerp(a, c, 0.5);
    lerp(ab, ac, 0.5)
}

/// `PushoutFromSphere`.
fn push_from_sphere(centre: DVec3, radius: f64, p: DVec3) -> DVec3 {
    let d = p - centre;
    let sq = d.length_squared();
    if sq > EPS_SQ && sq < radius * radius {
        centre + d * radius / sq.sqrt()
    } else {
        p
    }
}

/// `PushoutFromCollider` for a point of radius `extra` (SPCR's points have none).
fn push_point(col: &SpcrCollider, p: DVec3, extra: f64, delta: f64) -> DVec3 {
    match *col {
        SpcrCollider::Round {
            capsule: false,
            radius,
            pos,
            pos_prev,
            ..
        } => push_from_sphere(lerp(pos_prev, pos, delta), radius + extra, p),
        SpcrCollider::Round {
            capsule: true,
            radius,
            height,
            pos,
            dir,
            pos_prev,
            dir_prev,
            ..
        } => {
            let radius = radius + extra;
            let axis = lerp(dir_prev, dir, delta);
            let n = normalized(axis);
            let base = lerp(pos_prev, pos, delta);
            let along = n.dot(p - base);
            if along <= 0.0 {
                push_from_sphere(base, radius, p)
            } else if along >= height {
                push_from_sphere(base + axis, radius, p)
            } else {
                let on = base + n * along;
                let out = p - on;
                let sq = out.length_squared();
                if sq > CAPSULE_EPS_SQ && sq < radius * radius {
                    on + out * radius / sq.sqrt()
                } else {
                    p
                }
            }
        }
        SpcrCollider::Other(c) => {
            let q = p.as_vec3();
            d3(c.resolve(q, q, extra as f32))
        }
    }
}

/// `CollisionDetection_Sphere`: (point on the segment, the centre, radius) if they meet.
fn sphere_segment(centre: DVec3, radius: f64, p1: DVec3, p2: DVec3) -> (bool, DVec3, DVec3) {
    let d = p2 - p1;
    let len = d.length();
    let dir = d / len;
    let dot = dir.dot(centre - p1);
    let on_line = dir * ue_clamp(dot, 0.0, len) + p1;
    (
        (centre - on_line).length_squared() <= radius * radius,
        on_line,
        centre,
    )
}

/// `CollisionDetection`: where segment `p1`–`p2` meets a round collider, as SPCR finds
/// it: (point on the segment, point on the collider, radius). A segment of no length
/// meets nothing here (SPCR divides by its length).
fn segment_contact(
    col: &SpcrCollider,
    p1: DVec3,
    p2: DVec3,
    extra: f64,
    delta: f64,
) -> Option<(DVec3, DVec3, f64)> {
    let SpcrCollider::Round {
        capsule,
        radius,
        pos,
        dir,
        pos_prev,
        dir_prev,
        ..
    } = *col
    else {
        return None;
    };
    if (p2 - p1).length_squared() == 0.0 {
        return None;
    }
    let radius = radius + extra;
    let base = lerp(pos_prev, pos, delta);
    if !capsule {
        let (hit, on_line, on_col) = sphere_segment(base, radius, p1, p2);
        return hit.then_some((on_line, on_col, radius));
    }
    let axis = lerp(dir_prev, dir, delta);
    for centre in [base, base + axis] {
        let (hit, on_line, on_col) = sphere_segment(centre, radius, p1, p2);
        if hit {
            return Some((on_line, on_col, radius));
        }
    }
    // `ComputeNearestPoints` of the two lines.
    let seg = p2 - p1;
    let n1 = axis.cross(seg.cross(axis));
    let n2 = seg.cross(axis.cross(seg));
    let t1 = (p1 - base).dot(n2) / axis.dot(n2);
    let t2 = (base - p1).dot(n1) / seg.dot(n1);
    let sq = ((p1 + seg * t2) - (base + axis * t1)).length_squared();
    if sq > radius * radius {
        return None;
    }
    let (t1, t2) = (ue_clamp(t1, 0.0, 1.0), ue_clamp(t2, 0.0, 1.0));
    let on_col = base + axis * t1;
    let on_line = p1 + seg * t2;
    ((on_col - on_line).length_squared() <= radius * radius).then_some((on_line, on_col, radius))
}

/// `SimpleRaycast` against the plane `n·x + dist = 0`.
fn raycast(origin: DVec3, dir: DVec3, n: DVec3, dist: f64) -> Option<f64> {
    let v = dir.dot(n);
    let o = -origin.dot(n) - dist;
    if v.abs() <= 0.001 {
        return None;
    }
    let enter = o / v;
    (enter > ENTER_MIN).then_some(enter)
}

fn triangle_contains([a, b, c]: [DVec3; 3], p: DVec3) -> bool {
    let (ap, bp, cp) = (a - p, b - p, c - p);
    let u = ap.cross(bp);
    let v = bp.cross(cp);
    let w = cp.cross(ap);
    !(u.dot(v) < 0.0 || v.dot(w) < 0.0)
}

/// `CheckCollision` of `UpdateSurfaceCollision`: (intersection, push, radius) when a
/// round collider is within its radius of the triangle. `pull` is SPCR's
/// `SurfaceColliderType` PUSH (a capsule through the cloth's middle is cast along its
/// axis); else OFF.
fn surface_contact(
    col: &SpcrCollider,
    tri: [DVec3; 3],
    extra: f64,
    pull: bool,
    delta: f64,
) -> Option<(DVec3, DVec3, f64)> {
    let SpcrCollider::Round {
        capsule,
        radius,
        pos,
        dir,
        pos_prev,
        dir_prev,
        ..
    } = *col
    else {
        return None;
    };
    let radius = radius + extra;
    let [a, b, c] = tri;
    let col_pos = lerp(pos_prev, pos, delta);
    let col_dir = lerp(dir_prev, dir, delta);
    let col_n = safe_normal(col_dir);
    let centre = triangle_centre(tri);
    let to_col = normalized(col_pos - centre);
    let mut normal = normalized(safe_normal(b - a).cross(safe_normal(c - a)));
    let plane = -normal.dot(a);
    normal = -normal;
    let side_dot = to_col.dot(normal);
    let inverse = -normal;
    let within = |on_col: DVec3, hit: DVec3| (on_col - hit).length_squared() <= radius * radius;
    if capsule {
        let side = col_n.dot(normal) * side_dot;
        let towards = normalized(normal * side_dot * -1.0);
        let start = if side < 0.0 {
            col_pos + (col_dir * 0.5) * 2.0
        } else {
            col_pos
        };
        if let Some(enter) = raycast(start, towards, inverse, plane) {
            let hit = start + towards * enter;
            if triangle_contains(tri, hit) {
                return within(start, hit).then_some((hit, hit - start, radius));
            }
        } else if pull {
            // A capsule through the cloth's middle: cast along its axis.
            let on_col = col_pos;
            let end = col_pos + (col_dir * 0.5) * 2.0;
            if let Some(enter) = raycast(on_col, col_dir, inverse, plane) {
                let hit = on_col + col_dir * enter;
                if triangle_contains(tri, hit) {
                    let to_end = end - on_col;
                    let to_hit = hit - on_col;
                    let point_dot = (end - hit).dot(to_hit);
                    let line_dot = to_end.dot(to_end);
                    if !(point_dot >= 0.0 && point_dot <= line_dot) {
                        return None;
                    }
                    let ce = to_end.dot(to_hit);
                    let back = on_col + safe_normal(to_end) * -radius;
                    let push = hit - back;
                    let on_axis = on_col + to_end * (ce / line_dot);
                    return within(on_axis, hit).then_some((hit, push, radius));
                }
            }
        }
        None
    } else {
        let towards = normal * side_dot * -1.0;
        let enter = raycast(col_pos, towards, inverse, plane)?;
        let hit = col_pos + towards * enter;
        (triangle_contains(tri, hit) && within(col_pos, hit)).then_some((
            hit,
            hit - col_pos,
            radius,
        ))
    }
}
