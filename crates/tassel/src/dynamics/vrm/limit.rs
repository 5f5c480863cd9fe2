//! `VRMC_springBone_limit` (VRM, draft 1.0 of January 2026): cone, hinge and spherical
//! limits on how far a spring joint may swing.
//!
//! A limit lives in a frame of its own under the joint's parent: the joint's rest local
//! rotation, turned by the shortest arc from +Y to the bone axis (the draft's
//! `axisRotation`; a 180° turn about X when the bone points down −Y), then by the limit's
//! `rotation`. In that frame the limit's shapes are around +Y:
//!
//! - **cone**: the head→tail direction stays within `angle` of +Y;
//! - **hinge**: it stays in the YZ plane (turns about X only) and within `angle` of +Y;
//! - **spherical**: its pitch (about X, `atan2(z, y)`) stays within `±pitch` and its yaw
//!   (toward X, `asin(x)`) within `±yaw`.
//!
//! The solver applies the limit where the draft recommends: right after the inertia step
//! (with the bone length) and after each collider push; in fixed mode also after the
//! exact settling of a contact (`dynamics/vrm/job.rs`). A direction already inside its limit
//! is left as it is, bit for bit (the draft's code recomputes it, which changes only the
//! last bits). The draft's degenerate cases are resolved as follows: a direction exactly
//! opposite the cone's axis goes to the cone's +Z edge; a direction along the hinge's axis
//! (±X) goes to +Y; angles at or past π (yaw: π/2) are read as π (π/2), as the draft says.

use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};
use std::f32::consts::{FRAC_PI_2, PI};

/// The shape of a [`VrmLimit`]: angles in radians, measured from the limit's +Y axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VrmLimitShape {
    /// The bone stays within `angle` of the axis (0..=π; π is no limit).
    Cone {
        /// Half-angle of the cone, radians (≥ 0; read as π past π).
        angle: f32,
    },
    /// The bone turns about the limit's X axis only, within `angle` of the axis either
    /// way (0..=π; π is a whole disc).
    Hinge {
        /// Largest turn either way, radians (≥ 0; read as π past π).
        angle: f32,
    },
    /// The bone's pitch (about X) stays within `±pitch`, its yaw (toward X) within `±yaw`.
    Spherical {
        /// Largest pitch either way, radians (≥ 0; read as π past π).
        pitch: f32,
        /// Largest yaw either way, radians (≥ 0; read as π/2 past π/2).
        yaw: f32,
    },
}

/// A limit on a VRM spring joint's swing (`VRMC_springBone_limit`), as the file gives it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct VrmLimit {
    /// Its shape and angles.
    pub shape: VrmLimitShape,
    /// Its turn from the default orientation (the draft's `rotation`, x y z w; identity by
    /// default).
    pub rotation: Quat,
}

impl VrmLimit {
    /// A limit of `shape` in its default orientation.
    pub fn new(shape: VrmLimitShape) -> Self {
        Self {
            shape,
            rotation: Quat::IDENTITY,
        }
    }

    /// Checks the angles (finite, ≥ 0) and the rotation (finite, not zero); the message
    /// names the value.
    pub fn check(&self) -> std::result::Result<(), String> {
        let angles: &[(&str, f32)] = match self.shape {
            VrmLimitShape::Cone { angle } => &[("cone angle", angle)],
            VrmLimitShape::Hinge { angle } => &[("hinge angle", angle)],
            VrmLimitShape::Spherical { pitch, yaw } => {
                &[("spherical pitch", pitch), ("spherical yaw", yaw)]
            }
        };
        for &(what, v) in angles {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("limit {what} {v} must be finite and ≥ 0 (radians)"));
            }
        }
        let q = self.rotation;
        if !q.is_finite() || q.length_squared() < 1e-12 {
            return Err(format!(
                "limit rotation {q} must be a finite, non-zero quaternion"
            ));
        }
        Ok(())
    }
}

/// What a compiled limit tests in its frame (angles clamped, cosines and sines ready).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Bound {
    Cone { cos: f32, sin: f32 },
    Hinge { cos: f32, sin: f32 },
    Spherical { pitch: f32, yaw: f32 },
}

/// A [`VrmLimit`] compiled for its link.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkLimit {
    /// The limit's frame relative to the joint's parent: rest local rotation ·
    /// `axisRotation` · `rotation` (unit).
    pub frame: Quat,
    pub(crate) bound: Bound,
}

/// The draft's `axisRotation`: the shortest turn from +Y to `axis` (unit), or 180° about X
/// when `axis` is (nearly) −Y.
pub fn axis_rotation(axis: Vec3) -> Quat {
    let dot = axis.y;
    if dot + 1.0 < 1e-8 {
        Quat::from_xyzw(1.0, 0.0, 0.0, 0.0)
    } else {
        Quat::from_xyzw(axis.z, 0.0, -axis.x, dot + 1.0).normalize()
    }
}

