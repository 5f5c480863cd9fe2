//! Small math helpers on top of glam: a TRS [`Transform`], the shortest-arc rotation and
//! safe normalisation used throughout the solvers.

use glam::{Mat4, Quat, Vec3};
use serde::{Deserialize, Serialize};

/// A translation, rotation and (possibly non-uniform) scale, applied as scale, then
/// rotation, then translation, like a glTF node.
///
/// Composition follows the usual game-engine rule (scale does not shear);
/// `(a * b).relative_to(&a) == b` holds for any `b`, and `a.inverse() * (a * b) == b` when
/// `a`'s scale is uniform.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// Translation, in the parent's units (metres for glTF files).
    pub translation: Vec3,
    /// Rotation (unit quaternion).
    pub rotation: Quat,
    /// Scale per local axis.
    pub scale: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Transform {
    /// The transform that changes nothing.
    pub const IDENTITY: Transform = Transform {
        translation: Vec3::ZERO,
        rotation: Quat::IDENTITY,
        scale: Vec3::ONE,
    };

    /// A transform from its three parts.
    pub fn new(translation: Vec3, rotation: Quat, scale: Vec3) -> Self {
        Self {
            translation,
            rotation,
            scale,
        }
    }

    /// A pure translation.
    pub fn from_translation(translation: Vec3) -> Self {
        Self {
            translation,
            ..Self::IDENTITY
        }
    }

    /// A translation and a rotation, unit scale.
    pub fn from_translation_rotation(translation: Vec3, rotation: Quat) -> Self {
        Self {
            translation,
            rotation,
            scale: Vec3::ONE,
        }
    }

    /// Maps a point from this transform's local space to its parent space.
    #[inline]
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        self.translation + self.rotation * (self.scale * p)
    }

    /// Maps a direction (no translation) from local to parent space.
    #[inline]
    pub fn transform_vector(&self, v: Vec3) -> Vec3 {
        self.rotation * (self.scale * v)
    }

    /// Maps a point from parent space back into this transform's local space.
    #[inline]
    pub fn inverse_transform_point(&self, p: Vec3) -> Vec3 {
        (self.rotation.inverse() * (p - self.translation)) / self.scale
    }

    /// The inverse under this type's composition rule (exact for uniform scale; use
    /// [`Transform::relative_to`] for the exact model→local step).
    pub fn inverse(&self) -> Transform {
        let inv_r = self.rotation.inverse();
        let inv_s = self.scale.recip();
        Transform {
            translation: inv_s * (inv_r * -self.translation),
            rotation: inv_r,
            scale: inv_s,
        }
    }

    /// `self * child`: the child's transform expressed in this transform's parent space.
    #[inline]
    pub fn mul_transform(&self, child: &Transform) -> Transform {
        Transform {
            translation: self.transform_point(child.translation),
            rotation: (self.rotation * child.rotation).normalize(),
            scale: self.scale * child.scale,
        }
    }

    /// `parent.inverse() * self`, computed directly: this model-space transform seen from
    /// `parent`'s space.
    #[inline]
    pub fn relative_to(&self, parent: &Transform) -> Transform {
        let inv_r = parent.rotation.inverse();
        Transform {
            translation: (inv_r * (self.translation - parent.translation)) / parent.scale,
            rotation: (inv_r * self.rotation).normalize(),
            scale: self.scale / parent.scale,
        }
    }

    /// The 4×4 matrix of this transform.
    pub fn to_mat4(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }

    /// Linear blend of translation and scale, shortest-path slerp of rotation.
    pub fn lerp(&self, other: &Transform, t: f32) -> Transform {
        Transform {
            translation: self.translation.lerp(other.translation, t),
            rotation: slerp_shortest(self.rotation, other.rotation, t),
            scale: self.scale.lerp(other.scale, t),
        }
    }

    /// True when every component is finite.
    pub fn is_finite(&self) -> bool {
        self.translation.is_finite() && self.rotation.is_finite() && self.scale.is_finite()
    }

    /// Finite, a unit rotation (length within 10 %: a quaternion far from unit length
    /// scales every vector it turns), and every translation coordinate and scale factor
    /// within [`crate::limits::MAX_COORDINATE`]: the range Tassel accepts as input.
    #[inline]
    pub fn within_limits(&self) -> bool {
        // Every comparison with NaN is false and infinity is beyond the limit, so these
        // also reject what is not finite; `&` rather than `&&`: no branch per component.
        let max = crate::limits::MAX_COORDINATE;
        let (t, s) = (self.translation.abs(), self.scale.abs());
        ((self.rotation.length_squared() - 1.0).abs() <= 0.21)
            & (t.x <= max)
            & (t.y <= max)
            & (t.z <= max)
            & (s.x <= max)
            & (s.y <= max)
            & (s.z <= max)
    }
}

