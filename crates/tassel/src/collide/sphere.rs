//! Sphere collision: keep a point outside (with a swept test) or inside.

use crate::math::{closest_point_on_segment, normalize_or};
use glam::Vec3;

/// Pushes `p` out of the sphere (`center`, `limit` = sphere radius + point radius).
///
/// A point inside is pushed out along the shortest way. A point whose step (`prev` → `p`)
/// entered the sphere from outside — by more than a rounding tolerance, so that a point
/// resting on or sliding along the surface is never mistaken for one — is stopped where
/// the step met the surface (less that tolerance: the redirection then fades to nothing
/// as a path's dip fades to the tolerance, so the result is continuous in the input) and
/// keeps the tangential part of the rest of its step: it slides, it is never sent back to
/// `prev`. That also catches a step that passed right through (tunnelling).
pub fn push_out_of_sphere(p: Vec3, prev: Vec3, center: Vec3, limit: f32) -> Vec3 {
    let inner2 = super::entry_radius(limit).powi(2);
    let prev_out = (prev - center).length_squared() >= inner2;
    let c = closest_point_on_segment(center, prev, p);
    if prev_out && (c - center).length_squared() < inner2 {
        // The step entered: where it first met the entry surface, |o + t·v| = limit −
        // tolerance (the surface the test above uses, so that a path grazing it is
        // redirected by nothing and the contact is continuous in its input).
        let (o, v) = (prev - center, p - prev);
        let (vv, ov) = (v.length_squared(), o.dot(v));
        let disc = (ov * ov - vv * (o.length_squared() - inner2)).max(0.0);
        let t = if vv > 0.0 {
            ((-ov - disc.sqrt()) / vv).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let contact = prev + v * t;
        let n = normalize_or(contact - center, normalize_or(o, Vec3::Y));
        let rest = p - contact;
        let slid = contact + rest - n * rest.dot(n).min(0.0);
        return outside_sphere(slid, center, limit, n);
    }
    outside_sphere(p, center, limit, normalize_or(prev - center, Vec3::Y))
}

/// `p`, or the nearest point of the sphere's surface when it is inside.
fn outside_sphere(p: Vec3, center: Vec3, limit: f32, fallback: Vec3) -> Vec3 {
    let d = p - center;
    if d.length_squared() < limit * limit {
        center + normalize_or(d, fallback) * limit
    } else {
        p
    }
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
        // Tunnelled straight through in one step, head on: stopped on the entry side.
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
