//! VRM collider shapes placed in world space and the specification's collision query:
//! a signed distance (negative when the tail's sphere violates the shape) and the
//! direction to push along.

use super::settings::VrmShape;
use crate::math::{normalize_or, Transform};
use glam::Vec3;

/// A VRM collider in world space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlacedVrmCollider {
    /// Sphere (outside or inside).
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
        /// Keep inside.
        inside: bool,
    },
    /// Capsule from `head` to `tail` (outside or inside).
    Capsule {
        /// Head end.
        head: Vec3,
        /// Tail end.
        tail: Vec3,
        /// Radius.
        radius: f32,
        /// Keep inside.
        inside: bool,
    },
    /// Plane through `point` with unit `normal`.
    Plane {
        /// A point of the plane.
        point: Vec3,
        /// Unit normal.
        normal: Vec3,
    },
}

impl PlacedVrmCollider {
    /// Places `shape` with its joint's world transform: points go through the whole
    /// transform, the plane normal through the normal matrix (rotation and inverse scale).
    pub fn place(shape: &VrmShape, world: &Transform) -> Self {
        match *shape {
            VrmShape::Sphere {
                offset,
                radius,
                inside,
            } => PlacedVrmCollider::Sphere {
                center: world.transform_point(offset),
                radius,
                inside,
            },
            VrmShape::Capsule {
                offset,
                tail,
                radius,
                inside,
            } => PlacedVrmCollider::Capsule {
                head: world.transform_point(offset),
                tail: world.transform_point(tail),
                radius,
                inside,
            },
            VrmShape::Plane { offset, normal } => PlacedVrmCollider::Plane {
                point: world.transform_point(offset),
                normal: normalize_or(world.rotation * (normal / world.scale), Vec3::Y),
            },
        }
    }

    /// The specification's `calculateCollision` for a tail at `p` with radius `r`:
    /// `(direction, distance)`; when `distance < 0` the tail moves by `-direction·distance`.
    pub fn collision(&self, p: Vec3, r: f32) -> (Vec3, f32) {
        match *self {
            PlacedVrmCollider::Sphere {
                center,
                radius,
                inside,
            } => from_delta(p - center, radius, r, inside),
            PlacedVrmCollider::Capsule {
                head,
                tail,
                radius,
                inside,
            } => {
                let axis = tail - head;
                let mut delta = p - head;
                let dot = axis.dot(delta);
                let len2 = axis.length_squared();
                if dot <= 0.0 {
                    // Nearest to the head.
                } else if len2 <= dot {
                    delta -= axis;
                } else {
                    delta -= axis * (dot / len2);
                }
                from_delta(delta, radius, r, inside)
            }
            PlacedVrmCollider::Plane { point, normal } => (normal, (p - point).dot(normal) - r),
        }
    }

    /// How far a tail at `p` with radius `r` violates the collider (≤ 0 when it does not).
    pub fn penetration(&self, p: Vec3, r: f32) -> f32 {
        -self.collision(p, r).1
    }
}

/// Sphere-like distance from the vector `delta` (shape's nearest axis point → tail).
fn from_delta(delta: Vec3, radius: f32, r: f32, inside: bool) -> (Vec3, f32) {
    let len = delta.length();
    if inside {
        (-normalize_or(delta, Vec3::ZERO), radius - r - len)
    } else {
        (normalize_or(delta, Vec3::ZERO), len - (radius + r))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    #[test]
    fn sphere_distance_and_direction() {
        let c = PlacedVrmCollider::Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
            inside: false,
        };
        let (d, dist) = c.collision(Vec3::new(0.5, 0.0, 0.0), 0.25);
        assert!(d.abs_diff_eq(Vec3::X, 1e-6));
        assert!((dist + 0.75).abs() < 1e-6);
        let inside = PlacedVrmCollider::Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
            inside: true,
        };
        // 2 m out of a 1 m sphere with a 0.25 m tail: 1.25 m too far, pushed back (−X).
        let (d, dist) = inside.collision(Vec3::new(2.0, 0.0, 0.0), 0.25);
        assert!(d.abs_diff_eq(-Vec3::X, 1e-6));
        assert!((dist + 1.25).abs() < 1e-6);
    }

    #[test]
    fn capsule_uses_the_nearest_axis_point() {
        let c = PlacedVrmCollider::Capsule {
            head: Vec3::ZERO,
            tail: Vec3::new(0.0, 2.0, 0.0),
            radius: 0.5,
            inside: false,
        };
        // Beside the shaft: distance from the axis.
        let (d, dist) = c.collision(Vec3::new(0.3, 1.0, 0.0), 0.0);
        assert!(d.abs_diff_eq(Vec3::X, 1e-6) && (dist + 0.2).abs() < 1e-6);
        // Beyond the tail: distance from the tail end.
        let (_, dist) = c.collision(Vec3::new(0.0, 3.0, 0.0), 0.0);
        assert!((dist - 0.5).abs() < 1e-6);
        // Before the head.
        let (d, dist) = c.collision(Vec3::new(0.0, -0.2, 0.0), 0.1);
        assert!(d.abs_diff_eq(-Vec3::Y, 1e-6) && (dist + 0.4).abs() < 1e-6);
    }

    #[test]
    fn plane_normal_follows_the_joint() {
        // A joint turned 90° about Z: local +Y points along world −X.
        let world = Transform::from_translation_rotation(
            Vec3::new(1.0, 0.0, 0.0),
            Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
        );
        let p = PlacedVrmCollider::place(
            &VrmShape::Plane {
                offset: Vec3::ZERO,
                normal: Vec3::Y,
            },
            &world,
        );
        let (d, dist) = p.collision(Vec3::new(1.5, 0.0, 0.0), 0.1);
        assert!(d.abs_diff_eq(-Vec3::X, 1e-6));
        assert!((dist + 0.6).abs() < 1e-6, "{dist}");
    }
}
