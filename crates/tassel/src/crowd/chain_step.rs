//! The chain crowd's lane arithmetic: one solver step of one chain and the chain's output
//! pass, for [`LANES`] characters side by side. Each is
//! [`crate::dynamics::chain::step`]'s and the chain job's output pass, operation for
//! operation ([`super::lanes`] repeats glam's IEEE operations lane by lane), with every
//! branch that depends on a character's state taken per lane (a mask) and the narrow
//! phase left to the scalar colliders, asked for the lanes whose point may touch one.

use super::lanes::{differs, F, LANES, M, Q, V3};
use crate::collide::PlacedCollider;
use crate::dynamics::chain::compile::{ChainRig, NONE};
use crate::dynamics::chain::step::{cone_limit, pull};
use crate::dynamics::chain::PlanarAxis;
use crate::rng::SplitMix64;
use glam::Vec3;

/// A collider's broad-phase sphere per lane ([`PlacedCollider::bound_sphere`]): centre and
/// radius with the collider's part of the margin.
#[derive(Debug, Clone, Copy)]
pub(super) struct Bound {
    pub c: V3,
    pub w: F,
}

impl Bound {
    pub(super) const ZERO: Bound = Bound {
        c: V3 {
            x: F([0.0; LANES]),
            y: F([0.0; LANES]),
            z: F([0.0; LANES]),
        },
        w: F([0.0; LANES]),
    };
}

/// Everything one lane step reads besides the rig and the points (as
/// `chain::step::StepInput`, per lane).
pub(super) struct LaneStep<'a> {
    /// Animated targets per point at the end of the step.
    pub targets: &'a [V3],
    /// Planar normals per point.
    pub normals: &'a [V3],
    /// The colliders placed at the end of the step, lane after lane (`m` per lane).
    pub colliders: &'a [PlacedCollider],
    /// Their broad-phase spheres per collider.
    pub bounds: &'a [Bound],
    /// Each collider's bounding radius (`None`: it acts everywhere).
    pub reach: &'a [Option<f32>],
    pub move_cs: V3,
    pub rotate_cs: Q,
    /// Gravity's share of the step (the time mode's formula, per lane).
    pub gravity_step: V3,
    pub wind_cs: V3,
    /// Lanes with wind this step (speed > 0 and a direction).
    pub wind_on: M,
    pub dt: f32,
    pub dt_old: F,
    /// The lanes that take this step; the others are left as they are.
    pub active: M,
}

/// `pick(a, b) ? a : b` per component and lane.
#[inline(always)]
fn pick(a: V3, b: V3, take_a: impl Fn(f32, f32) -> bool) -> V3 {
    let f = |a: F, b: F| {
        F(std::array::from_fn(|i| {
            if take_a(a.0[i], b.0[i]) {
                a.0[i]
            } else {
                b.0[i]
            }
        }))
    };
    V3 {
        x: f(a.x, b.x),
        y: f(a.y, b.y),
        z: f(a.z, b.z),
    }
}

/// glam's `Vec3::min` per lane (`a < b ? a : b`, glam's NaN rule).
#[inline(always)]
fn vmin(a: V3, b: V3) -> V3 {
    pick(a, b, |a, b| a < b)
}

/// glam's `Vec3::max` per lane (`a > b ? a : b`).
#[inline(always)]
fn vmax(a: V3, b: V3) -> V3 {
    pick(a, b, |a, b| a > b)
}

/// [`crate::collide::NearSet::of`] per lane: bit `i` of lane `l` set when the list's member `i` may touch
/// the lane's box `lo`–`hi` for a point of radius `r`.
#[inline(always)]
fn near_sets(list: &[usize], bounds: &[Bound], lo: V3, hi: V3, r: f32) -> [u64; LANES] {
    let finite = lo.finite().and(hi.finite());
    // glam's `max_element` of `lo.abs().max(hi.abs())`: max(x, max(y, z)).
    let size = vmax(lo.abs(), hi.abs());
    let yz = vmax(V3::splat_f(size.y), V3::splat_f(size.z)).x;
    let largest = vmax(V3::splat_f(size.x), V3::splat_f(yz)).x;
    let extra = F::splat(r) + F::splat(1e-5) * (largest + F::splat(r));
    let mut bits = [0u64; LANES];
    let zero = V3::splat(Vec3::ZERO);
    for (i, &k) in list.iter().take(64).enumerate() {
        let b = bounds[k];
        let d = vmax(vmax(lo - b.c, b.c - hi), zero);
        let reach = b.w + extra;
        let near = d.dot(d).le(reach * reach);
        for (l, bits) in bits.iter_mut().enumerate() {
            *bits |= u64::from(near.0[l] & 1) << i;
        }
    }
    if !r.is_finite() {
        return [u64::MAX; LANES];
    }
    for (l, bits) in bits.iter_mut().enumerate() {
        if finite.0[l] == 0 {
            *bits = u64::MAX;
        }
    }
    bits
}

