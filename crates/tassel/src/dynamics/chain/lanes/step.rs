//! One solver step of one chain and the chain's output pass, for [`LANES`] lanes side by
//! side (characters of a crowd, or twin chains of one character). Each is
//! [`crate::dynamics::chain::step`]'s and the chain job's output pass, operation for
//! operation ([`crate::lanes`] repeats glam's IEEE operations lane by lane), with every
//! branch that depends on a lane's state taken per lane (a mask). The cone limit, the
//! broad phase, the colliders' quick rejection and, for keep-out spheres and capsules,
//! the narrow phase's contact decision, its push of a point found inside
//! ([`crate::collide::lanes`]) and the swept entry of a step that entered one
//! ([`crate::collide::entry_lanes`]) run in lanes; a capsule graze whose closed-form entry
//! finds no root and every other shape are left to the scalar colliders, asked only for
//! the lanes that need them.

use crate::collide::entry_lanes::{capsule_entry_out_of_line, sphere_entry};
use crate::collide::lanes::{
    capsule_contact, capsule_contact_still, sphere_contact, sphere_contact_still, Bound,
};
use crate::collide::{PlacedCollider, Shape};
use crate::dynamics::chain::compile::{ChainRig, NONE};
use crate::dynamics::chain::step::pull;
use crate::dynamics::chain::PlanarAxis;
use crate::lanes::{
    angle_between, differs, turned_toward, vmax, vmin, Isa, Lane, Mask, F, LANES, M, Q, V3,
};
use crate::rng::SplitMix64;
use glam::Vec3;

/// What the lanes know of a rig collider's shape (the same for every character).
#[derive(Debug, Clone, Copy)]
pub(crate) struct LaneShape {
    /// Its bounding radius ([`PlacedCollider::bounding_radius`]; `None`: it acts
    /// everywhere).
    pub reach: Option<f32>,
    /// Who decides whether a point touches it.
    pub decision: Decision,
}

/// Where a collider's contact decision is made.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Decision {
    /// A keep-out sphere of this radius: in lanes ([`sphere_contact`]).
    Sphere(f32),
    /// A capsule of this radius: in lanes ([`capsule_contact`]).
    Capsule(f32),
    /// Any other shape: the scalar narrow phase, for every lane asked.
    Scalar,
}

impl LaneShape {
    pub(crate) fn of(shape: Shape) -> LaneShape {
        let reach = PlacedCollider {
            shape,
            transform: crate::math::Transform::IDENTITY,
        }
        .bounding_radius();
        let decision = match shape {
            Shape::Sphere {
                radius,
                inside: false,
            } => Decision::Sphere(radius),
            Shape::Capsule { radius, .. } => Decision::Capsule(radius),
            _ => Decision::Scalar,
        };
        LaneShape { reach, decision }
    }
}

/// Everything one lane step reads besides the rig and the points (as
/// `chain::step::StepInput`, per lane).
pub(crate) struct LaneStep<'a> {
    /// Animated targets per point at the end of the step.
    pub targets: &'a [V3],
    /// Planar normals per point.
    pub normals: &'a [V3],
    /// The colliders placed at the end of the step, lane after lane: lane `l`'s from
    /// `l * stride` (`stride` is `m`, or 0 where every lane has the same).
    pub colliders: &'a [PlacedCollider],
    /// See `colliders`.
    pub stride: usize,
    /// Their broad-phase spheres per collider.
    pub bounds: &'a [Bound],
    /// Each rig collider's shape as the lanes see it.
    pub shapes: &'a [LaneShape],
    pub move_cs: V3,
    pub rotate_cs: Q,
    /// Gravity's share of the step (the time mode's formula, per lane).
    pub gravity_step: V3,
    pub wind_cs: V3,
    /// Lanes with wind this step (speed > 0 and a direction).
    pub wind_on: M,
    pub dt: f32,
    pub dt_old: F,
    /// The part of the step each lane takes (the scalar step's `StepInput::part`): 1 but
    /// in fixed mode's output step; `None`: 1 in every lane.
    pub part: Option<F>,
    /// The lanes that take this step; the others are left as they are.
    pub active: M,
    /// The next lane group's state, asked into the caches point by point as this one
    /// steps ([`Ahead`]).
    pub ahead: Ahead<'a>,
}

