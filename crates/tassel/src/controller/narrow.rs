//! Exact capsule queries against the level's primitives, in world space.
//!
//! parry's general GJK/EPA queries lose millimetres (and, for a capsule sunk into a large
//! box, the whole penetration) in `f32` when the shapes differ in size by two orders of
//! magnitude, as a character and a floor do. The controller's queries are all "a capsule
//! (a segment and a radius) against one convex primitive or triangle", which have a simple
//! exact form: the signed distance of the primitive is convex along the capsule's segment,
//! and its minimum there has a closed form per primitive ([`super::segment_query`]; a
//! golden-section search, kept in the tests, is the reference), and the sweep is Newton's
//! method on a convex function of time, whose tangents never overshoot the first contact.

use super::segment_query::{
    closest_on_triangle, min_of_max_lines, segment_box_outside, segment_triangle,
};
use crate::math::{closest_params_segment_segment, closest_point_on_segment, normalize_or};
use glam::{Quat, Vec3};

/// One level primitive, world space.
#[derive(Debug, Clone)]
pub(crate) enum Prim {
    Cuboid {
        centre: Vec3,
        rotation: Quat,
        half: Vec3,
    },
    Sphere {
        centre: Vec3,
        radius: f32,
    },
    Capsule {
        a: Vec3,
        b: Vec3,
        radius: f32,
    },
    /// A convex polyhedron: outward face planes `n·p = d` and its boundary triangulated,
    /// with each triangle's unit normal (by its winding), computed once.
    Convex {
        planes: Vec<(Vec3, f32)>,
        triangles: Vec<[Vec3; 3]>,
        normals: Vec<Vec3>,
    },
    Triangle {
        v: [Vec3; 3],
        normal: Vec3,
    },
}

/// The signed distance between a capsule and a primitive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Separation {
    /// Signed distance, metres (negative: penetration depth).
    pub distance: f32,
    /// Unit normal from the primitive towards the capsule.
    pub normal: Vec3,
    /// The closest point on the primitive's surface.
    pub point: Vec3,
}

