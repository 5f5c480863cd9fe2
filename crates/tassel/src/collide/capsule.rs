//! Capsule collision: keep a point outside a segment inflated by a radius.

use crate::math::{closest_params_segment_segment, closest_point_on_segment, normalize_or};
use glam::Vec3;

/// Pushes `p` out of the capsule `a`–`b` with `limit` = capsule radius + point radius. A
/// point whose step (`prev` → `p`) passed through the capsule is returned to the side it
/// came from.
pub fn push_out_of_capsule(p: Vec3, prev: Vec3, a: Vec3, b: Vec3, limit: f32) -> Vec3 {
    let c = closest_point_on_segment(p, a, b);
    let d = p - c;
    if d.length_squared() < limit * limit {
        let fallback = normalize_or(
            prev - closest_point_on_segment(prev, a, b),
            (b - a).any_orthonormal_vector(),
        );
        return c + normalize_or(d, fallback) * limit;
    }
    let (s, t) = closest_params_segment_segment(prev, p, a, b);
    let on_path = prev + (p - prev) * s;
    let on_axis = a + (b - a) * t;
    let prev_c = closest_point_on_segment(prev, a, b);
    if (on_path - on_axis).length_squared() < limit * limit
        && (prev - prev_c).length_squared() >= limit * limit
    {
        return prev_c + normalize_or(prev - prev_c, Vec3::Y) * limit;
    }
    p
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
