//! One solver step of one chain: the readable, per-point reference path.

use super::compile::{ChainRig, NONE};
use super::constraint::{solve, ChainGroup};
use super::settings::{ChainSettings, ClassicGravity, PlanarAxis, TimeMode};
use crate::collide::{NearSet, PlacedCollider};
use crate::math::normalize_or;
use crate::rng::SplitMix64;
use glam::{Quat, Vec3};

/// Everything one step reads besides the rig and the points.
pub(crate) struct StepInput<'a> {
    /// Animated target positions of every point (model space) at the end of the step.
    pub targets: &'a [Vec3],
    /// Planar-constraint normals per point (the parent's animated axis).
    pub normals: &'a [Vec3],
    /// All colliders, placed at the end of the step.
    pub colliders: &'a [PlacedCollider],
    /// Their bounding spheres ([`PlacedCollider::bound_sphere`]), for the broad phase.
    pub bounds: &'a [glam::Vec4],
    /// The old character origin seen from the new character space.
    pub move_cs: Vec3,
    /// The old character rotation seen from the new character space.
    pub rotate_cs: Quat,
    /// Gravity in character space.
    pub gravity_cs: Vec3,
    /// Wind direction in character space (unit or zero).
    pub wind_cs: Vec3,
    /// Step length and the previous step's length, seconds.
    pub dt: f32,
    pub dt_old: f32,
    /// The part of the step taken: 1, but in fixed mode's output step (the time left
    /// over after the frame's steps over the step's length), which moves the points by
    /// that part of each of the step's terms (velocity, gravity, pull, push; the
    /// character's motion is its own, from the last step to the frame) and of each bone
    /// constraint's correction.
    pub part: f32,
    /// True in fixed mode (gravity as an acceleration).
    pub fixed: bool,
    /// The world, when the chain collides with it and geometry is near.
    pub world: Option<crate::dynamics::world::WorldContact<'a>>,
    /// External forces this step, per point (empty: none act on the chain): the push
    /// (`x += push × dt`, after inertia, before the pull) and the acceleration
    /// (`v += accel × dt`, before the point moves).
    pub push: &'a [Vec3],
    pub accel: &'a [Vec3],
    /// `base_bone` space: the base bone's transforms at the last step and at this one.
    /// The points were carried from the first to the second; the character's turn acts
    /// on where they were (KawaiiPhysics' follow-rotation in base-bone space).
    pub base: Option<(crate::math::Transform, crate::math::Transform)>,
    /// The per-point settings (the rig's, or scaled by timed overrides).
    pub params: super::overrides::Params<'a>,
    /// The chain's colliders (indices into `colliders`: the rig's, and the shared ones
    /// when the chain uses them), and every collider's (the bridge points').
    pub list: &'a [usize],
    pub every: &'a [usize],
}

/// What one step of a chain uses for every point.
struct ChainStep {
    exponent: f32,
    /// The time the points move: `dt · part`.
    moved: f32,
    gravity_step: Vec3,
    wind_on: bool,
    /// The wind's direction noise, radians (0: none).
    wind_noise: f32,
}

impl ChainStep {
    fn of(s: &ChainSettings, input: &StepInput) -> Self {
        Self {
            exponent: s.target_framerate * input.dt,
            moved: input.dt * input.part,
            gravity_step: gravity_step(s, input.gravity_cs, input.dt, input.fixed) * input.part,
            wind_on: s.wind.speed > 0.0 && input.wind_cs != Vec3::ZERO,
            wind_noise: s.wind.direction_noise_angle.to_radians(),
        }
    }
}