impl Prim {
    /// World bounds.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            Prim::Cuboid {
                centre,
                rotation,
                half,
            } => {
                let m = glam::Mat3::from_quat(*rotation);
                let e = m.x_axis.abs() * half.x + m.y_axis.abs() * half.y + m.z_axis.abs() * half.z;
                (*centre - e, *centre + e)
            }
            Prim::Sphere { centre, radius } => (*centre - *radius, *centre + *radius),
            Prim::Capsule { a, b, radius } => (a.min(*b) - *radius, a.max(*b) + *radius),
            Prim::Convex { triangles, .. } => {
                let mut lo = Vec3::splat(f32::INFINITY);
                let mut hi = Vec3::splat(f32::NEG_INFINITY);
                for t in triangles {
                    for v in t {
                        lo = lo.min(*v);
                        hi = hi.max(*v);
                    }
                }
                (lo, hi)
            }
            Prim::Triangle { v, .. } => (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2])),
        }
    }

    /// Signed distance of point `p` and the unit direction in which it grows fastest.
    pub fn sdf(&self, p: Vec3) -> (f32, Vec3) {
        match self {
            Prim::Cuboid {
                centre,
                rotation,
                half,
            } => {
                let local = rotation.inverse() * (p - *centre);
                let q = local.abs() - *half;
                let outside = q.max(Vec3::ZERO);
                let out_len = outside.length();
                if out_len > 0.0 {
                    let g = outside * local.signum() / out_len;
                    (out_len, *rotation * g)
                } else {
                    // Inside: the nearest face.
                    let k = if q.x >= q.y && q.x >= q.z {
                        0
                    } else if q.y >= q.z {
                        1
                    } else {
                        2
                    };
                    let mut g = Vec3::ZERO;
                    g[k] = if local[k] >= 0.0 { 1.0 } else { -1.0 };
                    (q[k], *rotation * g)
                }
            }
            Prim::Sphere { centre, radius } => {
                let v = p - *centre;
                (v.length() - radius, normalize_or(v, Vec3::Y))
            }
            Prim::Capsule { a, b, radius } => {
                let v = p - closest_point_on_segment(p, *a, *b);
                (v.length() - radius, normalize_or(v, Vec3::Y))
            }
            Prim::Convex {
                planes, triangles, ..
            } => {
                let (mut best, mut normal) = (f32::NEG_INFINITY, Vec3::Y);
                for (n, d) in planes {
                    let s = n.dot(p) - d;
                    if s > best {
                        best = s;
                        normal = *n;
                    }
                }
                if best <= 0.0 {
                    return (best, normal);
                }
                let mut closest = p;
                let mut d2 = f32::INFINITY;
                for t in triangles {
                    let c = closest_on_triangle(p, t[0], t[1], t[2]);
                    let l = (p - c).length_squared();
                    if l < d2 {
                        d2 = l;
                        closest = c;
                    }
                }
                let v = p - closest;
                (d2.sqrt(), normalize_or(v, normal))
            }
            Prim::Triangle { v, normal } => {
                let c = closest_on_triangle(p, v[0], v[1], v[2]);
                let d = p - c;
                let side = if (p - v[0]).dot(*normal) >= 0.0 {
                    *normal
                } else {
                    -*normal
                };
                (d.length(), normalize_or(d, side))
            }
        }
    }

    /// The signed distance between the capsule `a`–`b` of `radius` and this primitive.
    pub fn separation(&self, a: Vec3, b: Vec3, radius: f32) -> Separation {
        let (t, (d, n)) = match self {
            // Closed form for the sphere: the nearest point of the segment to its centre.
            Prim::Sphere { centre, .. } => {
                let q = closest_point_on_segment(*centre, a, b);
                (q, self.sdf(q))
            }
            _ => {
                let q = a + (b - a) * self.min_along(a, b);
                (q, self.sdf(q))
            }
        };
        Separation {
            distance: d - radius,
            normal: n,
            point: t - n * d,
        }
    }

    /// Where along segment `a`–`b` (the parameter in `[0, 1]`) the (convex) signed
    /// distance is least, in closed form per primitive.
    fn min_along(&self, a: Vec3, b: Vec3) -> f32 {
        let ab = b - a;
        if ab.length_squared() < 1e-14 {
            return 0.0;
        }
        match self {
            Prim::Sphere { centre, .. } => {
                (ab.dot(*centre - a) / ab.length_squared()).clamp(0.0, 1.0)
            }
            Prim::Capsule { a: ca, b: cb, .. } => closest_params_segment_segment(a, b, *ca, *cb).0,
            Prim::Triangle { v, normal } => segment_triangle(a, b, v, *normal).0,
            Prim::Cuboid {
                centre,
                rotation,
                half,
            } => {
                let inv = rotation.inverse();
                let (p0, d) = (inv * (a - *centre), inv * ab);
                let lines = [
                    (p0.x - half.x, d.x),
                    (-p0.x - half.x, -d.x),
                    (p0.y - half.y, d.y),
                    (-p0.y - half.y, -d.y),
                    (p0.z - half.z, d.z),
                    (-p0.z - half.z, -d.z),
                ];
                let (t, deepest) = min_of_max_lines(6, |i| lines[i]);
                if deepest <= 0.0 {
                    t
                } else {
                    segment_box_outside(p0, d, *half)
                }
            }
            Prim::Convex {
                planes,
                triangles,
                normals,
            } => {
                let (t, deepest) = min_of_max_lines(planes.len(), |i| {
                    let (pn, pd) = planes[i];
                    (pn.dot(a) - pd, pn.dot(ab))
                });
                if deepest <= 0.0 {
                    return t;
                }
                let mut best = (0.0, f32::INFINITY);
                for (tri, &n) in triangles.iter().zip(normals) {
                    let (t, d2) = segment_triangle(a, b, tri, n);
                    if d2 < best.1 {
                        best = (t, d2);
                    }
                }
                best.0
            }
        }
    }

    /// The reference for [`Prim::min_along`]: a golden-section search for the least
    /// signed distance along `a`–`b` (endpoints compared too); the point.
    #[cfg(test)]
    fn min_along_search(&self, a: Vec3, b: Vec3) -> Vec3 {
        let ab = b - a;
        if ab.length_squared() < 1e-14 {
            return a;
        }
        let f = |t: f32| self.sdf(a + ab * t).0;
        const R: f32 = 0.618_034;
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        let mut x1 = hi - R * (hi - lo);
        let mut x2 = lo + R * (hi - lo);
        let (mut f1, mut f2) = (f(x1), f(x2));
        for _ in 0..36 {
            if f1 <= f2 {
                hi = x2;
                x2 = x1;
                f2 = f1;
                x1 = hi - R * (hi - lo);
                f1 = f(x1);
            } else {
                lo = x1;
                x1 = x2;
                f1 = f2;
                x2 = lo + R * (hi - lo);
                f2 = f(x2);
            }
        }
        let (mut best_t, mut best) = if f1 <= f2 { (x1, f1) } else { (x2, f2) };
        for end in [0.0, 1.0] {
            let v = f(end);
            if v < best {
                (best_t, best) = (end, v);
            }
        }
        a + ab * best_t
    }

    /// Sweeps the capsule `a`–`b` of `radius` along `v` (fraction 0..1 of it) and returns
    /// the first contact. Starting in contact or inside: a contact at 0 only when the
    /// motion goes further in; motion that leaves or slides along is free.
    pub fn sweep(&self, a: Vec3, b: Vec3, radius: f32, v: Vec3) -> Option<(f32, Separation)> {
        const TOUCH: f32 = 1e-5;
        let mut t = 0.0f32;
        for i in 0..32 {
            let s = self.separation(a + v * t, b + v * t, radius);
            let rate = s.normal.dot(v);
            if s.distance <= TOUCH {
                if i == 0 && rate >= -1e-7 * v.length() {
                    return None;
                }
                return Some((t, s));
            }
            if rate >= 0.0 {
                // The distance is convex in time and no longer falling: no contact ahead.
                return None;
            }
            // The tangent at t bounds the distance from below: stepping to its root never
            // passes the first contact.
            t += (s.distance - 0.5 * TOUCH) / -rate;
            if t > 1.0 {
                return None;
            }
        }
        // Not converged (a grazing approach): stop here, which is still short of contact.
        Some((t, self.separation(a + v * t, b + v * t, radius)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn floor(size: f32) -> Prim {
        Prim::Cuboid {
            centre: Vec3::new(0.0, -0.5, 0.0),
            rotation: Quat::IDENTITY,
            half: Vec3::new(size, 0.5, size),
        }
    }

    #[test]
    fn capsule_in_a_large_box_is_exact() {
        // The case parry's f32 EPA gets wrong: a 0.3 m capsule 5 cm into a 100 m floor.
        for size in [0.5f32, 10.0, 50.0, 1000.0] {
            let s =
                floor(size).separation(Vec3::new(0.0, 0.25, 0.0), Vec3::new(0.0, 1.45, 0.0), 0.3);
            assert!((s.distance + 0.05).abs() < 1e-6, "size {size}: {s:?}");
            assert!(s.normal.abs_diff_eq(Vec3::Y, 1e-6));
        }
    }

    #[test]
    fn sweep_stops_at_contact_and_ignores_leaving() {
        let f = floor(50.0);
        let (a, b) = (Vec3::new(0.0, 1.2, 0.0), Vec3::new(0.0, 2.4, 0.0));
        // Bottom at 0.9 m: contact after 0.9 of a 1 m fall.
        let (t, s) = f.sweep(a, b, 0.3, Vec3::new(0.0, -1.0, 0.0)).unwrap();
        assert!((t - 0.9).abs() < 1e-5, "{t}");
        assert!(s.distance.abs() < 2e-5);
        // Diagonal: the same height is lost after 0.9 of the motion.
        let (t, _) = f.sweep(a, b, 0.3, Vec3::new(2.0, -1.0, 0.5)).unwrap();
        assert!((t - 0.9).abs() < 1e-5, "{t}");
        // Resting on it: moving along or away is free, moving in is a contact at 0.
        let (a0, b0) = (Vec3::new(0.0, 0.3, 0.0), Vec3::new(0.0, 1.5, 0.0));
        assert!(f.sweep(a0, b0, 0.3, Vec3::X).is_none());
        assert!(f.sweep(a0, b0, 0.3, Vec3::Y).is_none());
        assert_eq!(f.sweep(a0, b0, 0.3, -Vec3::Y).unwrap().0, 0.0);
    }

    #[test]
    fn closest_point_on_a_triangle_by_region() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Z);
        assert!(closest_on_triangle(Vec3::new(0.2, 1.0, 0.2), a, b, c)
            .abs_diff_eq(Vec3::new(0.2, 0.0, 0.2), 1e-6));
        assert_eq!(closest_on_triangle(Vec3::new(-1.0, 0.0, -1.0), a, b, c), a);
        assert_eq!(
            closest_on_triangle(Vec3::new(0.5, 0.0, -1.0), a, b, c),
            Vec3::new(0.5, 0.0, 0.0)
        );
        let p = closest_on_triangle(Vec3::new(1.0, 0.0, 1.0), a, b, c);
        assert!(p.abs_diff_eq(Vec3::new(0.5, 0.0, 0.5), 1e-6));
    }

    /// The closed forms against the golden-section reference on random segments near each
    /// kind of primitive: never worse, and the same least distance (the search converges
    /// to ~1e-7 of the parameter).
    #[test]
    fn closed_forms_match_the_search() {
        let mut r = crate::rng::SplitMix64::new(21);
        let mut v = |s: f32| Vec3::new(r.range_f32(-s, s), r.range_f32(-s, s), r.range_f32(-s, s));
        // The ramp as the level builds it: a wedge 1 m wide, 1.5 m long, 0.6 m high.
        let mut built = Vec::new();
        let wedge = super::super::level::LevelCollider::new(
            "ramp",
            super::super::level::LevelShape::Ramp {
                width: 1.0,
                length: 1.5,
                height: 0.6,
            },
            Vec3::ZERO,
        );
        super::super::level::build_prims(&wedge, &mut built).unwrap();
        let ramp = built.pop().unwrap();
        let prims = [
            Prim::Cuboid {
                centre: Vec3::new(0.1, -0.2, 0.3),
                rotation: Quat::from_euler(glam::EulerRot::YXZ, 0.4, 0.3, -0.2),
                half: Vec3::new(0.6, 0.3, 0.9),
            },
            Prim::Capsule {
                a: Vec3::new(-0.5, 0.0, 0.2),
                b: Vec3::new(0.4, 0.3, -0.3),
                radius: 0.2,
            },
            Prim::Triangle {
                v: [
                    Vec3::new(-1.0, 0.0, -0.5),
                    Vec3::new(0.8, 0.2, -0.4),
                    Vec3::new(0.0, -0.1, 0.9),
                ],
                normal: (Vec3::new(1.8, 0.2, 0.1))
                    .cross(Vec3::new(1.0, -0.1, 1.4))
                    .normalize(),
            },
            ramp,
        ];
        for (k, prim) in prims.iter().enumerate() {
            for _ in 0..400 {
                let (a, b) = (v(1.6), v(1.6));
                let exact = prim.sdf(a + (b - a) * prim.min_along(a, b)).0;
                let search = prim.sdf(prim.min_along_search(a, b)).0;
                assert!(
                    exact <= search + 1e-5 && exact >= search - 1e-4,
                    "prim {k}: closed form {exact}, search {search} for {a} {b}"
                );
            }
        }
    }

    #[test]
    fn sphere_and_capsule_distances_by_hand() {
        let s = Prim::Sphere {
            centre: Vec3::new(1.0, 0.0, 0.0),
            radius: 0.5,
        };
        let d = s.separation(Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0), 0.2);
        assert!((d.distance - 0.3).abs() < 1e-6);
        assert!(d.normal.abs_diff_eq(-Vec3::X, 1e-6));
        let c = Prim::Capsule {
            a: Vec3::new(1.0, 0.0, -1.0),
            b: Vec3::new(1.0, 0.0, 1.0),
            radius: 0.25,
        };
        let d = c.separation(Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0), 0.25);
        assert!((d.distance - 0.5).abs() < 1e-5, "{d:?}");
    }
}