/// The next lane group's per-point state (its `pos`, `prev`, `dev`, `dev_before`, `out`
/// and `prev_targets`): while a group steps point `p`, point `p` of each is asked into
/// the second-level cache ([`crate::lanes::prefetch`]), so that the next group finds its
/// state there rather than in memory, a group's time ahead and spread evenly over the
/// step (a crowd larger than the caches otherwise waits for it). Empty slices: no next
/// group. A hint only: no effect on any value.
pub(crate) type Ahead<'a> = [&'a [V3]; 6];

/// No next group ([`Ahead`]).
pub(crate) const NO_AHEAD: Ahead<'static> = [&[]; 6];

/// `x` moved onto the sphere of radius `length` about `from`, along `from`→`x` (or
/// `fallback` when that has no direction): a bone's length restored. A function, not a
/// closure, so that it is always inlined into the caller's (AVX2) code.
#[inline(always)]
fn restore_length<T: Lane>(x: V3<T>, from: V3<T>, fallback: V3<T>, length: T) -> V3<T> {
    from + (x - from).normalize_or(fallback) * length
}

/// [`crate::collide::NearSet::of`] per lane, into `near`: member `i` of the list may touch
/// the lane's box `lo`–`hi` for a point of radius `r` in the lanes of `near[i]` (a mask
/// per member rather than a bit set per lane, so that the narrow phase reads it as is).
#[inline(always)]
fn near_sets<T: Lane>(
    list: &[usize],
    bounds: &[Bound],
    lo: V3<T>,
    hi: V3<T>,
    r: f32,
    near: &mut [M],
) {
    // A non-finite box or radius may touch everything, as may members from 64 on.
    let everywhere = if r.is_finite() {
        lo.finite().and(hi.finite()).not()
    } else {
        <T::M as Mask>::ALL
    };
    // glam's `max_element` of `lo.abs().max(hi.abs())`: max(x, max(y, z)).
    let size = vmax(lo.abs(), hi.abs());
    let yz = vmax(V3::splat_f(size.y), V3::splat_f(size.z)).x;
    let largest = vmax(V3::splat_f(size.x), V3::splat_f(yz)).x;
    let extra = T::splat(r) + T::splat(1e-5) * (largest + T::splat(r));
    let zero = V3::splat(Vec3::ZERO);
    for (i, (&k, out)) in list.iter().zip(near.iter_mut()).enumerate() {
        if i >= 64 {
            *out = M::ALL;
            continue;
        }
        let b = &bounds[k];
        let c = V3::of(b.c);
        let d = vmax(vmax(lo - c, c - hi), zero);
        let reach = T::of(b.w) + extra;
        *out = d.dot(d).le(reach * reach).or(everywhere).m();
    }
}

