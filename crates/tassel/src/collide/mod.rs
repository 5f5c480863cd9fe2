//! Character collider shapes and the point queries the solvers use: push a point of a given
//! radius out of (or, for inside limits, back into) a shape. Shapes live in the space of
//! the points they act on (model space for the chain solver); capsules and planes use the
//! collider's local +Y as their axis and normal.

mod r#box;
mod capsule;
pub(crate) mod entry_lanes;
pub(crate) mod lanes;
mod plane;
mod sphere;
mod tapered;

pub use capsule::{capsule_penetration, push_out_of_capsule};
pub use plane::{plane_penetration, push_above_plane};
pub use r#box::{box_penetration, push_out_of_box};
pub use sphere::{push_into_sphere, push_out_of_sphere, sphere_penetration};
pub use tapered::{push_out_of_tapered_capsule, tapered_capsule_penetration, Tapered};

use crate::math::Transform;
use glam::{Vec3, Vec4};
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
    /// A capsule along local +Y, centred on the origin, whose radius changes linearly from
    /// `radius0` at its +Y end to `radius1` at its −Y end (KawaiiPhysics' tapered capsule,
    /// and its push-out rule: see [`push_out_of_tapered_capsule`]).
    TaperedCapsule {
        /// Radius at the +Y end, metres (≥ 0).
        radius0: f32,
        /// Radius at the −Y end, metres (≥ 0).
        radius1: f32,
        /// Distance between the two ends' centres, metres (≥ 0).
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
            Shape::TaperedCapsule {
                radius0,
                radius1,
                length,
            } if ![radius0, radius1, length]
                .iter()
                .all(|v| v.is_finite() && *v >= 0.0) =>
            {
                bad(format!(
                    "{what}: tapered capsule radius0 {radius0}, radius1 {radius1} and length \
                     {length} must be finite and ≥ 0"
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

/// The distance of the entry surface a swept test uses: `limit` less the
/// [`contact_tolerance`] (never below 0).
pub(crate) fn entry_radius(limit: f32) -> f32 {
    (limit - contact_tolerance(limit)).max(0.0)
}

/// The colliders of a list (by position in it) that may act on a point inside one box
/// (by their [`PlacedCollider::bound_sphere`]); positions from 64 on always may.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct NearSet(u64);

impl NearSet {
    /// The members of `list` (indices into `bounds`, each a collider's
    /// [`PlacedCollider::bound_sphere`]) that may touch the box `lo`–`hi` for a point of
    /// radius `r`: all unless the box is farther from the bounding sphere than `r` plus a
    /// margin well above the f32 rounding of the narrow phases (1e-4 m, and 1e-5 of the
    /// size and distance from the origin of the collider and of the box). A non-finite
    /// box or radius may touch everything.
    pub(crate) fn of(list: &[usize], bounds: &[Vec4], lo: Vec3, hi: Vec3, r: f32) -> NearSet {
        if !(lo.is_finite() && hi.is_finite() && r.is_finite()) {
            return NearSet(u64::MAX);
        }
        // The point's part of the margin.
        let extra = r + 1e-5 * (lo.abs().max(hi.abs()).max_element() + r);
        let mut bits = 0u64;
        for (i, &k) in list.iter().take(64).enumerate() {
            let b = bounds[k];
            let c = b.truncate();
            let d = (lo - c).max(c - hi).max(Vec3::ZERO);
            let reach = b.w + extra;
            // Without a branch: which colliders are near changes from point to point.
            bits |= u64::from(d.length_squared() <= reach * reach) << i;
        }
        NearSet(bits)
    }

    /// Whether the list's member at position `i` may act.
    #[inline]
    pub(crate) fn contains(self, i: usize) -> bool {
        i >= 64 || self.0 & (1 << i) != 0
    }

    /// `x0` resolved against the members of `list` in order, as
    /// [`PlacedCollider::resolve`] with the step start `prev` (`None`: each collider's
    /// own input, a point at rest), skipping the colliders outside the set while the
    /// point is still `x0`. Same bits as asking every collider when `x0` and `prev` lie
    /// in the set's box: a skipped collider would give such a point back unchanged, and
    /// once a nearer one moved it (perhaps out of the box) every later one is asked.
    #[inline]
    pub(crate) fn resolve(
        self,
        list: &[usize],
        colliders: &[PlacedCollider],
        x0: Vec3,
        prev: Option<Vec3>,
        r: f32,
    ) -> Vec3 {
        let mut x = x0;
        for (i, &c) in list.iter().enumerate() {
            if self.contains(i) || x != x0 {
                x = colliders[c].resolve(x, prev.unwrap_or(x), r);
            }
        }
        x
    }
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
            Shape::TaperedCapsule {
                radius0,
                radius1,
                length,
            } => {
                let tapered = self.tapered_of(radius0, radius1, length, r);
                push_out_of_tapered_capsule(p, prev, &tapered, t.rotation * Vec3::X)
            }
            Shape::Box { half_extents } => push_out_of_box(p, t, half_extents, r),
            Shape::Plane => push_above_plane(p, prev, t.translation, t.rotation * Vec3::Y, r),
        }
    }

    /// The collider moved a share `w` of the way from `self` to `other` (shape of `other`);
    /// from `w = 1` on, `other` exactly (as the chains' path of the character's transform
    /// gives its newest frame there): a step that ends with its frame sees that frame's
    /// colliders, not a slerp's rounding of them.
    pub fn lerp(&self, other: &PlacedCollider, w: f32) -> PlacedCollider {
        if w >= 1.0 {
            return *other;
        }
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
            Shape::TaperedCapsule {
                radius0,
                radius1,
                length,
            } => tapered_capsule_penetration(p, &self.tapered_of(radius0, radius1, length, r)),
            Shape::Box { half_extents } => box_penetration(p, t, half_extents, r),
            Shape::Plane => plane_penetration(p, t.translation, t.rotation * Vec3::Y, r),
        }
    }

    /// False only when [`PlacedCollider::resolve`] provably gives back its input for a
    /// point of radius `r` at any `p` and `prev` inside the box `lo`–`hi` (so also for any
    /// step between two such points): the box is farther from the shape's bounding
    /// sphere than the point's radius plus a margin well above f32 rounding. A broad
    /// phase: the solvers skip colliders that cannot act and get the same bits. Planes,
    /// inside limits and non-finite boxes always may touch.
    #[cfg(test)]
    pub(crate) fn may_touch_box(&self, lo: Vec3, hi: Vec3, r: f32) -> bool {
        NearSet::of(&[0], &[self.bound_sphere()], lo, hi, r).contains(0)
    }

    /// The broad phase's sphere ([`NearSet`]): the shape's centre in `xyz`; in `w` the
    /// radius of a sphere about it that holds the shape, plus the collider's part of the
    /// margin for rounding (1e-4 m and 1e-5 of its size and distance from the origin);
    /// infinite for planes, inside limits and a non-finite placement, which act
    /// everywhere. The solvers keep one per collider and step.
    pub(crate) fn bound_sphere(&self) -> Vec4 {
        let c = self.transform.translation;
        let w = match self.bounding_radius() {
            Some(bound) if c.is_finite() => bound + 1e-4 + 1e-5 * (c.abs().max_element() + bound),
            _ => f32::INFINITY,
        };
        c.extend(w)
    }

    /// Radius of a sphere about the origin that holds the shape (`None` for planes and
    /// inside limits, which act everywhere).
    pub(crate) fn bounding_radius(&self) -> Option<f32> {
        match self.shape {
            Shape::Sphere {
                radius,
                inside: false,
            } => Some(radius),
            Shape::Capsule { radius, length } => Some(radius + 0.5 * length),
            Shape::TaperedCapsule {
                radius0,
                radius1,
                length,
            } => Some(radius0.max(radius1) + 0.5 * length),
            Shape::Box { half_extents } => Some(half_extents.length()),
            _ => None,
        }
    }

    /// A tapered capsule placed, for a point of radius `r`: its +Y end (`radius0`) first.
    /// `None` for other shapes.
    pub fn tapered(&self, r: f32) -> Option<Tapered> {
        let Shape::TaperedCapsule {
            radius0,
            radius1,
            length,
        } = self.shape
        else {
            return None;
        };
        Some(self.tapered_of(radius0, radius1, length, r))
    }

    fn tapered_of(&self, radius0: f32, radius1: f32, length: f32, r: f32) -> Tapered {
        let (b, a) = self.capsule_ends(length);
        Tapered {
            a,
            b,
            radius0,
            radius1,
            point: r,
        }
    }

    pub(crate) fn capsule_ends(&self, length: f32) -> (Vec3, Vec3) {
        let axis = self.transform.rotation * Vec3::Y * (0.5 * length);
        (
            self.transform.translation - axis,
            self.transform.translation + axis,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use glam::Quat;

    /// A collider moved all the way is the end placement bit for bit (a slerp at 1 is
    /// only within a few ulps of it), and halfway is halfway: the translations' mean and
    /// the rotation half the angle about the same axis, computed by hand.
    #[test]
    fn a_collider_moved_all_the_way_is_its_end_placement() {
        let shape = Shape::Capsule {
            radius: 0.04,
            length: 0.2,
        };
        let a = PlacedCollider {
            shape,
            transform: Transform::from_translation_rotation(
                Vec3::new(0.1, -0.2, 0.3),
                Quat::from_rotation_y(0.4),
            ),
        };
        let b = PlacedCollider {
            shape,
            transform: Transform::from_translation_rotation(
                Vec3::new(0.5, 0.2, -0.1),
                Quat::from_rotation_y(1.3),
            ),
        };
        let bits = |c: &PlacedCollider| {
            let t = &c.transform;
            let mut v = t.translation.to_array().to_vec();
            v.extend(t.rotation.to_array());
            v.extend(t.scale.to_array());
            v.into_iter().map(f32::to_bits).collect::<Vec<_>>()
        };
        assert_eq!(bits(&a.lerp(&b, 1.0)), bits(&b));
        assert_eq!(bits(&a.lerp(&b, 1.5)), bits(&b));
        // A slerp at 1 does not give these bits here (so the rule is what gives them).
        let slerped = crate::math::slerp_shortest(a.transform.rotation, b.transform.rotation, 1.0);
        let exact = b.transform.rotation.to_array().map(f32::to_bits);
        assert_ne!(slerped.to_array().map(f32::to_bits), exact);
        let half = a.lerp(&b, 0.5).transform;
        assert!((half.translation - Vec3::new(0.3, 0.0, 0.1)).length() < 1e-6);
        let want = Quat::from_rotation_y(0.85);
        assert!(
            half.rotation.dot(want).abs() > 1.0 - 1e-6,
            "{:?}",
            half.rotation
        );
    }

    /// The broad phase's promise: where `may_touch_box` says no, `resolve` gives back its
    /// input bit for bit for any point and step start in the box. Checked on boxes placed
    /// just beyond the margin around every bounded shape, with points on the box's faces
    /// and corners (the nearest to the shape) and inside it, and steps across it.
    #[test]
    fn a_collider_that_cannot_touch_a_box_gives_back_every_point_in_it() {
        let mut rng = SplitMix64::new(7);
        let mut u = |lo: f32, hi: f32| rng.range_f32(lo, hi);
        let (mut far, mut near) = (0, 0);
        for case in 0..4000 {
            let shape = match case % 3 {
                0 => Shape::Sphere {
                    radius: u(0.0, 0.3),
                    inside: false,
                },
                1 => Shape::Capsule {
                    radius: u(0.0, 0.2),
                    length: u(0.0, 0.6),
                },
                _ => Shape::Box {
                    half_extents: Vec3::new(u(0.0, 0.2), u(0.0, 0.2), u(0.0, 0.2)),
                },
            };
            let axis = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)).normalize_or(Vec3::Y);
            let placed = |offset: Vec3| PlacedCollider {
                shape,
                transform: Transform::from_translation_rotation(
                    offset,
                    Quat::from_axis_angle(axis, case as f32 * 0.37),
                ),
            };
            let centre = Vec3::new(u(-3.0, 3.0), u(-3.0, 3.0), u(-3.0, 3.0));
            let col = placed(centre);
            let r = u(0.0, 0.05);
            // A box whose nearest corner or face lies at a chosen distance from the centre.
            let dir = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)).normalize_or(Vec3::X);
            let bound = col.bounding_radius().unwrap();
            let gap = bound + r + u(-0.01, 0.02);
            let size = Vec3::new(u(0.0, 0.4), u(0.0, 0.4), u(0.0, 0.4));
            let corner = centre + dir * gap;
            // Grow the box away from the shape on every axis.
            let away = dir.signum();
            let other = corner + away * size;
            let (lo, hi) = (corner.min(other), corner.max(other));
            if col.may_touch_box(lo, hi, r) {
                near += 1;
                continue;
            }
            far += 1;
            let mut pick = |face: bool| {
                let mut q = Vec3::new(u(0.0, 1.0), u(0.0, 1.0), u(0.0, 1.0));
                if face {
                    // Snap one or more coordinates onto the face nearest the shape.
                    for k in 0..3 {
                        if u(0.0, 1.0) < 0.6 {
                            q[k] = if away[k] > 0.0 { 0.0 } else { 1.0 };
                        }
                    }
                }
                lo + (hi - lo) * q
            };
            for _ in 0..8 {
                let (p, prev) = (pick(true), pick(true));
                assert_eq!(col.resolve(p, prev, r), p, "case {case}: {shape:?}");
                let (p, prev) = (pick(false), pick(true));
                assert_eq!(col.resolve(p, prev, r), p, "case {case}: {shape:?}");
                assert_eq!(col.resolve(p, p, r), p, "case {case}: {shape:?}");
            }
        }
        // Both answers were exercised.
        assert!(far > 1000 && near > 300, "far {far}, near {near}");
        // Planes and inside limits act everywhere; a non-finite box is never skipped.
        let plane = PlacedCollider {
            shape: Shape::Plane,
            transform: Transform::IDENTITY,
        };
        assert!(plane.may_touch_box(Vec3::splat(50.0), Vec3::splat(60.0), 0.0));
        let sphere = PlacedCollider {
            shape: Shape::Sphere {
                radius: 0.1,
                inside: false,
            },
            transform: Transform::IDENTITY,
        };
        assert!(!sphere.may_touch_box(Vec3::splat(50.0), Vec3::splat(60.0), 0.0));
        assert!(sphere.may_touch_box(Vec3::new(f32::NAN, 50.0, 50.0), Vec3::splat(60.0), 0.0));
        let lost = PlacedCollider {
            transform: Transform::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)),
            ..sphere
        };
        assert!(lost.may_touch_box(Vec3::splat(50.0), Vec3::splat(60.0), 0.0));
        // A box touching the inflated sphere is never skipped.
        assert!(sphere.may_touch_box(Vec3::new(0.12, -1.0, -1.0), Vec3::splat(1.0), 0.03));
    }

    #[test]
    fn near_sets_hold_the_colliders_that_may_touch_and_every_one_from_64_on() {
        let at = |x: f32| PlacedCollider {
            shape: Shape::Sphere {
                radius: 0.1,
                inside: false,
            },
            transform: Transform::from_translation(Vec3::new(x, 0.0, 0.0)),
        };
        let colliders: Vec<PlacedCollider> = (0..70).map(|i| at(i as f32)).collect();
        let bounds: Vec<Vec4> = colliders.iter().map(|c| c.bound_sphere()).collect();
        let list: Vec<usize> = (0..70).rev().collect(); // list position i is collider 69 - i
        let set = NearSet::of(
            &list,
            &bounds,
            Vec3::new(-0.05, -0.05, -0.05),
            Vec3::splat(0.05),
            0.0,
        );
        for i in 0..70 {
            assert_eq!(set.contains(i), i == 69 || i >= 64, "position {i}");
        }
    }
}