/// Where point `p` (parent `pp`) goes this step before any contact: Verlet velocity,
/// damping, wind, the character's motion as inertia, gravity and the pull toward the
/// animated pose relative to the simulated parent. Moves `prev[p]` to `pos[p]`.
#[allow(clippy::too_many_arguments)]
#[inline]
fn advance(
    s: &ChainSettings,
    k: &ChainStep,
    input: &StepInput,
    p: usize,
    pp: usize,
    pos: &[Vec3],
    prev: &mut [Vec3],
    rng: &mut SplitMix64,
) -> Vec3 {
    let t = input.targets;
    // Verlet velocity from the previous position, damped.
    let mut velocity = if input.dt_old > 0.0 {
        (pos[p] - prev[p]) / input.dt_old
    } else {
        Vec3::ZERO
    };
    prev[p] = pos[p];
    velocity *= 1.0 - input.params.damping[p];
    if k.wind_on {
        let gust = rng.range_f32(1.0 - s.wind.gust, 1.0 + s.wind.gust);
        let dir = if k.wind_noise > 0.0 {
            noisy(input.wind_cs, k.wind_noise, rng)
        } else {
            input.wind_cs
        };
        velocity += dir * s.wind.speed * gust * s.target_framerate;
    }
    let forced = !input.push.is_empty();
    if forced {
        velocity += input.accel[p] * input.dt;
    }
    let mut x = pos[p] + velocity * k.moved;

    // Inertia: follow the character's translation and rotation only partly.
    x += input.move_cs * (1.0 - input.params.wd_location[p]);
    let before = match &input.base {
        Some((from, to)) => from.transform_point(to.inverse_transform_point(prev[p])),
        None => prev[p],
    };
    x += (input.rotate_cs * before - prev[p]) * (1.0 - input.params.wd_rotation[p]);
    x += k.gravity_step;
    if forced {
        x += input.push[p] * k.moved;
    }

    // Pull toward the animated pose, relative to the simulated parent.
    let base = pos[pp] + (t[p] - t[pp]);
    x += (base - x) * (pull(input.params.stiffness[p], k.exponent) * input.part);
    x
}

/// Point `p`'s contacts for one pass: the colliders near it and the world.
struct Contact<'a> {
    near: NearSet,
    list: &'a [usize],
    input: &'a StepInput<'a>,
    from: Vec3,
    r: f32,
}

impl<'a> Contact<'a> {
    /// Broad phase: every point the colliders see below starts as `x` now or as a point
    /// on the sphere of the bone's length about the parent (`restore`), and every step
    /// starts at `prev[p]`; a collider that cannot touch their box gives any such point
    /// back unchanged, so it is skipped while the point is still the one the pass began
    /// with (once a nearer collider moved it, every later collider is asked).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn of(
        list: &'a [usize],
        input: &'a StepInput<'a>,
        p: usize,
        parent: Vec3,
        length: f32,
        x: Vec3,
        from: Vec3,
    ) -> Self {
        let r = input.params.radius[p];
        let near = NearSet::of(
            list,
            input.bounds,
            from.min(x).min(parent - length),
            from.max(x).max(parent + length),
            r,
        );
        Self {
            near,
            list,
            input,
            from,
            r,
        }
    }

    /// [`Contact::of`] for point `p` where it is now (`pos[p]`), its parent `pp` at its
    /// current place: a group's collision and finishing passes.
    #[inline]
    fn at(
        list: &'a [usize],
        input: &'a StepInput<'a>,
        p: usize,
        pp: usize,
        pos: &[Vec3],
        prev: &[Vec3],
    ) -> Self {
        let t = input.targets;
        let length = (t[p] - t[pp]).length();
        Self::of(list, input, p, pos[pp], length, pos[p], prev[p])
    }

    #[inline]
    fn resolve(&self, x: Vec3) -> Vec3 {
        let mut x = self
            .near
            .resolve(self.list, self.input.colliders, x, Some(self.from), self.r);
        if let Some(world) = &self.input.world {
            x = world.resolve(x, self.from, self.r);
        }
        x
    }
}

/// Point `p`'s last word in a step: the cone limit, the planar constraint, the bone
/// length about its parent's final place, and collisions settled against that length.
#[allow(clippy::too_many_arguments)]
#[inline]
fn finish(
    s: &ChainSettings,
    input: &StepInput,
    p: usize,
    pp: usize,
    mut x: Vec3,
    pos: &[Vec3],
    contact: &Contact,
    collides: bool,
) -> Vec3 {
    let t = input.targets;
    // Cone limit around the animated direction.
    let anim_dir = t[p] - t[pp];
    let limit = input.params.limit_angle[p];
    if limit > 0.0 {
        x = cone_limit(x, pos[pp], anim_dir, limit);
    }
    if s.planar_constraint != PlanarAxis::None {
        let n = input.normals[p];
        x -= n * (x - pos[pp]).dot(n);
    }

    // Keep the bone length, then settle collisions against the length a few times;
    // collisions get the last word.
    let length = anim_dir.length();
    let fallback = normalize_or(anim_dir, Vec3::Y);
    let restore = |x: Vec3| pos[pp] + normalize_or(x - pos[pp], fallback) * length;
    x = restore(x);
    if collides {
        let mut settled = false;
        for _ in 0..3 {
            let y = contact.resolve(x);
            if y == x {
                settled = true;
                break;
            }
            x = restore(y);
        }
        if !settled {
            x = contact.resolve(x);
        }
    }
    x
}