impl core::ops::Mul for Transform {
    type Output = Transform;
    #[inline]
    fn mul(self, rhs: Transform) -> Transform {
        self.mul_transform(&rhs)
    }
}

/// Whether every transform of `ts` is finite ([`Transform::is_finite`] for all): one pass
/// that ORs a flag per component (an exponent of all ones: infinity or NaN), without a
/// branch per transform, for the solvers' checks of a whole pose.
pub(crate) fn all_finite(ts: &[Transform]) -> bool {
    const EXP: u32 = 0x7f80_0000;
    let bad = |x: f32| u32::from(x.to_bits() & EXP == EXP);
    let any_bad = ts.iter().fold(0, |acc, t| {
        let (v, q, s) = (t.translation, t.rotation, t.scale);
        acc | bad(v.x)
            | bad(v.y)
            | bad(v.z)
            | bad(q.x)
            | bad(q.y)
            | bad(q.z)
            | bad(q.w)
            | bad(s.x)
            | bad(s.y)
            | bad(s.z)
    });
    any_bad == 0
}

/// Slerp that always takes the shorter way round (flips `b` into `a`'s hemisphere).
pub fn slerp_shortest(a: Quat, b: Quat, t: f32) -> Quat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    a.slerp(b, t).normalize()
}

/// Whether two vectors are the same bits (unlike `==`, which takes −0 for 0 and no NaN for
/// itself): what the lane paths compare when they must give the scalar code's bits.
#[inline]
pub(crate) fn same_bits(a: Vec3, b: Vec3) -> bool {
    a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
}

/// Normalises `v`, or returns `fallback` when `v` is too short to have a direction.
#[inline]
pub fn normalize_or(v: Vec3, fallback: Vec3) -> Vec3 {
    let len2 = v.length_squared();
    if len2 > 1e-20 && len2.is_finite() {
        v / len2.sqrt()
    } else {
        fallback
    }
}

/// The smallest rotation that takes direction `from` to direction `to` (both non-zero),
/// exactly: the normalised quaternion (from × to, 1 + from·to) of the unit directions, so
/// that the smallest swings are kept (no dead zone: a turn of 1e-6 rad is a turn of 1e-6
/// rad). Antiparallel inputs (1 + from·to below 1e-7, where that form has no precision
/// left) turn by exactly 180° (w = 0) about an axis perpendicular to `from`. This is the
/// from-to rotation the VRM specification and three.js's `setFromUnitVectors` use.
pub fn rotation_arc(from: Vec3, to: Vec3) -> Quat {
    let a = normalize_or(from, Vec3::Y);
    let b = normalize_or(to, a);
    let w = 1.0 + a.dot(b);
    if w < 1e-7 {
        let axis = a.any_orthonormal_vector();
        return Quat::from_xyzw(axis.x, axis.y, axis.z, 0.0);
    }
    let c = a.cross(b);
    Quat::from_xyzw(c.x, c.y, c.z, w).normalize()
}

/// Closest point to `p` on the segment `a`–`b`.
#[inline]
pub fn closest_point_on_segment(p: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 <= 1e-20 {
        return a;
    }
    let t = ((p - a).dot(ab) / len2).clamp(0.0, 1.0);
    a + ab * t
}

