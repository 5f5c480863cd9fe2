//! The Unreal math SPCR's update leans on, with its tolerances in metres: what a clamp
//! does with NaN, when a normal is zero, how a rotation between two directions is built.

use glam::{DQuat, DVec3};

/// SPCR's `SPCR_EPSILON` (1e-4) on squared centimetres, in square metres.
pub(super) const EPS_SQ: f64 = 1e-8;
/// SPCR's 0.001 cm² below which a capsule's radial push is skipped, in square metres.
pub(super) const CAPSULE_EPS_SQ: f64 = 1e-7;
/// Unreal's `SMALL_NUMBER` (1e-8) on squared centimetres (`GetSafeNormal`), in m².
pub(super) const SAFE_SQ: f64 = 1e-12;
/// A capsule shorter than this (SPCR_EPSILON cm) is a sphere, as SPCR's `bCapsule`.
pub(super) const CAPSULE_MIN_HEIGHT: f64 = 1e-6;
/// A ray that enters a triangle's plane nearer than this (0.001 cm) misses it.
pub(super) const ENTER_MIN: f64 = 1e-5;

/// SPCR wraps its wind phase at this written-out π, not at `std::f64::consts::PI`.
#[allow(clippy::approx_constant)]
pub(super) const SPCR_PI: f64 = 3.141592;

/// Unreal's `FMath::Clamp`: `x < lo ? lo : x < hi ? x : hi` (NaN gives `hi`).
#[inline]
pub(super) fn ue_clamp(x: f64, lo: f64, hi: f64) -> f64 {
    if x < lo {
        lo
    } else if x < hi {
        x
    } else {
        hi
    }
}

/// Unreal's `GetSafeNormal`: zero below its tolerance.
#[inline]
pub(super) fn safe_normal(v: DVec3) -> DVec3 {
    let sq = v.length_squared();
    if sq == 1.0 {
        v
    } else if sq < SAFE_SQ {
        DVec3::ZERO
    } else {
        v / sq.sqrt()
    }
}

/// Unreal's `FVector::Normalize`: unchanged below its tolerance.
#[inline]
pub(super) fn normalized(v: DVec3) -> DVec3 {
    let sq = v.length_squared();
    if sq > SAFE_SQ {
        v / sq.sqrt()
    } else {
        v
    }
}

/// Unreal's `FMath::Lerp`.
#[inline]
pub(super) fn lerp(a: DVec3, b: DVec3, t: f64) -> DVec3 {
    a + (b - a) * t
}

/// Unreal's `FQuat::FindBetweenNormals`.
pub(super) fn find_between_normals(a: DVec3, b: DVec3) -> DQuat {
    let w = 1.0 + a.dot(b);
    let q = if w >= 1e-6 {
        let c = a.cross(b);
        glam::DVec4::new(c.x, c.y, c.z, w)
    } else if a.x.abs() > a.y.abs() {
        glam::DVec4::new(-a.z, 0.0, a.x, 0.0)
    } else {
        glam::DVec4::new(0.0, -a.z, a.y, 0.0)
    };
    let len_sq = q.length_squared();
    if len_sq > 1e-8 {
        DQuat::from_vec4(q / len_sq.sqrt())
    } else {
        DQuat::IDENTITY
    }
}

/// Unreal's `FVector::RotateAngleAxis` (degrees).
pub(super) fn rotate_angle_axis(v: DVec3, degrees: f64, axis: DVec3) -> DVec3 {
    let (s, c) = degrees.to_radians().sin_cos();
    let (x, y, z) = (axis.x, axis.y, axis.z);
    let omc = 1.0 - c;
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let (xy, yz, zx) = (x * y, y * z, z * x);
    let (xs, ys, zs) = (x * s, y * s, z * s);
    DVec3::new(
        (omc * xx + c) * v.x + (omc * xy - zs) * v.y + (omc * zx + ys) * v.z,
        (omc * xy + zs) * v.x + (omc * yy + c) * v.y + (omc * yz - xs) * v.z,
        (omc * zx - ys) * v.x + (omc * yz + xs) * v.y + (omc * zz + c) * v.z,
    )
}
