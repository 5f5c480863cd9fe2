//! Oriented box collision: keep a point of radius `r` outside a box (its surface inflated
//! by `r`, i.e. a rounded box).

use crate::math::{normalize_or, Transform};
use glam::Vec3;

/// Pushes `p` out of the box placed by `t` with the given half extents.
pub fn push_out_of_box(p: Vec3, t: &Transform, half: Vec3, r: f32) -> Vec3 {
    let local = t.rotation.inverse() * (p - t.translation);
    let clamped = local.clamp(-half, half);
    let out = if clamped != local {
        // Outside the box itself: keep at distance r from the nearest box point.
        let d = local - clamped;
        if d.length_squared() >= r * r {
            return p;
        }
        clamped + normalize_or(d, Vec3::Y) * r
    } else {
        // Inside: leave through the nearest face.
        let gap = half - local.abs();
        let axis = if gap.x <= gap.y && gap.x <= gap.z {
            0
        } else if gap.y <= gap.z {
            1
        } else {
            2
        };
        let mut q = local;
        let sign = if local[axis] >= 0.0 { 1.0 } else { -1.0 };
        q[axis] = sign * (half[axis] + r);
        q
    };
    t.translation + t.rotation * out
}

/// Violation depth of a point of radius `r` against the box.
pub fn box_penetration(p: Vec3, t: &Transform, half: Vec3, r: f32) -> f32 {
    let local = t.rotation.inverse() * (p - t.translation);
    let clamped = local.clamp(-half, half);
    if clamped != local {
        r - (local - clamped).length()
    } else {
        r + (half - local.abs()).min_element()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    #[test]
    fn leaves_through_nearest_face() {
        let t = Transform::from_translation_rotation(
            Vec3::new(1.0, 0.0, 0.0),
            Quat::from_rotation_z(0.3),
        );
        let half = Vec3::new(0.5, 0.2, 0.4);
        for p in [
            Vec3::new(1.1, 0.05, 0.1),
            Vec3::new(1.45, 0.0, 0.0),
            Vec3::new(0.6, 0.1, -0.35),
        ] {
            let q = push_out_of_box(p, &t, half, 0.05);
            assert!(box_penetration(q, &t, half, 0.05) <= 1e-5, "{p} -> {q}");
        }
        // By hand: a point 0.1 under the +Y face of an axis-aligned box moves 0.1 + r up.
        let q = push_out_of_box(
            Vec3::new(0.0, 0.1, 0.0),
            &Transform::IDENTITY,
            Vec3::splat(0.2),
            0.05,
        );
        assert!(q.abs_diff_eq(Vec3::new(0.0, 0.25, 0.0), 1e-6));
    }
}
