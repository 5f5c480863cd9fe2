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

    /// Tassel's exact resolution on the bone sphere (fixed mode, after the spec's push):
    /// the tail at distance `length` from the joint at `pos` that satisfies this collider
    /// and is nearest to `tail`. The constraint is a cone of directions around the joint
    /// (`u·a ≥ c`); the tail keeps its direction about the cone's axis. Where no direction
    /// satisfies it (the joint too deep), the tail points straight out.
    pub fn settle(&self, pos: Vec3, length: f32, tail: Vec3, r: f32) -> Vec3 {
        if length <= 0.0 {
            return tail;
        }
        // Returns (axis a, min cosine c).
        let cone = |q: Vec3, limit: f32, inside: bool| -> Option<(Vec3, f32)> {
            let d = pos - q;
            let dl = d.length();
            if dl < 1e-9 {
                return None;
            }
            let k = (limit * limit - dl * dl - length * length) / (2.0 * length * dl);
            Some(if inside { (-d / dl, -k) } else { (d / dl, k) })
        };
        let constraint = match *self {
            PlacedVrmCollider::Plane { point, normal } => {
                Some((normal, (r - (pos - point).dot(normal)) / length))
            }
            PlacedVrmCollider::Sphere {
                center,
                radius,
                inside,
            } => cone(
                center,
                if inside {
                    (radius - r).max(0.0)
                } else {
                    radius + r
                },
                inside,
            ),
            PlacedVrmCollider::Capsule {
                head,
                tail: end,
                radius,
                inside,
            } => {
                let q = crate::math::closest_point_on_segment(tail, head, end);
                cone(
                    q,
                    if inside {
                        (radius - r).max(0.0)
                    } else {
                        radius + r
                    },
                    inside,
                )
            }
        };
        let Some((a, c)) = constraint else {
            return tail;
        };
        let u = normalize_or(tail - pos, a);
        if u.dot(a) >= c - 1e-6 || c < -1.0 {
            return tail;
        }
        if c >= 1.0 {
            return pos + a * length;
        }
        let side = u - a * u.dot(a);
        let side = normalize_or(side, a.any_orthonormal_vector());
        pos + (a * c + side * (1.0 - c * c).sqrt()) * length
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
    fn settle_finds_the_nearest_allowed_tail() {
        // Joint 0.03 above a floor, bone 0.05 hanging straight down through it: the
        // spec's push along the normal is undone by the length projection; settle tips the
        // bone just enough (tail 0.02 above the floor for a 0.02 tail radius).
        let floor = PlacedVrmCollider::Plane {
            point: Vec3::ZERO,
            normal: Vec3::Y,
        };
        let pos = Vec3::new(0.0, 0.03, 0.0);
        let t = floor.settle(pos, 0.05, Vec3::new(0.001, -0.02, 0.0), 0.02);
        assert!(
            (t.y - 0.02).abs() < 1e-6 && (t.distance(pos) - 0.05).abs() < 1e-6,
            "{t}"
        );
        assert!(t.x > 0.0, "keeps its side: {t}");
        // Sphere: the result touches radius + r and keeps the bone length.
        let ball = PlacedVrmCollider::Sphere {
            center: Vec3::new(0.05, 0.0, 0.0),
            radius: 0.04,
            inside: false,
        };
        let pos = Vec3::new(0.0, 0.0, 0.0);
        let t = ball.settle(pos, 0.06, Vec3::new(0.06, 0.0, 0.001), 0.01);
        assert!(
            (t.distance(Vec3::new(0.05, 0.0, 0.0)) - 0.05).abs() < 1e-5,
            "{t}"
        );
        assert!((t.length() - 0.06).abs() < 1e-6);
        // Inside sphere: pulled back to radius − r.
        let cage = PlacedVrmCollider::Sphere {
            center: Vec3::ZERO,
            radius: 0.1,
            inside: true,
        };
        let pos = Vec3::new(0.05, 0.0, 0.0);
        let t = cage.settle(pos, 0.06, Vec3::new(0.11, 0.0, 0.0), 0.01);
        assert!((t.length() - 0.09).abs() < 1e-5 && (t.distance(pos) - 0.06).abs() < 1e-5);
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