/// [`crate::collide::NearSet::resolve`] for the `open` lanes: the members of the list in
/// order, each asked for the lanes whose set holds it or whose point a member before it
/// moved; and of those, only the lanes that [`PlacedCollider::resolve`]'s own quick
/// rejection (both ends of the step beyond the shape's bounding sphere, the step too
/// short to reach it) and, for keep-out spheres and capsules, the narrow phase's own
/// contact decision do not turn away, computed here for all lanes at once with their
/// operations.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn collide<T: Lane>(
    list: &[usize],
    colliders: &[PlacedCollider],
    stride: usize,
    bounds: &[Bound],
    shapes: &[LaneShape],
    near: &[M],
    x: V3<T>,
    prev: Option<V3<T>>,
    r: f32,
    open: T::M,
) -> (V3<T>, T::M) {
    let mut y = x;
    // `differs(y, x)`, kept up to date lane by lane where a member moves `y` (the only
    // place it changes) rather than compared afresh for every member.
    let mut moved = <T::M as Mask>::NONE;
    for (i, &c) in list.iter().enumerate() {
        let mut ask = open.and(<T::M as Mask>::of(near[i]).or(moved));
        if !ask.any() {
            continue;
        }
        let q = prev.unwrap_or(y);
        let shape = shapes[c];
        let bound = &bounds[c];
        let bc = V3::of(bound.c);
        if let Some(reach) = shape.reach {
            let reach = T::splat(reach + r);
            let reach2 = reach * reach;
            let dp = y - bc;
            let dq = q - bc;
            let step = y - q;
            let gap = dp.length() - reach;
            let rejected = dp
                .dot(dp)
                .gt(reach2)
                .and(dq.dot(dq).gt(reach2))
                .and(step.dot(step).lt(gap * gap));
            ask = ask.and(rejected.not());
            if !ask.any() {
                continue;
            }
        }
        // Keep-out spheres and capsules: the lanes asked get their point from the lanes'
        // own narrow phase (a push, or the swept entry); other shapes, and a capsule
        // graze the lanes cannot answer, from the scalar one.
        let (a, b) = (V3::of(bound.a), V3::of(bound.b));
        // (Without a step, `q` is `y`: the contacts for a point that did not step.)
        let contact = match shape.decision {
            Decision::Sphere(radius) => {
                let limit = T::splat(radius + r);
                let contact = match prev {
                    Some(_) => sphere_contact(y, q, bc, limit),
                    None => sphere_contact_still(y, bc, limit),
                };
                Some((contact, limit, false))
            }
            Decision::Capsule(radius) => {
                let limit = T::splat(radius + r);
                let contact = match prev {
                    Some(_) => capsule_contact(y, q, a, b, limit),
                    None => capsule_contact_still(y, a, b, limit),
                };
                Some((contact, limit, true))
            }
            Decision::Scalar => None,
        };
        if let Some((contact, limit, capsule)) = contact {
            ask = ask.and(contact.may);
            let pushed = ask.and(contact.entered.not());
            if pushed.any() {
                y = V3::select(pushed, contact.pushed(), y);
                moved = pushed.and(differs(y, x)).or(pushed.not().and(moved));
            }
            ask = ask.and(contact.entered);
            if !ask.any() {
                continue;
            }
            // The entries: in lanes too, but for a capsule's graze whose closed form
            // found no root (the scalar narrow phase bisects there).
            let (entry, hard) = match capsule {
                // A sphere's entry is a few `f32` operations: in line.
                false => (
                    sphere_entry(y, q, bc, limit, &contact),
                    <T::M as Mask>::NONE,
                ),
                // Without AVX-512, one lane alone goes to the scalar narrow phase (the
                // same bits): the closed form in `f64` costs as much for one lane as for
                // all sixteen, in four 256-bit registers a value (`tassel bench --simd
                // avx2` 7 % faster; with AVX-512 2 % slower, so not there).
                true if T::ISA != Isa::Avx512 && !ask.several() => (y, ask),
                true => capsule_entry_out_of_line(y, q, a, b, limit, &contact, ask),
            };
            let slid = ask.and(hard.not());
            y = V3::select(slid, entry, y);
            moved = slid.and(differs(y, x)).or(slid.not().and(moved));
            ask = ask.and(hard);
            if !ask.any() {
                continue;
            }
        }
        // The scalar narrow phase, lane by lane (in `F`, whose lanes are plain memory).
        let (ask, mut yf, qf, xf) = (ask.m(), y.f(), q.f(), x.f());
        let mut mv = moved.m();
        for l in 0..LANES {
            if ask.0[l] != 0 {
                let p = colliders[l * stride + c].resolve(yf.get(l), qf.get(l), r);
                yf.set(l, p);
                mv.0[l] = if p != xf.get(l) { !0 } else { 0 };
            }
        }
        y = V3::of(yf);
        moved = <T::M as Mask>::of(mv);
    }
    (y, moved)
}