/// [`NearSet::resolve`] for the `open` lanes: the members of the list in order, each asked
/// for the lanes whose set holds it or whose point a member before it moved; and of
/// those, only the lanes that [`PlacedCollider::resolve`]'s own quick rejection (both
/// ends of the step beyond the shape's bounding sphere, the step too short to reach it)
/// does not turn away, computed here for all lanes at once with its operations.
/// `reach` holds each collider's bounding radius (`None`: acts everywhere).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn collide(
    list: &[usize],
    colliders: &[PlacedCollider],
    bounds: &[Bound],
    reach: &[Option<f32>],
    sets: &[u64; LANES],
    x: V3,
    prev: Option<V3>,
    r: f32,
    open: M,
) -> V3 {
    let m = colliders.len() / LANES;
    let mut y = x;
    for (i, &c) in list.iter().enumerate() {
        let near = if i >= 64 {
            M::ALL
        } else {
            M(std::array::from_fn(|l| {
                0u32.wrapping_sub(((sets[l] >> i) & 1) as u32)
            }))
        };
        let mut ask = open.and(near.or(differs(y, x)));
        if !ask.any() {
            continue;
        }
        let q = prev.unwrap_or(y);
        if let Some(bound) = reach[c] {
            let reach = F::splat(bound + r);
            let reach2 = reach * reach;
            let dp = y - bounds[c].c;
            let dq = q - bounds[c].c;
            let step = y - q;
            let gap = dp.length() - reach;
            let rejected = dp
                .dot(dp)
                .gt(reach2)
                .and(dq.dot(dq).gt(reach2))
                .and(step.dot(step).lt(gap * gap));
            ask = ask.and(rejected.not());
        }
        for l in 0..LANES {
            if ask.0[l] != 0 {
                let p = colliders[l * m + c].resolve(y.get(l), q.get(l), r);
                y.set(l, p);
            }
        }
    }
    y
}

