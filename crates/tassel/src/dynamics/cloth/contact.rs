//! Cloth contacts beyond single points: segments and quad surfaces against spheres and
//! capsules.

use super::settings::SurfaceCollision;
use crate::collide::{PlacedCollider, Shape};
use crate::math::{
    closest_params_segment_segment, closest_point_on_segment, closest_point_on_triangle,
    normalize_or,
};
use glam::Vec3;

/// A keep-out sphere or capsule as a core segment (equal ends for a sphere) and a radius.
/// Other shapes (boxes, planes, keep-inside spheres) only act on points.
pub(crate) fn core(col: &PlacedCollider) -> Option<(Vec3, Vec3, f32)> {
    let t = &col.transform;
    match col.shape {
        Shape::Sphere {
            radius,
            inside: false,
        } => Some((t.translation, t.translation, radius)),
        Shape::Capsule { radius, length } => {
            let axis = t.rotation * Vec3::Y * (0.5 * length);
            Some((t.translation - axis, t.translation + axis, radius))
        }
        _ => None,
    }
}

/// Moves the free ends of segment `a`–`b` so that it is at least `radius` from the core
/// segment `e0`–`e1`. `free` says which ends may move. Returns whether it touched.
pub(crate) fn push_segment(
    a: &mut Vec3,
    b: &mut Vec3,
    free: [bool; 2],
    (e0, e1, radius): (Vec3, Vec3, f32),
) -> bool {
    let (s, t) = closest_params_segment_segment(*a, *b, e0, e1);
    let q = *a + (*b - *a) * s;
    let c = e0 + (e1 - e0) * t;
    let d = q - c;
    let dist = d.length();
    if dist >= radius {
        return false;
    }
    let fallback = normalize_or((*b - *a).any_orthonormal_vector(), Vec3::Y);
    let n = normalize_or(d, fallback);
    let depth = radius - dist;
    match free {
        [true, true] => {
            *a += n * depth;
            *b += n * depth;
        }
        // Only one end moves: the closest point moves by its share, so move that end more
        // (at most five times the depth, near the fixed end).
        [false, true] => *b += n * (depth / s.max(0.2)),
        [true, false] => *a += n * (depth / (1.0 - s).max(0.2)),
        [false, false] => return false,
    }
    true
}

/// One triangle of a cloth quad against a core segment. `side` is the pair's memory: the
/// side of the triangle's plane (+1 along its normal, −1 against) the collider was on when
/// they last met, 0 when unknown.
pub(crate) fn push_triangle(
    p: [&mut Vec3; 3],
    free: [bool; 3],
    (e0, e1, radius): (Vec3, Vec3, f32),
    mode: SurfaceCollision,
    side: &mut i8,
) {
    if mode == SurfaceCollision::Off || !free.iter().any(|f| *f) {
        return;
    }
    let (p0, p1, p2) = (*p[0], *p[1], *p[2]);
    let normal = (p1 - p0).cross(p2 - p0);
    if normal.length_squared() < 1e-14 {
        return;
    }
    let normal = normal.normalize();
    // Cheap reject: the core is farther from the triangle's bounding sphere than the
    // radius. The side memory still learns where the collider is.
    let centroid = (p0 + p1 + p2) / 3.0;
    let bound = (p0 - centroid)
        .length_squared()
        .max((p1 - centroid).length_squared())
        .max((p2 - centroid).length_squared())
        .sqrt();
    let near = closest_point_on_segment(centroid, e0, e1);
    if (near - centroid).length() > bound + radius {
        *side = if normal.dot(near - p0) >= 0.0 { 1 } else { -1 };
        return;
    }
    // Closest points between the core and the triangle: alternating projections between
    // the two convex sets (a sphere's core is a point, done in one).
    let mut c = near;
    let mut q = closest_point_on_triangle(c, p0, p1, p2);
    if e0 != e1 {
        for _ in 0..4 {
            let next = closest_point_on_segment(q, e0, e1);
            if same_bits(next, c) {
                // A fixed point: every later round would give these same bits.
                break;
            }
            c = next;
            q = closest_point_on_triangle(c, p0, p1, p2);
        }
    }
    let signed = normal.dot(c - p0);
    let dist = (c - q).length();
    let over_face = (c - normal * signed - q).length_squared() < 1e-10;
    let current: i8 = if signed >= 0.0 { 1 } else { -1 };
    let shift = if mode == SurfaceCollision::PushPull && over_face && signed.abs() < 2.0 * radius {
        // Engaged: the collider must stay on its remembered side, `radius` away.
        let sigma = if *side != 0 { *side } else { current };
        *side = sigma;
        let violation = radius - sigma as f32 * signed;
        if violation <= 0.0 {
            return;
        }
        -normal * (sigma as f32 * violation)
    } else {
        if dist > radius {
            *side = current;
            return;
        }
        let away = normalize_or(q - c, normal * current as f32 * -1.0);
        away * (radius - dist)
    };
    let movable = free.iter().filter(|f| **f).count() as f32;
    // With fixed corners the free ones move more, so the contact point still clears.
    let gain = 3.0 / movable;
    for (v, f) in p.into_iter().zip(free) {
        if f {
            *v += shift * gain;
        }
    }
}

/// Whether two vectors are the same bits (unlike `==`, which takes −0 for 0).
fn same_bits(a: Vec3, b: Vec3) -> bool {
    a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
}
