//! Capsule collision: keep a point outside a segment inflated by a radius.

use crate::math::{closest_params_segment_segment, closest_point_on_segment, normalize_or};
use glam::{DVec3, Vec3};

/// Pushes `p` out of the capsule `a`–`b` with `limit` = capsule radius + point radius.
///
/// As [`crate::collide::push_out_of_sphere`]: a point inside is pushed out radially; a
/// step that entered the capsule from outside by more than a rounding tolerance (also one
/// that passed right through) stops where it met the surface and keeps the tangential
/// part of the rest of its step, so a point sliding along the capsule slides on.
pub fn push_out_of_capsule(p: Vec3, prev: Vec3, a: Vec3, b: Vec3, limit: f32) -> Vec3 {
    let inner = crate::collide::entry_radius(limit);
    let dist = |q: Vec3| (q - closest_point_on_segment(q, a, b)).length();
    let prev_fallback = || {
        normalize_or(
            prev - closest_point_on_segment(prev, a, b),
            (b - a).any_orthonormal_vector(),
        )
    };
    let prev_dist = dist(prev);
    if prev_dist >= inner {
        let (s, t) = closest_params_segment_segment(prev, p, a, b);
        let on_path = prev + (p - prev) * s;
        let on_axis = a + (b - a) * t;
        if (on_path - on_axis).length_squared() < inner * inner {
            // The step entered: find the first point of the path at `inner`, the surface
            // the test above uses (a path grazing it is then redirected by nothing: the
            // contact is continuous in its input). In closed form; by bisection where
            // rounding near a graze leaves the closed form without a root.
            let lo = if prev_dist > inner {
                capsule_entry(prev, p - prev, a, b, inner)
                    .map_or_else(|| entry_by_bisection(prev, p, s, inner, dist), |t| t.min(s))
            } else {
                0.0
            };
            let contact = prev + (p - prev) * lo;
            let n = normalize_or(
                contact - closest_point_on_segment(contact, a, b),
                prev_fallback(),
            );
            let rest = p - contact;
            let slid = contact + rest - n * rest.dot(n).min(0.0);
            return outside_capsule(slid, a, b, limit, n);
        }
    }
    outside_capsule(p, a, b, limit, prev_fallback())
}

/// The first share `t` of the step `o` → `o + v` at which the path is `rho` from the
/// segment `a`–`b` (it enters the capsule of that radius), in closed form: the capsule is
/// the union of the finite cylinder's side and the two end balls, so the first entry is
/// the earliest of the side's entry (where it lies between the ends) and the balls'
/// entries. `None` when the line does not meet the capsule (rounding near a graze).
///
/// In f64: a thin capsule far from the step's start makes the quadratics' discriminants
/// small differences of large numbers, which f32 gets wrong by 1e-5 of the step.
fn capsule_entry(o: Vec3, v: Vec3, a: Vec3, b: Vec3, rho: f32) -> Option<f32> {
    let (o, v, a, b) = (o.as_dvec3(), v.as_dvec3(), a.as_dvec3(), b.as_dvec3());
    let rho2 = f64::from(rho) * f64::from(rho);
    // The entry root of t²·qa + 2t·half_b + qc = 0 for a start outside (qc > 0), in the
    // form without cancellation for an approaching path: qc / (−half_b + √h).
    let entry = |qa: f64, half_b: f64, qc: f64| -> Option<f64> {
        let h = half_b * half_b - qa * qc;
        if h.is_nan() || h < 0.0 {
            return None;
        }
        // The exit must not lie behind the start (a shape behind is no entry).
        let far = -half_b + h.sqrt();
        (far > 0.0).then(|| (qc / far).max(0.0))
    };
    let mut first = f64::INFINITY;
    // An end ball at `c`: |o − c + v·t|² = ρ².
    let vv = v.dot(v);
    let mut ball = |c: DVec3| {
        let oc = o - c;
        if let Some(t) = entry(vv, v.dot(oc), oc.dot(oc) - rho2) {
            first = first.min(t);
        }
    };
    ball(a);
    let ba = b - a;
    let baba = ba.dot(ba);
    if baba > 1e-20 {
        ball(b);
        // The infinite cylinder, from the parts of the start and the step across the axis.
        let n = ba / baba.sqrt();
        let oa = o - a;
        let v_across = v - n * n.dot(v);
        let oa_across = oa - n * n.dot(oa);
        if let Some(t) = entry(
            v_across.dot(v_across),
            v_across.dot(oa_across),
            oa_across.dot(oa_across) - rho2,
        ) {
            // Only where the side is: between the ends.
            let y = ba.dot(oa + v * t);
            if y > 0.0 && y < baba {
                first = first.min(t);
            }
        }
    }
    first.is_finite().then_some(first as f32)
}

