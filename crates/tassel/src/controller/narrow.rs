//! Exact capsule queries against the level's primitives, in world space.
//!
//! parry's general GJK/EPA queries lose millimetres (and, for a capsule sunk into a large
//! box, the whole penetration) in `f32` when the shapes differ in size by two orders of
//! magnitude, as a character and a floor do. The controller's queries are all "a capsule
//! (a segment and a radius) against one convex primitive or triangle", which have a simple
//! exact form: the signed distance of the primitive is convex, so its minimum along the
//! capsule's segment is found by a golden-section search, and the sweep is Newton's method
//! on a convex function of time, whose tangents never overshoot the first contact.

use crate::math::{closest_point_on_segment, normalize_or};
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
    /// A convex polyhedron: outward face planes `n·p = d` and its boundary triangulated.
    Convex {
        planes: Vec<(Vec3, f32)>,
        triangles: Vec<[Vec3; 3]>,
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

/// Ericson's closest point on triangle `abc` to `p`. Same regions as
/// [`crate::math::closest_point_on_triangle`], but the interior case multiplies by the
/// reciprocal of the denominator; switching to the shared one moves the controller's
/// output by an ulp, so it is left for a commit that may change output.
fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
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
            Prim::Convex { planes, triangles } => {
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
                let q = self.min_along(a, b);
                (q, self.sdf(q))
            }
        };
        Separation {
            distance: d - radius,
            normal: n,
            point: t - n * d,
        }
    }

    /// The point of segment `a`–`b` where the (convex) signed distance is least, by a
    /// golden-section search; endpoints are compared too.
    fn min_along(&self, a: Vec3, b: Vec3) -> Vec3 {
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
