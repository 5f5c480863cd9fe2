//! The `spcr` cloth mode: SPCRJointDynamicsUE4's update as its code runs it
//! (`Plugins/5.4/.../AnimNode_SPCRJointDynamics.cpp`, `EvaluateSkeletalControl_AnyThread`).
//!
//! One frame: the frame time is added to a rest; every whole step of `1/step_rate` in it
//! is run (the time bookkeeping in f32, as SPCR's `float`; the rest in f64, as SPCR's
//! `FVector` on Unreal 5); each step puts the fixed
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
//!
//! `topology.rs` builds SPCR's constraints and quads from the rig, `collider.rs` keeps the
//! colliders as SPCR does and holds its contact tests, `ue.rs` the few Unreal math
//! functions whose exact arithmetic SPCR's results depend on.

mod collider;
mod topology;
mod ue;

pub(crate) use topology::SpcrRig;

use super::compile::CompiledCloth;
use super::settings::SurfaceCollision;
use crate::collide::PlacedCollider;
use crate::math::Transform;
use crate::rng::SplitMix64;
use collider::{d3, push_point, segment_contact, surface_contact, triangle_centre, SpcrCollider};
use glam::{DQuat, DVec3, Vec3};
use ue::{find_between_normals, normalized, rotate_angle_axis, safe_normal, ue_clamp, SPCR_PI};

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
            // The hitch guard (SPCR has none): the steps beyond it are dropped, the part of
            // a step left over kept. (Subtracting the dropped time would lose the rest to
            // f32 rounding after a long hitch and stall the next frames.)
            self.rest = self.rest % h + cap as f32 * h;
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