/// Closest points between segments `p1`–`q1` and `p2`–`q2` (Ericson, Real-Time Collision
/// Detection §5.1.9). Returns the parameters `(s, t)` along each segment.
pub fn closest_params_segment_segment(p1: Vec3, q1: Vec3, p2: Vec3, q2: Vec3) -> (f32, f32) {
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let a = d1.dot(d1);
    let e = d2.dot(d2);
    let f = d2.dot(r);
    const EPS: f32 = 1e-12;
    if a <= EPS && e <= EPS {
        return (0.0, 0.0);
    }
    if a <= EPS {
        return (0.0, (f / e).clamp(0.0, 1.0));
    }
    let c = d1.dot(r);
    if e <= EPS {
        return ((-c / a).clamp(0.0, 1.0), 0.0);
    }
    let b = d1.dot(d2);
    let denom = a * e - b * b;
    let mut s = if denom > EPS {
        ((b * f - c * e) / denom).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

/// Closest point to `p` on the triangle `a`, `b`, `c` (Ericson, Real-Time Collision
/// Detection §5.1.5, by Voronoi regions).
pub fn closest_point_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + ab * v;
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + ac * w;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + (c - b) * w;
    }
    let denom = va + vb + vc;
    if denom.abs() < 1e-30 {
        return a;
    }
    let v = vb / denom;
    let w = vc / denom;
    a + ab * v + ac * w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `all_finite` says what `is_finite` on every transform says: for poses of finite
    /// values (the largest and smallest floats among them) and for each component of each
    /// transform in turn made +∞, −∞ or NaN.
    #[test]
    fn all_finite_is_every_transform_finite() {
        let pose: Vec<Transform> = (0..5)
            .map(|i| Transform {
                translation: Vec3::new(f32::MAX, -f32::MAX, i as f32),
                rotation: Quat::from_xyzw(f32::MIN_POSITIVE, 0.0, -0.0, 1.0),
                scale: Vec3::new(1e-45, 1.0, 3e38),
            })
            .collect();
        assert!(all_finite(&pose) && pose.iter().all(Transform::is_finite));
        assert!(all_finite(&[]));
        let mut bad_cases = 0;
        for j in 0..pose.len() {
            for c in 0..10 {
                for v in [f32::INFINITY, f32::NEG_INFINITY, f32::NAN] {
                    let mut p = pose.clone();
                    let t = &mut p[j];
                    match c {
                        0..=2 => t.translation[c] = v,
                        3 => t.rotation.x = v,
                        4 => t.rotation.y = v,
                        5 => t.rotation.z = v,
                        6 => t.rotation.w = v,
                        _ => t.scale[c - 7] = v,
                    }
                    assert!(!p.iter().all(Transform::is_finite));
                    assert!(!all_finite(&p), "joint {j} component {c} value {v}");
                    bad_cases += 1;
                }
            }
        }
        assert_eq!(bad_cases, 5 * 10 * 3);
    }

    /// Small angles by hand: X turned by θ about Z is (0, 0, sin θ/2, cos θ/2), down to
    /// angles far below the old 1 − 1e-7 dead zone (≈ 4.5e-4 rad).
    #[test]
    fn rotation_arc_keeps_tiny_swings() {
        for theta in [1e-6f32, 1e-5, 1e-4, 4e-4, 1e-3, 0.1, 1.0, 3.0] {
            let to = Vec3::new(theta.cos(), theta.sin(), 0.0);
            let q = rotation_arc(Vec3::X, to);
            let want = Quat::from_xyzw(0.0, 0.0, (theta / 2.0).sin(), (theta / 2.0).cos());
            assert!(
                (q.z - want.z).abs() <= 1e-6 * want.z.max(1e-3) + 2e-9
                    && (q.w - want.w).abs() < 1e-6,
                "θ = {theta}: {q} vs {want}"
            );
            assert!((q * Vec3::X - to).length() < 2e-7, "θ = {theta}");
        }
        // Scale does not matter, and from == to is the identity exactly.
        assert_eq!(
            rotation_arc(Vec3::new(0.0, 3.0, 0.0), Vec3::Y),
            Quat::IDENTITY
        );
        let q = rotation_arc(Vec3::X * 5.0, Vec3::new(1e-3, 1.0, 0.0) * 0.1);
        assert!((q * Vec3::X - Vec3::new(1e-3, 1.0, 0.0).normalize()).length() < 2e-7);
    }

    /// 180°: w exactly 0 and `from` taken to `to`. Just short of it (π − 1.6e-3 rad) the turn is
    /// right to f32's precision there: 1 + cos θ ≈ 1.3e-6 carries the rounding of the dot
    /// product (≈ 6e-8), so the axis is exact and the angle within ≈ 1e-4 rad.
    #[test]
    fn rotation_arc_half_turn_is_exact() {
        for from in [Vec3::X, Vec3::Y, Vec3::new(1.0, 2.0, -3.0).normalize()] {
            let q = rotation_arc(from, -from);
            assert_eq!(q.w, 0.0, "{from}");
            assert!((q * from + from).length() < 1e-6, "{from}: {q}");
            assert!((q.length() - 1.0).abs() < 1e-6);
        }
        let near_pi = std::f32::consts::PI - 1.6e-3;
        let to = Vec3::new(near_pi.cos(), near_pi.sin(), 0.0);
        let q = rotation_arc(Vec3::X, to);
        assert!((q * Vec3::X - to).length() < 1e-4, "{q}");
        assert!(q.x == 0.0 && q.y.abs() < 1e-7, "{q}");
    }

    #[test]
    fn inverse_undoes_composition() {
        let a = Transform::new(
            Vec3::new(1.0, 2.0, 3.0),
            Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1),
            Vec3::new(2.0, 0.5, 1.5),
        );
        let b = Transform::new(
            Vec3::new(-0.4, 0.2, 0.9),
            Quat::from_rotation_y(0.5),
            Vec3::splat(1.3),
        );
        let rel = (a * b).relative_to(&a);
        assert!(rel.translation.abs_diff_eq(b.translation, 1e-5));
        assert!(rel.rotation.abs_diff_eq(b.rotation, 1e-5));
        assert!(rel.scale.abs_diff_eq(b.scale, 1e-5));
        let uniform = Transform {
            scale: Vec3::splat(2.0),
            ..a
        };
        let back = uniform.inverse() * (uniform * b);
        assert!(back.translation.abs_diff_eq(b.translation, 1e-5));
        assert!(back.rotation.abs_diff_eq(b.rotation, 1e-5));
    }

    #[test]
    fn rotation_arc_maps_directions() {
        let cases = [
            (Vec3::X, Vec3::Y),
            (Vec3::new(1.0, 2.0, 3.0), Vec3::new(-3.0, 0.5, 0.1)),
            (Vec3::Z, -Vec3::Z),
            (Vec3::Y, Vec3::Y),
        ];
        for (a, b) in cases {
            let q = rotation_arc(a, b);
            assert!(
                (q * a.normalize()).abs_diff_eq(b.normalize(), 1e-5),
                "{a} -> {b}"
            );
        }
    }

    #[test]
    fn slerp_takes_short_way() {
        let a = Quat::from_rotation_z(0.1);
        let b = -Quat::from_rotation_z(0.3); // same rotation, other hemisphere
        let mid = slerp_shortest(a, b, 0.5);
        let expected = Quat::from_rotation_z(0.2);
        assert!(mid.dot(expected).abs() > 1.0 - 1e-6);
    }

    #[test]
    fn segment_segment_closest() {
        // Two perpendicular segments crossing above each other at distance 1.
        let (s, t) = closest_params_segment_segment(
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, -1.0),
            Vec3::new(0.0, 1.0, 1.0),
        );
        assert!((s - 0.5).abs() < 1e-6 && (t - 0.5).abs() < 1e-6);
    }

    #[test]
    fn closest_point_on_triangle_by_region() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        // Above the face: straight down onto it.
        let q = closest_point_on_triangle(Vec3::new(0.2, 0.3, 5.0), a, b, c);
        assert!((q - Vec3::new(0.2, 0.3, 0.0)).length() < 1e-6);
        // Beyond a vertex, beyond an edge, beyond the hypotenuse.
        assert_eq!(
            closest_point_on_triangle(Vec3::new(-1.0, -1.0, 1.0), a, b, c),
            a
        );
        let q = closest_point_on_triangle(Vec3::new(0.5, -2.0, 0.0), a, b, c);
        assert!((q - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-6);
        let q = closest_point_on_triangle(Vec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((q - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
    }
}
