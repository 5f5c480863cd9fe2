//! Character collider shapes and the point queries the solvers use: push a point of a given
//! radius out of (or, for inside limits, back into) a shape. Shapes live in the space of
//! the points they act on (model space for the chain solver); capsules and planes use the
//! collider's local +Y as their axis and normal.

mod r#box;
mod capsule;
mod plane;
mod sphere;

pub use capsule::{capsule_penetration, push_out_of_capsule};
pub use plane::{plane_penetration, push_above_plane};
pub use r#box::{box_penetration, push_out_of_box};
pub use sphere::{push_into_sphere, push_out_of_sphere, sphere_penetration};

use crate::math::Transform;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// A collider shape in its own local frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum Shape {
    /// A sphere; `inside` keeps points inside it instead of outside.
    Sphere {
        /// Radius in metres (≥ 0).
        radius: f32,
        /// Keep points inside (a limit) rather than outside.
        #[serde(default)]
        inside: bool,
    },
    /// A capsule along local +Y, centred on the origin.
    Capsule {
        /// Radius in metres (≥ 0).
        radius: f32,
        /// Length of the axis segment between the two cap centres, metres (≥ 0).
        length: f32,
    },
    /// An oriented box centred on the origin.
    Box {
        /// Half sizes along local X, Y, Z in metres (each ≥ 0).
        half_extents: Vec3,
    },
    /// The plane through the origin with normal local +Y; points stay on the +Y side.
    Plane,
}

impl Shape {
    /// Checks radii and sizes.
    pub fn validate(&self, what: &str) -> Result<(), crate::Error> {
        let bad = |m: String| Err(crate::Error::InvalidParameter(m));
        match *self {
            Shape::Sphere { radius, .. } if !(radius.is_finite() && radius >= 0.0) => bad(format!(
                "{what}: sphere radius {radius} must be finite and ≥ 0"
            )),
            Shape::Capsule { radius, length }
                if !(radius.is_finite()
                    && radius >= 0.0
                    && length.is_finite()
                    && length >= 0.0) =>
            {
                bad(format!(
                    "{what}: capsule radius {radius} and length {length} must be finite and ≥ 0"
                ))
            }
            Shape::Box { half_extents }
                if !(half_extents.is_finite() && half_extents.min_element() >= 0.0) =>
            {
                bad(format!(
                    "{what}: box half extents {half_extents} must be finite and ≥ 0"
                ))
            }
            _ => Ok(()),
        }
    }
}

/// How far inside a shape a step's path must dip before it counts as entering it: points
/// pushed exactly onto a surface sit there only to f32 rounding, and a point sliding along
/// it must not be taken for one that passed through (1e-4 of the contact distance).
pub(crate) fn contact_tolerance(limit: f32) -> f32 {
    1e-4 * limit
}

/// A shape placed in the solver's space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlacedCollider {
    /// The shape.
    pub shape: Shape,
    /// Where it is (scale is ignored).
    pub transform: Transform,
}

impl PlacedCollider {
    /// Moves a point of radius `r` that was at `prev` and is now at `p` to satisfy the
    /// collider: out of keep-out shapes (also when it passed through during the step),
    /// into keep-inside spheres, above planes.
    pub fn resolve(&self, p: Vec3, prev: Vec3, r: f32) -> Vec3 {
        let t = &self.transform;
        // Cheap reject: both ends of the step far from a bounded shape.
        if let Some(bound) = self.bounding_radius() {
            let reach = bound + r;
            let c = t.translation;
            if (p - c).length_squared() > reach * reach
                && (prev - c).length_squared() > reach * reach
                && (p - prev).length_squared() < ((p - c).length() - reach).powi(2)
            {
                return p;
            }
        }
        match self.shape {
            Shape::Sphere {
                radius,
                inside: false,
            } => push_out_of_sphere(p, prev, t.translation, radius + r),
            Shape::Sphere {
                radius,
                inside: true,
            } => push_into_sphere(p, t.translation, (radius - r).max(0.0)),
            Shape::Capsule { radius, length } => {
                let (a, b) = self.capsule_ends(length);
                push_out_of_capsule(p, prev, a, b, radius + r)
            }
            Shape::Box { half_extents } => push_out_of_box(p, t, half_extents, r),
            Shape::Plane => push_above_plane(p, prev, t.translation, t.rotation * Vec3::Y, r),
        }
    }

    /// The collider moved a share `w` of the way from `self` to `other` (shape of `other`).
    pub fn lerp(&self, other: &PlacedCollider, w: f32) -> PlacedCollider {
        PlacedCollider {
            shape: other.shape,
            transform: self.transform.lerp(&other.transform, w),
        }
    }

    /// How far a point of radius `r` at `p` violates the collider (≤ 0 when it does not).
    pub fn penetration(&self, p: Vec3, r: f32) -> f32 {
        let t = &self.transform;
        match self.shape {
            Shape::Sphere { radius, inside } => {
                sphere_penetration(p, t.translation, radius, r, inside)
            }
            Shape::Capsule { radius, length } => {
                let (a, b) = self.capsule_ends(length);
                capsule_penetration(p, a, b, radius + r)
            }
            Shape::Box { half_extents } => box_penetration(p, t, half_extents, r),
            Shape::Plane => plane_penetration(p, t.translation, t.rotation * Vec3::Y, r),
        }
    }

    /// Radius of a sphere about the origin that holds the shape (`None` for planes and
    /// inside limits, which act everywhere).
    fn bounding_radius(&self) -> Option<f32> {
        match self.shape {
            Shape::Sphere {
                radius,
                inside: false,
            } => Some(radius),
            Shape::Capsule { radius, length } => Some(radius + 0.5 * length),
            Shape::Box { half_extents } => Some(half_extents.length()),
            _ => None,
        }
    }

    fn capsule_ends(&self, length: f32) -> (Vec3, Vec3) {
        let axis = self.transform.rotation * Vec3::Y * (0.5 * length);
        (
            self.transform.translation - axis,
            self.transform.translation + axis,
        )
    }
}
