//! Closed forms for "where along a segment is a primitive nearest": the capsule's axis
//! against a triangle, a box and a convex polyhedron (against a segment, a capsule, it is
//! [`crate::math::closest_params_segment_segment`]). They replace
//! the golden-section search of [`super::narrow`] (kept there as the test reference):
//! each is exact, and a few dozen flops instead of 38 signed-distance evaluations.
//!
//! Every function takes the segment as `a + t·(b − a)`, `t ∈ [0, 1]`, and returns `t`.

use crate::math::closest_params_segment_segment;
use glam::Vec3;

/// Ericson's closest point on triangle `abc` to `p` (5.1.5). Same regions as
/// [`crate::math::closest_point_on_triangle`], but the interior case multiplies by the
/// reciprocal of the denominator; switching to the shared one moves the controller's
/// output by an ulp, so it is left for a commit that may change output.
pub(crate) fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
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

/// The segment's parameter nearest triangle `v` (unit `normal`), and the squared distance.
/// A segment through the triangle meets it at distance 0; otherwise the nearest pair is an
/// endpoint against the triangle or the segment against one of its edges.
pub(crate) fn segment_triangle(a: Vec3, b: Vec3, v: &[Vec3; 3], normal: Vec3) -> (f32, f32) {
    let d = b - a;
    let (ha, hb) = (normal.dot(a - v[0]), normal.dot(b - v[0]));
    if normal != Vec3::ZERO && ((ha <= 0.0 && hb >= 0.0) || (ha >= 0.0 && hb <= 0.0)) {
        let span = ha - hb;
        let t = if span.abs() > 1e-30 { ha / span } else { 0.0 };
        let p = a + d * t;
        // Inside when on the inner side of all three edges (in the plane's orientation).
        let inside = (0..3).all(|k| {
            let (e0, e1) = (v[k], v[(k + 1) % 3]);
            (e1 - e0).cross(p - e0).dot(normal) >= 0.0
        });
        if inside {
            return (t, 0.0);
        }
    }
    let mut best = (0.0, f32::INFINITY);
    for t in [0.0, 1.0] {
        let p = a + d * t;
        let l = (p - closest_on_triangle(p, v[0], v[1], v[2])).length_squared();
        if l < best.1 {
            best = (t, l);
        }
    }
    for k in 0..3 {
        let (e0, e1) = (v[k], v[(k + 1) % 3]);
        let (s, u) = closest_params_segment_segment(a, b, e0, e1);
        let l = ((a + d * s) - (e0 + (e1 - e0) * u)).length_squared();
        if l < best.1 {
            best = (s, l);
        }
    }
    best
}

/// The least of `F(t) = maxᵢ (αᵢ + βᵢ·t)` over `t ∈ [0, 1]`: `(t, F(t))`. `F` is convex and
/// piecewise linear, so its least value is at an end or where a rising line crosses a
/// falling one.
pub(crate) fn min_of_max_lines(n: usize, line: impl Fn(usize) -> (f32, f32)) -> (f32, f32) {
    let f = |t: f32| {
        (0..n).fold(f32::NEG_INFINITY, |m, i| {
            let (al, be) = line(i);
            m.max(al + be * t)
        })
    };
    let (f0, f1) = (f(0.0), f(1.0));
    let mut best = if f0 <= f1 { (0.0, f0) } else { (1.0, f1) };
    for i in 0..n {
        let (ai, bi) = line(i);
        if bi <= 0.0 {
            continue;
        }
        for j in 0..n {
            let (aj, bj) = line(j);
            if bj >= 0.0 {
                continue;
            }
            let t = (aj - ai) / (bi - bj);
            if t > 0.0 && t < 1.0 {
                let v = f(t);
                if v < best.1 {
                    best = (t, v);
                }
            }
        }
    }
    best
}

