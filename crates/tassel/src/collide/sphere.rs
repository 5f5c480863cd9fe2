//! Sphere collision: keep a point outside (with a swept test) or inside.

use crate::math::{closest_point_on_segment, normalize_or};
use glam::Vec3;

/// Pushes `p` out of the sphere (`center`, `limit` = sphere radius + point radius) along
/// the shortest way. A point that crossed the whole sphere during the step (`prev` → `p`)
/// is put back on the side it came from.
pub fn push_out_of_sphere(p: Vec3, prev: Vec3, center: Vec3, limit: f32) -> Vec3 {
    let d = p - center;
    let dist2 = d.length_squared();
    if dist2 < limit * limit {
        let fallback = normalize_or(prev - center, Vec3::Y);
        return center + normalize_or(d, fallback) * limit;
    }
    // Swept: did the path pass through the sphere?
    let c = closest_point_on_segment(center, prev, p);
    if (c - center).length_squared() < limit * limit
        && (prev - center).length_squared() >= limit * limit
    {
        return center + normalize_or(prev - center, Vec3::Y) * limit;
    }
    p
}

/// Pulls `p` back inside the sphere (`center`, `limit` = sphere radius − point radius).
pub fn push_into_sphere(p: Vec3, center: Vec3, limit: f32) -> Vec3 {
    let d = p - center;
    if d.length_squared() > limit * limit {
        center + normalize_or(d, Vec3::Y) * limit
    } else {
        p
    }
}

/// Violation depth of a point of radius `r` against a sphere (outside or inside limit).
pub fn sphere_penetration(p: Vec3, center: Vec3, radius: f32, r: f32, inside: bool) -> f32 {
    let dist = (p - center).length();
    if inside {
        dist - (radius - r).max(0.0)
    } else {
        radius + r - dist
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pushes_to_surface() {
        let p = push_out_of_sphere(
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::ZERO,
            1.0,
        );
        assert!(p.abs_diff_eq(Vec3::X, 1e-6));
        // Tunnelled straight through in one step: back to the entry side.
        let p = push_out_of_sphere(
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(-2.0, 0.0, 0.0),
            Vec3::ZERO,
            1.0,
        );
        assert!(p.abs_diff_eq(-Vec3::X, 1e-6));
        let p = push_into_sphere(Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO, 1.0);
        assert!(p.abs_diff_eq(Vec3::Y, 1e-6));
    }
}