impl LinkLimit {
    /// `limit` (checked) for a joint with rest local rotation `rest_rotation` and bone axis
    /// `bone_axis` (unit, joint-local).
    pub fn new(limit: &VrmLimit, rest_rotation: Quat, bone_axis: Vec3) -> Self {
        let frame =
            (rest_rotation * axis_rotation(bone_axis) * limit.rotation.normalize()).normalize();
        let cs = |a: f32| {
            let a = a.min(PI);
            (a.cos(), a.sin())
        };
        let bound = match limit.shape {
            VrmLimitShape::Cone { angle } => {
                let (cos, sin) = cs(angle);
                Bound::Cone { cos, sin }
            }
            VrmLimitShape::Hinge { angle } => {
                let (cos, sin) = cs(angle);
                Bound::Hinge { cos, sin }
            }
            VrmLimitShape::Spherical { pitch, yaw } => Bound::Spherical {
                pitch: pitch.min(PI),
                yaw: yaw.min(FRAC_PI_2),
            },
        };
        Self { frame, bound }
    }

    /// The tail (world) kept within the limit: `tail` itself when its direction from
    /// `position` is inside, else `position` plus the limited direction times `length`.
    /// `parent_rotation` is the joint's parent's world rotation.
    #[inline]
    pub fn apply(&self, parent_rotation: Quat, position: Vec3, tail: Vec3, length: f32) -> Vec3 {
        let frame = parent_rotation * self.frame;
        let d = frame.inverse() * (tail - position);
        let len2 = d.length_squared();
        if !(len2 > 1e-20 && len2.is_finite()) {
            return tail;
        }
        match self.bound.clamp(d / len2.sqrt()) {
            Some(limited) => position + (frame * limited) * length,
            None => tail,
        }
    }

    /// [`LinkLimit::outline`] in world space: the boundary at `length` from the joint at
    /// `position`, whose parent's world rotation is `parent_rotation`.
    pub fn outline_world(
        &self,
        parent_rotation: Quat,
        position: Vec3,
        length: f32,
        n: usize,
    ) -> Vec<Vec3> {
        let frame = parent_rotation * self.frame;
        self.outline(n)
            .into_iter()
            .map(|d| position + frame * d * length)
            .collect()
    }

    /// Points on the limit's boundary as unit directions in its frame (`n` of them), for
    /// drawing: the cone's rim, the hinge's arc, the spherical box's outline.
    pub fn outline(&self, n: usize) -> Vec<Vec3> {
        let n = n.max(4);
        let t = |k: usize| k as f32 / (n - 1) as f32;
        match self.bound {
            Bound::Cone { cos, sin } => (0..n)
                .map(|k| {
                    let a = std::f32::consts::TAU * t(k);
                    Vec3::new(sin * a.cos(), cos, sin * a.sin())
                })
                .collect(),
            Bound::Hinge { cos, sin } => {
                let reach = sin.atan2(cos);
                (0..n)
                    .map(|k| {
                        let a = -reach + 2.0 * reach * t(k);
                        Vec3::new(0.0, a.cos(), a.sin())
                    })
                    .collect()
            }
            Bound::Spherical { pitch, yaw } => {
                // The box's four edges, walked around.
                let at = |p: f32, y: f32| Vec3::new(y.sin(), y.cos() * p.cos(), y.cos() * p.sin());
                let q = n / 4;
                let s = |k: usize| -1.0 + 2.0 * k as f32 / q.max(1) as f32;
                let mut out = Vec::with_capacity(4 * q + 1);
                out.extend((0..q).map(|k| at(pitch * s(k), -yaw)));
                out.extend((0..q).map(|k| at(pitch, yaw * s(k))));
                out.extend((0..q).map(|k| at(-pitch * s(k), yaw)));
                out.extend((0..q).map(|k| at(-pitch, -yaw * s(k))));
                out.push(at(-pitch, -yaw));
                out
            }
        }
    }
}

impl Bound {
    /// The direction `d` (unit, limit frame) moved into the limit, or `None` when it is
    /// inside.
    #[inline]
    pub(crate) fn clamp(&self, d: Vec3) -> Option<Vec3> {
        match *self {
            Bound::Cone { cos, sin } => {
                if d.y >= cos {
                    return None;
                }
                // The draft scales x and z by sin(angle) / sqrt(1 − y²): the same ratio,
                // with the denominator taken from x and z (exact near the axis, where
                // 1 − y² loses its digits).
                let off = (d.x * d.x + d.z * d.z).sqrt();
                if off <= 1e-6 {
                    // Straight against the axis: every rim point is as near; take +Z's.
                    return Some(Vec3::new(0.0, cos, sin));
                }
                let ratio = sin / off;
                Some(Vec3::new(d.x * ratio, cos, d.z * ratio))
            }
            Bound::Hinge { cos, sin } => {
                if d.x == 0.0 && d.y >= cos {
                    return None;
                }
                let planar = d.y * d.y + d.z * d.z;
                if planar <= 1e-12 {
                    // Along the hinge's axis: the plane's nearest points are a whole
                    // circle; take the limit's axis.
                    return Some(Vec3::Y);
                }
                let p = Vec3::new(0.0, d.y, d.z) / planar.sqrt();
                if p.y >= cos {
                    return Some(p);
                }
                Some(Vec3::new(0.0, cos, if p.z < 0.0 { -sin } else { sin }))
            }
            Bound::Spherical { pitch, yaw } => {
                let p = d.z.atan2(d.y);
                let y = d.x.clamp(-1.0, 1.0).asin();
                if p.abs() <= pitch && y.abs() <= yaw {
                    return None;
                }
                let p = p.clamp(-pitch, pitch);
                let y = y.clamp(-yaw, yaw);
                Some(Vec3::new(y.sin(), y.cos() * p.cos(), y.cos() * p.sin()))
            }
        }
    }
}