/// Advances the points of chain `ci` by one step, point after point (KawaiiPhysics
/// 1.10's order: each point integrated, collided, limited and put back at its length
/// before the next).
pub(crate) fn step_chain(
    rig: &ChainRig,
    ci: usize,
    input: &StepInput,
    pos: &mut [Vec3],
    prev: &mut [Vec3],
    rng: &mut SplitMix64,
) {
    let chain = &rig.chains[ci];
    let s = &chain.settings;
    let k = ChainStep::of(s, input);
    let t = input.targets;
    let collides = !input.list.is_empty() || input.world.is_some();
    for p in chain.points.clone() {
        let parent = rig.parent[p];
        if parent == NONE {
            pos[p] = t[p];
            prev[p] = t[p];
            continue;
        }
        let pp = parent as usize;
        let x = if rig.carried[p] {
            // A point between bones that only collides: on its segment, its share of the
            // bone's length from the bone's final place toward where the bone's child
            // steps to. That child steps first, from its bone, as it would without the
            // points, and is put at the bone's length (a chain that touches nothing moves
            // as without them; a child stepped nearer than the points would fold the
            // segment back on itself).
            let (a, b) = (rig.real_parent[p] as usize, rig.inter_end[p] as usize);
            let anim = t[b] - t[a];
            let dir = |pos: &[Vec3]| normalize_or(pos[b] - pos[a], normalize_or(anim, Vec3::Y));
            if pp == a {
                let x = advance(s, &k, input, b, a, pos, prev, rng);
                pos[b] = x;
                pos[b] = pos[a] + dir(pos) * anim.length();
            }
            prev[p] = pos[p];
            pos[a] + dir(pos) * (rig.inter_alpha[p] * anim.length())
        } else if rig.carried[pp] {
            // Stepped with the first point of its segment, above.
            pos[p]
        } else {
            advance(s, &k, input, p, pp, pos, prev, rng)
        };
        let length = (t[p] - t[pp]).length();
        let contact = Contact::of(input.list, input, p, pos[pp], length, x, prev[p]);
        let x = contact.resolve(x);
        pos[p] = finish(s, input, p, pp, x, pos, &contact, collides);
    }
}

/// A group's chains and its constraints' range, borrowed: a bone-constraint group, or
/// one chain alone (no constraints) stepped in the same phase order.
#[derive(Clone)]
pub(crate) struct GroupRef<'g> {
    pub chains: &'g [usize],
    pub constraints: std::ops::Range<usize>,
    pub bridges: std::ops::Range<usize>,
}

impl<'g> From<&'g ChainGroup> for GroupRef<'g> {
    fn from(g: &'g ChainGroup) -> Self {
        GroupRef {
            chains: &g.chains,
            constraints: g.constraints.clone(),
            bridges: g.bridges.clone(),
        }
    }
}

