//! Capsule collision: keep a point outside a segment inflated by a radius.

use crate::math::{closest_params_segment_segment, closest_point_on_segment, normalize_or};
use glam::Vec3;

/// Pushes `p` out of the capsule `a`–`b` with `limit` = capsule radius + point radius.
///
/// As [`crate::collide::push_out_of_sphere`]: a point inside is pushed out radially; a
/// step that entered the capsule from outside by more than a rounding tolerance (also one
/// that passed right through) stops where it met the surface and keeps the tangential
/// part of the rest of its step, so a point sliding along the capsule slides on.
pub fn push_out_of_capsule(p: Vec3, prev: Vec3, a: Vec3, b: Vec3, limit: f32) -> Vec3 {
    let tol = crate::collide::contact_tolerance(limit);
    let inner = (limit - tol).max(0.0);
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
            // The step entered. Distance to a convex shape is convex along a line, so it
            // falls monotonically from `prev` to the closest approach: bisect for the
            // first point at `inner`, the surface the test above uses (a path grazing it
            // is then redirected by nothing: the contact is continuous in its input).
            let (mut lo, mut hi) = (0.0f32, s);
            if prev_dist > inner {
                for _ in 0..32 {
                    let mid = 0.5 * (lo + hi);
                    if dist(prev + (p - prev) * mid) > inner {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
            }
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
}