/// For a segment `p0 + t·d` (box-local) that stays outside the box of half extents `h`:
/// the parameter of least distance. The squared distance is a convex quadratic between
/// the points where the segment crosses a face plane; each piece's minimum is closed-form.
pub(crate) fn segment_box_outside(p0: Vec3, d: Vec3, h: Vec3) -> f32 {
    let mut cuts = [0.0f32; 8];
    let mut n = 0;
    cuts[n] = 0.0;
    n += 1;
    for k in 0..3 {
        if d[k] != 0.0 {
            for side in [-h[k], h[k]] {
                let t = (side - p0[k]) / d[k];
                if t > 0.0 && t < 1.0 {
                    cuts[n] = t;
                    n += 1;
                }
            }
        }
    }
    cuts[n] = 1.0;
    n += 1;
    let cuts = &mut cuts[..n];
    cuts.sort_unstable_by(f32::total_cmp);
    let dist2 = |t: f32| {
        let p = p0 + d * t;
        (p.abs() - h).max(Vec3::ZERO).length_squared()
    };
    let mut best = (0.0, dist2(0.0));
    for w in cuts.windows(2) {
        let (lo, hi) = (w[0], w[1]);
        if hi <= lo {
            continue;
        }
        // Which faces the piece is beyond, from its middle.
        let mid = p0 + d * (0.5 * (lo + hi));
        let (mut num, mut den) = (0.0f32, 0.0f32);
        for k in 0..3 {
            let s = if mid[k] > h[k] {
                h[k]
            } else if mid[k] < -h[k] {
                -h[k]
            } else {
                continue;
            };
            let c = p0[k] - s;
            num += c * d[k];
            den += d[k] * d[k];
        }
        let t = if den > 0.0 {
            (-num / den).clamp(lo, hi)
        } else {
            lo
        };
        let v = dist2(t);
        if v < best.1 {
            best = (t, v);
        }
    }
    best.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn rnd(r: &mut SplitMix64, s: f32) -> Vec3 {
        Vec3::new(r.range_f32(-s, s), r.range_f32(-s, s), r.range_f32(-s, s))
    }

    /// Brute force: the least of `f` over 20 001 samples of `[0, 1]`.
    fn sampled(f: impl Fn(f32) -> f32) -> f32 {
        (0..=20_000)
            .map(|i| f(i as f32 / 20_000.0))
            .fold(f32::INFINITY, f32::min)
    }

    #[test]
    fn the_shared_segment_segment_matches_sampling() {
        let mut r = SplitMix64::new(11);
        for _ in 0..300 {
            let (p1, d1, p2, d2) = (
                rnd(&mut r, 1.0),
                rnd(&mut r, 1.0),
                rnd(&mut r, 1.0),
                rnd(&mut r, 1.0),
            );
            let (s, t) = closest_params_segment_segment(p1, p1 + d1, p2, p2 + d2);
            let got = ((p1 + d1 * s) - (p2 + d2 * t)).length();
            let brute = sampled(|s| {
                let p = p1 + d1 * s;
                (p - crate::math::closest_point_on_segment(p, p2, p2 + d2)).length()
            });
            assert!(
                got <= brute + 1e-5 && got >= brute - 1e-3,
                "{got} vs {brute}"
            );
        }
    }

    #[test]
    fn segment_triangle_matches_sampling() {
        let mut r = SplitMix64::new(12);
        for _ in 0..300 {
            let v = [rnd(&mut r, 1.0), rnd(&mut r, 1.0), rnd(&mut r, 1.0)];
            let n = (v[1] - v[0]).cross(v[2] - v[0]);
            if n.length() < 1e-3 {
                continue;
            }
            let (a, b) = (rnd(&mut r, 1.5), rnd(&mut r, 1.5));
            let (t, d2) = segment_triangle(a, b, &v, n.normalize());
            let p = a + (b - a) * t;
            let at_t = (p - closest_on_triangle(p, v[0], v[1], v[2])).length();
            assert!((at_t - d2.sqrt()).abs() < 1e-4, "{at_t} vs {}", d2.sqrt());
            let brute = sampled(|s| {
                let p = a + (b - a) * s;
                (p - closest_on_triangle(p, v[0], v[1], v[2])).length()
            });
            assert!(
                at_t <= brute + 1e-5 && at_t >= brute - 1e-3,
                "{at_t} vs {brute}"
            );
        }
    }

    #[test]
    fn min_of_max_lines_by_hand_and_sampling() {
        // max(t, 1 − t) is least at t = ½, value ½.
        let two = [(0.0, 1.0), (1.0, -1.0)];
        let (t, v) = min_of_max_lines(2, |i| two[i]);
        assert!((t - 0.5).abs() < 1e-6 && (v - 0.5).abs() < 1e-6);
        let mut r = SplitMix64::new(13);
        for _ in 0..300 {
            let lines: Vec<(f32, f32)> = (0..6)
                .map(|_| (r.range_f32(-1.0, 1.0), r.range_f32(-2.0, 2.0)))
                .collect();
            let (_, v) = min_of_max_lines(lines.len(), |i| lines[i]);
            let brute = sampled(|t| lines.iter().fold(f32::MIN, |m, &(a, b)| m.max(a + b * t)));
            assert!(v <= brute + 1e-6 && v >= brute - 1e-3, "{v} vs {brute}");
        }
    }

    #[test]
    fn segment_box_outside_matches_sampling() {
        let mut r = SplitMix64::new(14);
        let h = Vec3::new(0.5, 0.2, 1.0);
        let dist = |p: Vec3| (p.abs() - h).max(Vec3::ZERO).length();
        let mut checked = 0;
        for _ in 0..2000 {
            let (p0, d) = (rnd(&mut r, 2.0), rnd(&mut r, 3.0));
            if sampled(|t| dist(p0 + d * t)) < 1e-3 {
                continue; // touches or crosses the box: not this function's case
            }
            let t = segment_box_outside(p0, d, h);
            let got = dist(p0 + d * t);
            let brute = sampled(|t| dist(p0 + d * t));
            assert!(
                got <= brute + 1e-5 && got >= brute - 1e-3,
                "{got} vs {brute}"
            );
            checked += 1;
        }
        assert!(checked > 500, "only {checked} cases");
    }
}