/// Advances the chains of a bone-constraint group by one step in KawaiiPhysics 1.20's
/// phase order: every point integrated; `before` constraint passes; every point
/// collided; `after` passes; then every point limited and put back at its bone length
/// (and settled against the colliders, Tassel's last word as in [`step_chain`]).
/// `input_of(ci)` is chain `ci`'s step input; the constraints use the first chain's `dt`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn step_group<'a>(
    rig: &ChainRig,
    group: GroupRef,
    input_of: &dyn Fn(usize) -> StepInput<'a>,
    pos: &mut [Vec3],
    prev: &mut [Vec3],
    rngs: &mut [SplitMix64],
    lambda: &mut [f32],
    bridges: &mut Bridges,
) {
    for &ci in group.chains {
        let chain = &rig.chains[ci];
        let input = input_of(ci);
        let k = ChainStep::of(&chain.settings, &input);
        for p in chain.points.clone() {
            let parent = rig.parent[p];
            if parent == NONE {
                pos[p] = input.targets[p];
                prev[p] = input.targets[p];
                continue;
            }
            if rig.carried[p] {
                // Placed on its segment once both ends have stepped, below.
                continue;
            }
            // A bone after points that only collide pulls toward its bone, as without the
            // points; `kawaii` mode pulls toward the last point's place before this step,
            // as KawaiiPhysics 1.21 does (its `Simulate` reads the parent in the array,
            // which `SimulateOnce` has not placed yet).
            let from = if rig.carried[parent as usize] && chain.settings.mode != TimeMode::Kawaii {
                rig.real_parent[p]
            } else {
                parent
            };
            pos[p] = advance(
                &chain.settings,
                &k,
                &input,
                p,
                from as usize,
                pos,
                prev,
                &mut rngs[ci],
            );
        }
        // Points between bones that only collide: on their segment between its ends'
        // new places (1.21's `SimulateOnce` after every bone's `Simulate`).
        // (`fixed` and `classic`: at their share of the bone's length from the bone, as
        // the per-point step puts them.)
        if rig.subdivided {
            let kawaii = chain.settings.mode == TimeMode::Kawaii;
            let t = input.targets;
            for p in chain.points.clone() {
                if rig.carried[p] {
                    let (a, b) = (rig.real_parent[p] as usize, rig.inter_end[p] as usize);
                    let alpha = rig.inter_alpha[p];
                    prev[p] = pos[p];
                    pos[p] = if kawaii {
                        pos[a].lerp(pos[b], alpha)
                    } else {
                        let anim = t[b] - t[a];
                        let dir = normalize_or(pos[b] - pos[a], normalize_or(anim, Vec3::Y));
                        pos[a] + dir * (alpha * anim.length())
                    };
                }
            }
        }
    }
    // Bridge points: on their constraint, between its two points' new places.
    let on_bridges = &rig.constraints.bridges[group.bridges.clone()];
    for (i, br) in group.bridges.clone().zip(on_bridges) {
        bridges.prev[i] = bridges.pos[i];
        bridges.pos[i] = pos[br.a as usize].lerp(pos[br.b as usize], br.alpha);
    }
    let lead = input_of(group.chains[0]);
    let (dt, part) = (lead.dt, lead.part);
    let list = &rig.constraints.list[group.constraints.clone()];
    let lambda = &mut lambda[group.constraints.clone()];
    solve(list, lambda, pos, dt, rig.constraints.before, part);
    for &ci in group.chains {
        let chain = &rig.chains[ci];
        let input = input_of(ci);
        if input.list.is_empty() && input.world.is_none() {
            continue;
        }
        for p in chain.points.clone() {
            let parent = rig.parent[p];
            if parent == NONE {
                continue;
            }
            let pp = parent as usize;
            let contact = Contact::at(input.list, &input, p, pp, pos, prev);
            pos[p] = contact.resolve(pos[p]);
        }
    }
    if !on_bridges.is_empty() {
        collide_bridges(rig, group.clone(), input_of, pos, bridges, part);
    }
    solve(list, lambda, pos, dt, rig.constraints.after, part);
    for &ci in group.chains {
        let chain = &rig.chains[ci];
        let input = input_of(ci);
        let collides = !input.list.is_empty() || input.world.is_some();
        for p in chain.points.clone() {
            let parent = rig.parent[p];
            if parent == NONE {
                continue;
            }
            let pp = parent as usize;
            let contact = Contact::at(input.list, &input, p, pp, pos, prev);
            pos[p] = finish(
                &chain.settings,
                &input,
                p,
                pp,
                pos[p],
                pos,
                &contact,
                collides,
            );
        }
    }
}

/// The bridge points of a group's step (their places this step and last), and a
/// per-point scratch for the pushes they feed back.
pub(crate) struct Bridges<'b> {
    pub pos: &'b mut [Vec3],
    pub prev: &'b mut [Vec3],
    /// Per chain point: the pushes fed back to it (xyz) and their weights (w).
    pub feedback: &'b mut [glam::Vec4],
}

/// The bridge points of `group` against every rig collider and the world (the first of
/// the group's chains that collides with it), swept from their last place; then each
/// point's push (where it went from where it was put) fed back to the constraint's two
/// points by their nearness, `1 − alpha` and `alpha`, a point's sum divided by its
/// weight where that passes 1, times `feedback_scale` (KawaiiPhysics 1.21's bridge
/// feedback, between the collision pass and the after-collision constraint pass). `part`
/// scales the feedback in fixed mode's output step.
fn collide_bridges<'a>(
    rig: &ChainRig,
    group: GroupRef,
    input_of: &dyn Fn(usize) -> StepInput<'a>,
    pos: &mut [Vec3],
    bridges: &mut Bridges,
    part: f32,
) {
    let input = input_of(group.chains[0]);
    let world = group
        .chains
        .iter()
        .find_map(|&ci| input_of(ci).world.map(|w| (w, ci)));
    let all = input.every;
    let scale = rig.constraints.feedback_scale * part;
    let on_bridges = &rig.constraints.bridges[group.bridges.clone()];
    for (i, br) in group.bridges.clone().zip(on_bridges) {
        let (from, put) = (bridges.prev[i], bridges.pos[i]);
        // A timed override's radius scale (its first point's chain's).
        let r = br.radius * input.params.radius_scale[rig.chain_of[br.a as usize] as usize];
        let near = NearSet::of(all, input.bounds, from.min(put), from.max(put), r);
        let mut x = near.resolve(all, input.colliders, put, Some(from), r);
        if let Some((w, _)) = &world {
            x = w.resolve(x, from, r);
        }
        bridges.pos[i] = x;
        let push = x - put;
        // UE's `IsNearlyZero` (1e-4 cm a component), in metres.
        if scale > 0.0 && push.abs().max_element() > 1e-6 {
            let (a, b) = (br.a as usize, br.b as usize);
            bridges.feedback[a] += (push * (1.0 - br.alpha)).extend(1.0 - br.alpha);
            bridges.feedback[b] += (push * br.alpha).extend(br.alpha);
        }
    }
    if scale > 0.0 {
        for br in on_bridges {
            for e in [br.a as usize, br.b as usize] {
                let f = bridges.feedback[e];
                if f.w > 0.0 {
                    pos[e] += f.truncate() / f.w.max(1.0) * scale;
                    bridges.feedback[e] = glam::Vec4::ZERO;
                }
            }
        }
    }
}