/// The last share of the step `prev` → `p` (up to the closest approach `s`) still farther
/// than `inner` from the capsule's axis, by bisection: the distance to a convex shape is
/// convex along a line, so it falls monotonically from `prev` to the closest approach.
fn entry_by_bisection(prev: Vec3, p: Vec3, s: f32, inner: f32, dist: impl Fn(Vec3) -> f32) -> f32 {
    let (mut lo, mut hi) = (0.0f32, s);
    for _ in 0..32 {
        let mid = 0.5 * (lo + hi);
        if dist(prev + (p - prev) * mid) > inner {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// `p`, or the nearest point of the capsule's surface when it is inside.
fn outside_capsule(p: Vec3, a: Vec3, b: Vec3, limit: f32, fallback: Vec3) -> Vec3 {
    let c = closest_point_on_segment(p, a, b);
    let d = p - c;
    if d.length_squared() < limit * limit {
        c + normalize_or(d, fallback) * limit
    } else {
        p
    }
}

/// Violation depth of `p` against the capsule `a`–`b` inflated by `limit`.
pub fn capsule_penetration(p: Vec3, a: Vec3, b: Vec3, limit: f32) -> f32 {
    limit - (p - closest_point_on_segment(p, a, b)).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pushes_out_radially_and_catches_tunnelling() {
        let (a, b) = (Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
        let p = push_out_of_capsule(
            Vec3::new(0.1, 0.5, 0.0),
            Vec3::new(0.1, 0.5, 0.0),
            a,
            b,
            0.5,
        );
        assert!(p.abs_diff_eq(Vec3::new(0.5, 0.5, 0.0), 1e-6));
        let p = push_out_of_capsule(
            Vec3::new(3.0, 0.0, 0.0),
            Vec3::new(-3.0, 0.0, 0.0),
            a,
            b,
            0.5,
        );
        assert!(p.abs_diff_eq(Vec3::new(-0.5, 0.0, 0.0), 1e-6));
        assert!(capsule_penetration(p, a, b, 0.5).abs() < 1e-6);
    }

    /// The closed-form entry against its definition: the first point of the path at the
    /// radius from the axis segment, found by bisecting the distance (which falls
    /// monotonically up to the closest approach), on random capsules (spheres among them)
    /// and steps that enter through the side, the end balls, nearly along the axis and
    /// right through.
    #[test]
    fn the_closed_form_entry_is_where_the_path_first_meets_the_capsule() {
        use crate::math::closest_params_segment_segment;
        let mut rng = crate::rng::SplitMix64::new(11);
        let mut u = |lo: f32, hi: f32| rng.range_f32(lo, hi);
        let mut checked = 0;
        for case in 0..20_000 {
            let a = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
            let axis = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
            let b = if case % 5 == 0 {
                a
            } else {
                a + axis * u(0.0, 0.5)
            };
            let rho = u(0.01, 0.3);
            let prev = a + Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
            // Aim at a point near the capsule, sometimes along its axis.
            let aim = if case % 7 == 0 {
                b + (b - a) * u(-3.0, 3.0)
            } else {
                a + (b - a) * u(-0.3, 1.3)
                    + Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)) * rho
            };
            let p = prev + (aim - prev) * u(0.5, 2.0);
            let dist = |q: Vec3| (q - closest_point_on_segment(q, a, b)).length();
            let (s, t) = closest_params_segment_segment(prev, p, a, b);
            let closest = (prev + (p - prev) * s - (a + (b - a) * t)).length();
            // Only steps that start clearly outside and end up clearly inside the closest
            // approach: the cases push_out_of_capsule asks about.
            if dist(prev) < rho * 1.001 || closest > rho * 0.999 {
                continue;
            }
            checked += 1;
            let bisected = entry_by_bisection(prev, p, s, rho, dist);
            let t = capsule_entry(prev, p - prev, a, b, rho)
                .expect("the path enters")
                .min(s);
            let step = (p - prev).length();
            assert!(
                ((t - bisected) * step).abs() < 2e-6,
                "case {case}: closed form {t} (dist {}), bisection {bisected} (dist {}), step {step}, rho {rho}, a {a} b {b} prev {prev} p {p}",
                dist(prev + (p - prev) * t),
                dist(prev + (p - prev) * bisected)
            );
            let at = prev + (p - prev) * t;
            assert!(
                (dist(at) - rho).abs() < 2e-6,
                "case {case}: {} vs {rho}",
                dist(at)
            );
        }
        assert!(checked > 5_000, "only {checked} entering steps");
    }
}