/// Advances the points of chain `ci` by one step in the `input.active` lanes, computed in
/// the lane type `T` (the points and the input stay in [`F`]).
/// `rng` holds the chain's wind generator per lane.
#[inline(always)]
pub(crate) fn step_lanes<T: Lane>(
    rig: &ChainRig,
    ci: usize,
    input: &LaneStep,
    pos: &mut [V3],
    prev: &mut [V3],
    rng: &mut [SplitMix64; LANES],
    near: &mut [M],
) {
    let chain = &rig.chains[ci];
    let s = &chain.settings;
    let exponent = s.target_framerate * input.dt;
    let active = <T::M as Mask>::of(input.active);
    // The time a lane's points move this step: `dt` times its part.
    let (dt, part) = match input.part {
        None => (T::splat(input.dt), None),
        Some(a) => (T::of(F(a.0.map(|a| input.dt * a))), Some(T::of(a))),
    };
    let list = &chain.colliders;
    let dt_old = T::of(input.dt_old);
    let has_velocity = dt_old.gt(T::splat(0.0));
    let wind_lanes = input.wind_on.and(input.active);
    let wind = V3::<T>::of(input.wind_cs) * T::splat(s.wind.speed);
    let move_cs = V3::<T>::of(input.move_cs);
    let rotate_cs = Q::<T>::of(input.rotate_cs);
    let gravity_step = V3::<T>::of(input.gravity_step);
    for p in chain.points.clone() {
        for field in input.ahead {
            crate::lanes::prefetch(field.get(p..p + 1).unwrap_or_default());
        }
        let parent = rig.parent[p];
        let (pos_p, prev_p) = (V3::<T>::of(pos[p]), V3::<T>::of(prev[p]));
        if parent == NONE {
            let t = V3::<T>::of(input.targets[p]);
            pos[p] = V3::select(active, t, pos_p).f();
            prev[p] = V3::select(active, t, prev_p).f();
            continue;
        }
        let pp = parent as usize;

        let mut velocity = V3::select(
            has_velocity,
            (pos_p - prev_p) / dt_old,
            V3::splat(Vec3::ZERO),
        );
        let start = pos_p;
        velocity = velocity * T::splat(1.0 - rig.damping[p]);
        if wind_lanes.any() {
            let mut gust = [0.0f32; LANES];
            for (l, g) in gust.iter_mut().enumerate() {
                if wind_lanes.0[l] != 0 {
                    *g = rng[l].range_f32(1.0 - s.wind.gust, 1.0 + s.wind.gust);
                }
            }
            let blown = velocity + wind * T::of(F(gust)) * T::splat(s.target_framerate);
            velocity = V3::select(<T::M as Mask>::of(wind_lanes), blown, velocity);
        }
        let mut x = start + velocity * dt;

        x = x + move_cs * T::splat(1.0 - rig.wd_location[p]);
        x = x + (rotate_cs.mul_vec3(start) - start) * T::splat(1.0 - rig.wd_rotation[p]);
        x = x + gravity_step;

        let parent_pos = V3::<T>::of(pos[pp]);
        let (tp, tpp) = (V3::<T>::of(input.targets[p]), V3::of(input.targets[pp]));
        let base = parent_pos + (tp - tpp);
        let mut pulled = T::splat(pull(rig.stiffness[p], exponent));
        if let Some(a) = part {
            pulled = pulled * a;
        }
        x = x + (base - x) * pulled;

        let r = rig.radius[p];
        let anim_dir = tp - tpp;
        let length = anim_dir.length();
        near_sets(
            list,
            input.bounds,
            vmin(vmin(start, x), parent_pos - V3::splat_f(length)),
            vmax(vmax(start, x), parent_pos + V3::splat_f(length)),
            r,
            near,
        );
        let near = &*near;
        let fallback = anim_dir.normalize_or(V3::splat(Vec3::Y));
        // The step's collisions: the first pass, then (after the cone, the plane and the
        // length) up to three passes that each restore the length of what they moved and a
        // last one that does not. One call site, so that the narrow phase is inlined once.
        let mut open = active;
        for pass in 0..5 {
            let (y, moved) = collide(
                list,
                input.colliders,
                input.stride,
                input.bounds,
                input.shapes,
                near,
                x,
                Some(start),
                r,
                open,
            );
            if pass == 0 {
                x = y;
                let limit = rig.limit_angle[p];
                if limit > 0.0 {
                    // `cone_limit` in lanes: the angle, and where it is past the limit (a
                    // NaN angle is not) the point turned back onto the cone, by the scalar
                    // function's operations.
                    let d = x - parent_pos;
                    let over = angle_between(d, anim_dir).gt(T::splat(limit)).and(active);
                    if over.any() {
                        let dir = turned_toward(anim_dir, d, fallback, limit);
                        x = V3::select(over, parent_pos + dir * d.length(), x);
                    }
                }
                if s.planar_constraint != PlanarAxis::None {
                    let n = V3::<T>::of(input.normals[p]);
                    x = x - n * (x - parent_pos).dot(n);
                }
                x = restore_length(x, parent_pos, fallback, length);
                if list.is_empty() {
                    break;
                }
            } else if pass < 4 {
                open = open.and(moved);
                x = V3::select(open, restore_length(y, parent_pos, fallback, length), x);
                if !open.any() {
                    break;
                }
            } else {
                x = y;
            }
        }
        pos[p] = V3::select(active, x, pos_p).f();
        prev[p] = V3::select(active, start, prev_p).f();
    }
}