/// Advances the points of chain `ci` by one step in the `input.active` lanes.
/// `rng` holds the chain's wind generator per lane.
#[inline(always)]
pub(super) fn step_lanes(
    rig: &ChainRig,
    ci: usize,
    input: &LaneStep,
    pos: &mut [V3],
    prev: &mut [V3],
    rng: &mut [SplitMix64; LANES],
) {
    let chain = &rig.chains[ci];
    let s = &chain.settings;
    let exponent = s.target_framerate * input.dt;
    let active = input.active;
    let dt = F::splat(input.dt);
    let t = input.targets;
    let list = &chain.colliders;
    let has_velocity = input.dt_old.gt(F::splat(0.0));
    let wind_lanes = input.wind_on.and(active);
    let wind = input.wind_cs * F::splat(s.wind.speed);
    for p in chain.points.clone() {
        let parent = rig.parent[p];
        if parent == NONE {
            pos[p] = V3::select(active, t[p], pos[p]);
            prev[p] = V3::select(active, t[p], prev[p]);
            continue;
        }
        let pp = parent as usize;

        let mut velocity = V3::select(
            has_velocity,
            (pos[p] - prev[p]) / input.dt_old,
            V3::splat(Vec3::ZERO),
        );
        let start = pos[p];
        velocity = velocity * F::splat(1.0 - rig.damping[p]);
        if wind_lanes.any() {
            let mut gust = [0.0f32; LANES];
            for (l, g) in gust.iter_mut().enumerate() {
                if wind_lanes.0[l] != 0 {
                    *g = rng[l].range_f32(1.0 - s.wind.gust, 1.0 + s.wind.gust);
                }
            }
            let blown = velocity + wind * F(gust) * F::splat(s.target_framerate);
            velocity = V3::select(wind_lanes, blown, velocity);
        }
        let mut x = start + velocity * dt;

        x = x + input.move_cs * F::splat(1.0 - rig.wd_location[p]);
        x = x + (input.rotate_cs.mul_vec3(start) - start) * F::splat(1.0 - rig.wd_rotation[p]);
        x = x + input.gravity_step;

        let base = pos[pp] + (t[p] - t[pp]);
        x = x + (base - x) * F::splat(pull(rig.stiffness[p], exponent));

        let r = rig.radius[p];
        let anim_dir = t[p] - t[pp];
        let length = anim_dir.length();
        let parent_pos = pos[pp];
        let sets = near_sets(
            list,
            input.bounds,
            vmin(vmin(start, x), parent_pos - V3::splat_f(length)),
            vmax(vmax(start, x), parent_pos + V3::splat_f(length)),
            r,
        );
        let cols = input.colliders;
        x = collide(
            list,
            cols,
            input.bounds,
            input.reach,
            &sets,
            x,
            Some(start),
            r,
            active,
        );

        let limit = rig.limit_angle[p];
        if limit > 0.0 {
            for l in 0..LANES {
                if active.0[l] == 0 {
                    continue;
                }
                let limited = cone_limit(x.get(l), parent_pos.get(l), anim_dir.get(l), limit);
                x.set(l, limited);
            }
        }
        if s.planar_constraint != PlanarAxis::None {
            let n = input.normals[p];
            x = x - n * (x - parent_pos).dot(n);
        }

        let fallback = anim_dir.normalize_or(V3::splat(Vec3::Y));
        let restore = |x: V3| parent_pos + (x - parent_pos).normalize_or(fallback) * length;
        x = restore(x);
        if !list.is_empty() {
            let mut open = active;
            for _ in 0..3 {
                let y = collide(
                    list,
                    cols,
                    input.bounds,
                    input.reach,
                    &sets,
                    x,
                    Some(start),
                    r,
                    open,
                );
                open = open.and(differs(y, x));
                x = V3::select(open, restore(y), x);
                if !open.any() {
                    break;
                }
            }
            if open.any() {
                x = collide(
                    list,
                    cols,
                    input.bounds,
                    input.reach,
                    &sets,
                    x,
                    Some(start),
                    r,
                    open,
                );
            }
        }
        pos[p] = V3::select(active, x, pos[p]);
        prev[p] = V3::select(active, start, prev[p]);
    }
}

/// The output pass of chain `ci` (as the chain job's): the animated pose plus the
/// deviation interpolated by `w` and scaled by the chain's alpha, bone lengths restored
/// from the root down, kept out of the colliders; for the `live` lanes (the others get
/// the arithmetic, not the narrow phase).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn output_lanes(
    rig: &ChainRig,
    ci: usize,
    w: F,
    targets: &[V3],
    dev_before: &[V3],
    dev: &[V3],
    colliders: &[PlacedCollider],
    bounds: &[Bound],
    reach: &[Option<f32>],
    out: &mut [V3],
    live: M,
) {
    let chain = &rig.chains[ci];
    let alpha = F::splat(chain.settings.alpha);
    let list = &chain.colliders;
    let y_axis = V3::splat(Vec3::Y);
    for p in chain.points.clone() {
        let t = targets[p];
        let d = dev_before[p].lerp(dev[p], w) * alpha;
        let parent = rig.parent[p];
        if parent == NONE {
            out[p] = t;
            continue;
        }
        let pp = parent as usize;
        let anim = t - targets[pp];
        let from = out[pp];
        let length = anim.length();
        let fallback = anim.normalize_or(y_axis);
        let restore = |x: V3| from + (x - from).normalize_or(fallback) * length;
        let mut x = restore(t + d);
        let r = rig.radius[p];
        let sets = near_sets(
            list,
            bounds,
            from - V3::splat_f(length),
            from + V3::splat_f(length),
            r,
        );
        let mut open = live;
        for pass in 0..3 {
            let y = collide(list, colliders, bounds, reach, &sets, x, None, r, open);
            open = open.and(differs(y, x));
            x = V3::select(open, if pass < 2 { restore(y) } else { y }, x);
            if !open.any() {
                break;
            }
        }
        out[p] = x;
    }
}