/// A unit direction drawn uniformly from the cone of half-angle `angle` radians about
/// unit `dir` (KawaiiPhysics' `FMath::VRandCone`).
pub(crate) fn noisy(dir: Vec3, angle: f32, rng: &mut SplitMix64) -> Vec3 {
    let cos_t = 1.0 - rng.range_f32(0.0, 1.0) * (1.0 - angle.cos());
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = rng.range_f32(0.0, std::f32::consts::TAU);
    let (u, v) = dir.any_orthonormal_pair();
    dir * cos_t + (u * phi.cos() + v * phi.sin()) * sin_t
}

/// Gravity's share of one step of `dt` for the chain's time mode (fixed: an acceleration;
/// classic: the chain's rule).
pub(crate) fn gravity_step(s: &ChainSettings, g: Vec3, dt: f32, fixed: bool) -> Vec3 {
    match (fixed, s.classic_gravity) {
        (true, _) | (false, ClassicGravity::DtSquared) => g * dt * dt,
        (false, ClassicGravity::PerFrame) => g * dt,
        (false, ClassicGravity::HalfDtSquared) => g * (0.5 * dt * dt),
    }
}

/// The share of the way to the animated pose a point with stiffness `k` moves in a step
/// of `exponent` target frames.
#[inline]
pub(crate) fn pull(k: f32, exponent: f32) -> f32 {
    if k >= 1.0 {
        1.0
    } else if exponent == 1.0 {
        // Fixed steps at the target rate: x^1 is x (powf gives exactly that, slowly).
        1.0 - (1.0 - k)
    } else {
        1.0 - (1.0 - k).powf(exponent)
    }
}

/// `x` kept within `limit` radians of the animated direction `anim_dir` about `parent`.
pub(crate) fn cone_limit(x: Vec3, parent: Vec3, anim_dir: Vec3, limit: f32) -> Vec3 {
    let d = x - parent;
    let angle = d.angle_between(anim_dir);
    if angle.is_finite() && angle > limit {
        let axis = normalize_or(anim_dir.cross(d), anim_dir.any_orthonormal_vector());
        let dir = Quat::from_axis_angle(axis, limit) * normalize_or(anim_dir, Vec3::Y);
        parent + dir * d.length()
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Directions from `noisy` stay within the cone, spread over it (uniform on the cap:
    /// the mean cosine is halfway between 1 and cos α), and are unit.
    #[test]
    fn noisy_wind_stays_in_its_cone_and_fills_it() {
        let mut rng = SplitMix64::new(3);
        let axis = Vec3::new(1.0, 2.0, -0.5).normalize();
        for degrees in [5.0f32, 30.0, 90.0, 180.0] {
            let angle = degrees.to_radians();
            let (mut widest, mut sum_cos) = (0.0f32, 0.0f64);
            let n = 20_000;
            for _ in 0..n {
                let d = noisy(axis, angle, &mut rng);
                assert!((d.length() - 1.0).abs() < 1e-5);
                let a = d.dot(axis).clamp(-1.0, 1.0).acos();
                assert!(a <= angle + 1e-3, "{degrees}°: {}°", a.to_degrees());
                widest = widest.max(a);
                sum_cos += d.dot(axis) as f64;
            }
            assert!(
                widest > 0.97 * angle,
                "{degrees}°: widest {}°",
                widest.to_degrees()
            );
            let want = 0.5 * (1.0 + angle.cos() as f64);
            let mean = sum_cos / n as f64;
            assert!(
                (mean - want).abs() < 0.01,
                "{degrees}°: mean cos {mean}, uniform {want}"
            );
        }
    }
}