/// The output pass of chain `ci` (as the chain job's): the animated pose plus the
/// deviation interpolated by `w` and scaled by the chain's alpha, bone lengths restored
/// from the root down, kept out of the colliders; for the `live` lanes (the others keep
/// their `out`, and get the arithmetic, not the narrow phase).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn output_lanes<T: Lane>(
    rig: &ChainRig,
    ci: usize,
    w: F,
    targets: &[V3],
    dev_before: &[V3],
    dev: &[V3],
    colliders: &[PlacedCollider],
    stride: usize,
    bounds: &[Bound],
    shapes: &[LaneShape],
    out: &mut [V3],
    live: M,
    near: &mut [M],
) {
    let chain = &rig.chains[ci];
    let alpha = T::splat(chain.settings.alpha);
    let list = &chain.colliders;
    let y_axis = V3::splat(Vec3::Y);
    let w = T::of(w);
    let live_t = <T::M as Mask>::of(live);
    for p in chain.points.clone() {
        let t = V3::<T>::of(targets[p]);
        let d = V3::<T>::of(dev_before[p]).lerp(V3::of(dev[p]), w) * alpha;
        let parent = rig.parent[p];
        if parent == NONE {
            out[p] = V3::select(live_t, t, V3::of(out[p])).f();
            continue;
        }
        let pp = parent as usize;
        let anim = t - V3::of(targets[pp]);
        let from = V3::<T>::of(out[pp]);
        let length = anim.length();
        let fallback = anim.normalize_or(y_axis);
        let mut x = restore_length(t + d, from, fallback, length);
        let r = rig.radius[p];
        near_sets(
            list,
            bounds,
            from - V3::splat_f(length),
            from + V3::splat_f(length),
            r,
            near,
        );
        let near = &*near;
        let mut open = live_t;
        for pass in 0..3 {
            let (y, moved) = collide(
                list, colliders, stride, bounds, shapes, near, x, None, r, open,
            );
            open = open.and(moved);
            x = V3::select(
                open,
                if pass < 2 {
                    restore_length(y, from, fallback, length)
                } else {
                    y
                },
                x,
            );
            if !open.any() {
                break;
            }
        }
        out[p] = V3::select(live_t, x, V3::of(out[p])).f();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Transform;
    use glam::Quat;

    /// [`collide`] with a point's near sets ([`near_sets`] of the step's box) gives the
    /// bits of asking every member of the list for every open lane: a member outside a
    /// lane's set gives that lane's point back unchanged. Keep-out spheres, capsules (in
    /// lanes) and boxes (scalar), clustered about the points so that many sets leave
    /// members out and many points are pushed; swept steps and points at rest.
    #[test]
    fn collide_with_near_sets_gives_the_bits_of_asking_every_member() {
        let mut rng = SplitMix64::new(17);
        let mut u = |lo: f32, hi: f32| rng.range_f32(lo, hi);
        let bits = |v: V3| [v.x, v.y, v.z].map(|c| c.0.map(f32::to_bits));
        let m = 8;
        let list: Vec<usize> = (0..m).collect();
        // Lanes whose set leaves a member out, and lanes a member moved.
        let (mut left_out, mut moved_lanes) = (0, 0);
        for round in 0..2000 {
            let shapes: Vec<Shape> = (0..m)
                .map(|k| match (round + k) % 3 {
                    0 => Shape::Sphere {
                        radius: u(0.02, 0.08),
                        inside: false,
                    },
                    1 => Shape::Capsule {
                        radius: u(0.02, 0.06),
                        length: u(0.0, 0.2),
                    },
                    _ => Shape::Box {
                        half_extents: Vec3::new(u(0.01, 0.05), u(0.01, 0.05), u(0.01, 0.05)),
                    },
                })
                .collect();
            let lane_shapes: Vec<LaneShape> = shapes.iter().map(|&sh| LaneShape::of(sh)).collect();
            let mut colliders = Vec::with_capacity(m * LANES);
            let mut bounds = vec![Bound::ZERO; m];
            let (mut start, mut x, mut lo, mut hi) = (V3::ZERO, V3::ZERO, V3::ZERO, V3::ZERO);
            let r = u(0.0, 0.03);
            for l in 0..LANES {
                let parent = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
                let length = u(0.03, 0.12);
                let dir = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)).normalize_or(Vec3::Y);
                let s0 = parent + dir * length;
                let x0 = s0 + Vec3::new(u(-0.03, 0.03), u(-0.03, 0.03), u(-0.03, 0.03));
                for (k, &shape) in shapes.iter().enumerate() {
                    // Most colliders about the bone, some far from it.
                    let spread = if k % 4 == 3 { 0.6 } else { 0.15 };
                    let centre =
                        s0 + Vec3::new(u(-spread, spread), u(-spread, spread), u(-spread, spread));
                    let rotation =
                        Quat::from_euler(glam::EulerRot::XYZ, u(-3.0, 3.0), u(-3.0, 3.0), 0.0);
                    let pc = PlacedCollider {
                        shape,
                        transform: Transform::from_translation_rotation(centre, rotation),
                    };
                    bounds[k].set(l, &pc);
                    colliders.push(pc);
                }
                start.set(l, s0);
                x.set(l, x0);
                lo.set(l, s0.min(x0).min(parent - length));
                hi.set(l, s0.max(x0).max(parent + length));
            }
            let mut near = vec![M::NONE; m];
            near_sets::<F>(&list, &bounds, lo, hi, r, &mut near);
            let every = vec![M::ALL; m];
            for prev in [Some(start), None] {
                let open = M::from_bools(std::array::from_fn(|l| (l + round) % 7 != 0));
                let run = |near: &[M]| {
                    collide::<F>(
                        &list,
                        &colliders,
                        m,
                        &bounds,
                        &lane_shapes,
                        near,
                        x,
                        prev,
                        r,
                        open,
                    )
                };
                let (y, moved) = run(&near);
                let (y_all, moved_all) = run(&every);
                assert_eq!(bits(y), bits(y_all), "round {round}, prev {prev:?}");
                assert_eq!(moved.0, moved_all.0, "round {round}");
                for l in 0..LANES {
                    moved_lanes += usize::from(moved.0[l] != 0);
                    left_out += usize::from(open.0[l] != 0 && near.iter().any(|n| n.0[l] == 0));
                }
            }
        }
        assert!(moved_lanes > 10_000, "{moved_lanes} lanes moved");
        assert!(
            left_out > 25_000,
            "{left_out} lanes whose set left a member out"
        );
    }
}
