//! Cloth contacts beyond single points: segments and quad surfaces against spheres and
//! capsules.

use super::settings::SurfaceCollision;
use crate::collide::{PlacedCollider, Shape};
use crate::math::{
    closest_params_segment_segment, closest_point_on_segment, closest_point_on_triangle,
    normalize_or, same_bits,
};
use glam::Vec3;

/// A keep-out sphere or capsule as a core segment `e0`–`e1` (equal ends for a sphere) and
/// a radius, with the segment's box `lo`–`hi`. Other shapes (boxes, planes, keep-inside
/// spheres) only act on points.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Core {
    pub e0: Vec3,
    pub e1: Vec3,
    pub radius: f32,
    pub lo: Vec3,
    pub hi: Vec3,
}

impl Core {
    /// The core of `col`, if it has one.
    pub(crate) fn of(col: &PlacedCollider) -> Option<Core> {
        let c = col.transform.translation;
        let (e0, e1, radius) = match col.shape {
            Shape::Sphere {
                radius,
                inside: false,
            } => (c, c, radius),
            Shape::Capsule { radius, length } => {
                let (a, b) = col.capsule_ends(length);
                (a, b, radius)
            }
            _ => return None,
        };
        Some(Core {
            e0,
            e1,
            radius,
            lo: e0.min(e1),
            hi: e0.max(e1),
        })
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

/// What [`push_triangle`] needs of a triangle besides its corners: its unit normal, its
/// centroid and the radius of its bounding sphere about the centroid. Computed once per
/// triangle and kept while its corners stay where they are (the colliders after the first
/// usually leave them), so that each further collider only pays for its own test.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TriangleFrame {
    pub normal: Vec3,
    pub centroid: Vec3,
    pub bound: f32,
}

impl TriangleFrame {
    /// The frame of triangle `p0 p1 p2`; `None` when it is degenerate (no normal), which
    /// [`push_triangle`] leaves alone.
    pub(crate) fn of(p0: Vec3, p1: Vec3, p2: Vec3) -> Option<TriangleFrame> {
        let normal = (p1 - p0).cross(p2 - p0);
        if normal.length_squared() < 1e-14 {
            return None;
        }
        let normal = normal.normalize();
        let centroid = (p0 + p1 + p2) / 3.0;
        let bound = (p0 - centroid)
            .length_squared()
            .max((p1 - centroid).length_squared())
            .max((p2 - centroid).length_squared())
            .sqrt();
        Some(TriangleFrame {
            normal,
            centroid,
            bound,
        })
    }
}

/// One triangle of a cloth quad against a core segment. `frame` is the triangle's
/// [`TriangleFrame`] (of the corners as they are now). `side` is the pair's memory: the
/// side of the triangle's plane (+1 along its normal, −1 against) the collider was on when
/// they last met, 0 when unknown.
pub(crate) fn push_triangle(
    p: [&mut Vec3; 3],
    free: [bool; 3],
    frame: &TriangleFrame,
    (e0, e1, radius): (Vec3, Vec3, f32),
    mode: SurfaceCollision,
    side: &mut i8,
) {
    if mode == SurfaceCollision::Off || !free.iter().any(|f| *f) {
        return;
    }
    let (p0, p1, p2) = (*p[0], *p[1], *p[2]);
    let TriangleFrame {
        normal,
        centroid,
        bound,
    } = *frame;
    // Cheap reject: the core is farther from the triangle's bounding sphere than the
    // radius. The side memory still learns where the collider is.
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

/// Triangle `corners` against each of a cloth's colliders in turn (`cores`, slot by slot;
/// `None`: a collider without a core), as [`push_triangle`] with the pair's side memory
/// `sides[slot]`. Returns the corners moved and whether any collider changed them (by
/// `!=`, collider by collider). The triangle's frame is made once, and again only after
/// a collider moved a corner: the result is that of a frame made afresh per collider.
pub(crate) fn push_triangle_against(
    corners: [Vec3; 3],
    free: [bool; 3],
    r: f32,
    cores: &[Option<Core>],
    mode: SurfaceCollision,
    sides: &mut [i8],
) -> ([Vec3; 3], bool) {
    let frame = TriangleFrame::of(corners[0], corners[1], corners[2]);
    push_triangle_against_from(corners, frame, free, r, cores, mode, sides)
}

/// [`push_triangle_against`] with the triangle's frame already made: `frame` must be
/// [`TriangleFrame::of`] the `corners` (the cloth's lanes make it for several triangles
/// at once, with the same operations).
pub(crate) fn push_triangle_against_from(
    mut corners: [Vec3; 3],
    mut frame: Option<TriangleFrame>,
    free: [bool; 3],
    r: f32,
    cores: &[Option<Core>],
    mode: SurfaceCollision,
    sides: &mut [i8],
) -> ([Vec3; 3], bool) {
    let mut touched = false;
    for (core, side) in cores.iter().zip(sides) {
        let Some(core) = core else { continue };
        // A degenerate triangle is left alone by every collider, so it stays degenerate.
        let Some(f) = &frame else { break };
        let [mut a, mut b, mut c] = corners;
        push_triangle(
            [&mut a, &mut b, &mut c],
            free,
            f,
            (core.e0, core.e1, core.radius + r),
            mode,
            side,
        );
        let moved = [a, b, c];
        touched |= moved != corners;
        if (0..3).any(|i| !same_bits(moved[i], corners[i])) {
            corners = moved;
            frame = TriangleFrame::of(a, b, c);
        }
    }
    (corners, touched)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Transform;
    use crate::rng::SplitMix64;
    use glam::Quat;

    /// The reference: every collider in turn with the triangle's frame made afresh from
    /// the corners as they are (the way the cloth did it before the frame was kept).
    fn one_by_one(
        mut p: [Vec3; 3],
        free: [bool; 3],
        r: f32,
        cores: &[Option<Core>],
        mode: SurfaceCollision,
        sides: &mut [i8],
    ) -> ([Vec3; 3], bool) {
        let mut touched = false;
        for (core, side) in cores.iter().zip(sides) {
            let Some(core) = core else { continue };
            let Some(frame) = TriangleFrame::of(p[0], p[1], p[2]) else {
                continue;
            };
            let [mut a, mut b, mut c] = p;
            let e = (core.e0, core.e1, core.radius + r);
            push_triangle([&mut a, &mut b, &mut c], free, &frame, e, mode, side);
            touched |= [a, b, c] != p;
            p = [a, b, c];
        }
        (p, touched)
    }

    /// Keeping the triangle's frame across colliders gives the bits of a frame made for
    /// each collider: corners, touch flag and side memory, over triangles that the
    /// colliders miss, graze and push (one after another), degenerate ones, and
    /// colliders without a core.
    #[test]
    fn kept_triangle_frame_gives_the_bits_of_a_fresh_one() {
        let mut rng = SplitMix64::new(11);
        let mut u = |lo: f32, hi: f32| rng.range_f32(lo, hi);
        let (mut pushed, mut missed, mut pushed_twice) = (0, 0, 0);
        for round in 0..20_000 {
            let mut cores = Vec::new();
            for k in 0..4 {
                let shape = match (round + k) % 5 {
                    0 => Shape::Sphere {
                        radius: u(0.02, 0.2),
                        inside: false,
                    },
                    1 => Shape::Plane,
                    _ => Shape::Capsule {
                        radius: u(0.02, 0.2),
                        length: u(0.0, 0.5),
                    },
                };
                let rotation =
                    Quat::from_euler(glam::EulerRot::XYZ, u(-3.0, 3.0), u(-3.0, 3.0), 0.0);
                let centre = Vec3::new(u(-0.3, 0.3), u(-0.3, 0.3), u(-0.3, 0.3));
                cores.push(Core::of(&PlacedCollider {
                    shape,
                    transform: Transform::from_translation_rotation(centre, rotation),
                }));
            }
            let mut corner = || Vec3::new(u(-0.4, 0.4), u(-0.4, 0.4), u(-0.4, 0.4));
            let mut p = [corner(), corner(), corner()];
            if round % 50 == 0 {
                p[2] = p[1]; // degenerate
            }
            let free = [round % 3 != 0, true, round % 7 != 0];
            let mode = if round % 4 == 0 {
                SurfaceCollision::Push
            } else {
                SurfaceCollision::PushPull
            };
            let start: [i8; 4] = std::array::from_fn(|k| [0, 1, -1][(round + k) % 3]);
            let r = u(0.0, 0.03);
            let (mut want_sides, mut got_sides) = (start, start);
            let want = one_by_one(p, free, r, &cores, mode, &mut want_sides);
            let got = push_triangle_against(p, free, r, &cores, mode, &mut got_sides);
            let bits = |q: [Vec3; 3]| q.map(|v| v.to_array().map(f32::to_bits));
            assert_eq!(bits(got.0), bits(want.0), "round {round}: corners");
            assert_eq!(got.1, want.1, "round {round}: touched");
            assert_eq!(got_sides, want_sides, "round {round}: side memory");
            // How often a collider after the first met corners an earlier one had moved.
            let mut sides = start;
            let mut count = 0;
            let mut q = p;
            for k in 0..4 {
                let (next, moved) =
                    one_by_one(q, free, r, &cores[k..k + 1], mode, &mut sides[k..k + 1]);
                count += usize::from(moved);
                q = next;
            }
            pushed += usize::from(want.1);
            missed += usize::from(!want.1);
            pushed_twice += usize::from(count >= 2);
        }
        assert!(
            pushed > 2000 && missed > 2000 && pushed_twice > 500,
            "{pushed} {missed} {pushed_twice}"
        );
    }
}
