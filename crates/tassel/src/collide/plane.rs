//! Plane collision: keep a point on the normal's side, also when it crossed in one step.

use glam::Vec3;

/// Puts `p` on the plane (`origin`, unit `normal`) lifted by the point radius `r` when it
/// is closer than `r`, behind the plane, or crossed the plane on its way from `prev`.
pub fn push_above_plane(p: Vec3, prev: Vec3, origin: Vec3, normal: Vec3, r: f32) -> Vec3 {
    let h = (p - origin).dot(normal);
    let h_prev = (prev - origin).dot(normal);
    let crossed = h_prev >= 0.0 && h < 0.0;
    if h < r || crossed {
        p + normal * (r - h)
    } else {
        p
    }
}

/// Violation depth of a point of radius `r` against the plane.
pub fn plane_penetration(p: Vec3, origin: Vec3, normal: Vec3, r: f32) -> f32 {
    r - (p - origin).dot(normal)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lifts_to_radius() {
        let p = push_above_plane(
            Vec3::new(1.0, -0.3, 2.0),
            Vec3::new(1.0, 0.5, 2.0),
            Vec3::ZERO,
            Vec3::Y,
            0.1,
        );
        assert!(p.abs_diff_eq(Vec3::new(1.0, 0.1, 2.0), 1e-6));
        let q = Vec3::new(0.0, 0.5, 0.0);
        assert_eq!(push_above_plane(q, q, Vec3::ZERO, Vec3::Y, 0.1), q);
    }
}
