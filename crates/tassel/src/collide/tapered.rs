//! Tapered capsule collision (KawaiiPhysics' `FTaperedCapsuleLimit`): a segment whose
//! radius changes linearly from one end to the other.
//!
//! KawaiiPhysics' rule, not the exact distance to the hull of the two end balls: the
//! point's closest point on the axis segment gives `t` (0 at the `radius0` end), the
//! radius there is `max(lerp(radius0, radius1, t), 0)`, and a point nearer the axis than
//! that radius plus its own is pushed straight away from the axis point onto it. Pushing
//! along that direction keeps the closest axis point (it is at right angles to the axis
//! inside the segment, and points away past an end), so the result is outside by the
//! same rule. As for the other keep-out shapes, a step that entered from outside stops
//! where it met the surface and keeps the tangential part of the rest of its step.

use crate::math::{closest_params_segment_segment, normalize_or};
use glam::Vec3;

/// The axis segment from the `radius0` end `a` to the `radius1` end `b` with each end's
/// radius plus the point's: the shape as the queries see it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tapered {
    /// The `radius0` end.
    pub a: Vec3,
    /// The `radius1` end.
    pub b: Vec3,
    /// Radius at `a`.
    pub radius0: f32,
    /// Radius at `b`.
    pub radius1: f32,
    /// The point's radius.
    pub point: f32,
}

impl Tapered {
    /// The closest point of the axis to `q` and the contact distance there (the shape's
    /// radius at that point, never below 0, plus the point's). A segment shorter than
    /// 1e-6 m is its midpoint with the larger radius (KawaiiPhysics' `KINDA_SMALL_NUMBER`
    /// case).
    pub fn at(&self, q: Vec3) -> (Vec3, f32) {
        let seg = self.b - self.a;
        let ss = seg.length_squared();
        if ss.is_nan() || ss <= 1e-12 {
            let r = self.radius0.max(self.radius1).max(0.0);
            return ((self.a + self.b) * 0.5, r + self.point);
        }
        let t = ((q - self.a).dot(seg) / ss).clamp(0.0, 1.0);
        let r = (self.radius0 + (self.radius1 - self.radius0) * t).max(0.0);
        (self.a + seg * t, r + self.point)
    }

    /// How far `p` is inside (≤ 0 when it is not).
    pub fn penetration(&self, p: Vec3) -> f32 {
        let (c, limit) = self.at(p);
        limit - (p - c).length()
    }

    /// `p`, or where the rule pushes it when it is inside: straight away from its closest
    /// axis point (along `fallback` when it is on the axis).
    fn outside(&self, p: Vec3, fallback: Vec3) -> Vec3 {
        let (c, limit) = self.at(p);
        let d = p - c;
        if d.length_squared() < limit * limit {
            c + normalize_or(d, fallback) * limit
        } else {
            p
        }
    }
}

/// Pushes `p` (which was at `prev` at the step's start) out of the tapered capsule `s`.
/// `fallback` is the push direction for a point on the axis (KawaiiPhysics: the
/// collider's local X). A step that entered from outside by more than the contact
/// tolerance (also one that passed right through) stops where it first met the surface,
/// found by bisection along the step, and keeps the tangential part of the rest.
pub fn push_out_of_tapered_capsule(p: Vec3, prev: Vec3, s: &Tapered, fallback: Vec3) -> Vec3 {
    let tolerance = |q: Vec3| crate::collide::contact_tolerance(s.at(q).1);
    // Inside beyond the rounding tolerance.
    let inside = |q: Vec3| s.penetration(q) > tolerance(q);
    if !inside(prev) && prev != p {
        // The step's deepest candidates: its point nearest the axis, and its end.
        let (near, _) = closest_params_segment_segment(prev, p, s.a, s.b);
        let hit = [near, 1.0]
            .into_iter()
            .find(|&w| inside(prev + (p - prev) * w));
        if let Some(hi) = hit {
            // The first surface crossing before `hi`, by bisection (the penetration is
            // continuous along the path).
            let (mut lo, mut hi) = (0.0f32, hi);
            for _ in 0..32 {
                let mid = 0.5 * (lo + hi);
                if inside(prev + (p - prev) * mid) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let contact = prev + (p - prev) * lo;
            let (c, _) = s.at(contact);
            let n = normalize_or(contact - c, fallback);
            let rest = p - contact;
            let slid = contact + rest - n * rest.dot(n).min(0.0);
            return s.outside(slid, n);
        }
    }
    s.outside(p, fallback)
}

/// How far `p` violates the tapered capsule `s` (≤ 0 when it does not).
pub fn tapered_capsule_penetration(p: Vec3, s: &Tapered) -> f32 {
    s.penetration(p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn cone() -> Tapered {
        // Along Y: radius 0.3 at y = +0.5, 0.1 at y = -0.5.
        Tapered {
            a: Vec3::new(0.0, 0.5, 0.0),
            b: Vec3::new(0.0, -0.5, 0.0),
            radius0: 0.3,
            radius1: 0.1,
            point: 0.02,
        }
    }

    /// By hand: at the middle the radius is the mean (0.2 + 0.02), at the ends each end's,
    /// beyond an end the end's ball.
    #[test]
    fn the_radius_follows_the_axis_point_linearly() {
        let s = cone();
        let fb = Vec3::X;
        let mid = push_out_of_tapered_capsule(
            Vec3::new(0.05, 0.0, 0.0),
            Vec3::new(0.05, 0.0, 0.0),
            &s,
            fb,
        );
        assert!(mid.abs_diff_eq(Vec3::new(0.22, 0.0, 0.0), 1e-6), "{mid}");
        let top =
            push_out_of_tapered_capsule(Vec3::new(0.0, 0.5, 0.1), Vec3::new(0.0, 0.5, 0.1), &s, fb);
        assert!(top.abs_diff_eq(Vec3::new(0.0, 0.5, 0.32), 1e-6), "{top}");
        // Quarter of the way down from the +Y end: 0.3 + (0.1 - 0.3) * 0.25 = 0.25.
        let q = push_out_of_tapered_capsule(
            Vec3::new(0.0, 0.25, -0.1),
            Vec3::new(0.0, 0.25, -0.1),
            &s,
            fb,
        );
        assert!(q.abs_diff_eq(Vec3::new(0.0, 0.25, -0.27), 1e-6), "{q}");
        // Below the -Y end, inside its ball: straight away from the end.
        let below = push_out_of_tapered_capsule(
            Vec3::new(0.0, -0.55, 0.0),
            Vec3::new(0.0, -0.55, 0.0),
            &s,
            fb,
        );
        assert!(
            below.abs_diff_eq(Vec3::new(0.0, -0.62, 0.0), 1e-6),
            "{below}"
        );
        // On the axis: the fallback.
        let on = push_out_of_tapered_capsule(Vec3::ZERO, Vec3::ZERO, &s, fb);
        assert!(on.abs_diff_eq(Vec3::new(0.22, 0.0, 0.0), 1e-6), "{on}");
        // Equal radii: the plain capsule.
        let even = Tapered { radius1: 0.3, ..s };
        let p = push_out_of_tapered_capsule(
            Vec3::new(0.1, -0.2, 0.0),
            Vec3::new(0.1, -0.2, 0.0),
            &even,
            fb,
        );
        assert!(p.abs_diff_eq(Vec3::new(0.32, -0.2, 0.0), 1e-6), "{p}");
    }

    /// Negative radii along the taper are 0 (KawaiiPhysics' `Max(..., 0)`), and a shape
    /// of no length is a ball of the larger radius.
    #[test]
    fn a_radius_below_zero_counts_as_zero_and_no_length_is_a_ball() {
        let s = Tapered {
            a: Vec3::new(0.0, 1.0, 0.0),
            b: Vec3::new(0.0, -1.0, 0.0),
            radius0: 0.2,
            radius1: -0.2,
            point: 0.0,
        };
        // At y = -0.5 (t = 0.75) the lerp is -0.1: nothing to push.
        let p = Vec3::new(0.01, -0.5, 0.0);
        assert_eq!(push_out_of_tapered_capsule(p, p, &s, Vec3::X), p);
        let ball = Tapered {
            b: s.a,
            radius1: 0.05,
            ..s
        };
        let q = push_out_of_tapered_capsule(
            Vec3::new(0.0, 1.1, 0.0),
            Vec3::new(0.0, 1.1, 0.0),
            &ball,
            Vec3::X,
        );
        assert!(q.abs_diff_eq(Vec3::new(0.0, 1.2, 0.0), 1e-6), "{q}");
    }

    /// Invariants on random shapes and steps: the result is never inside (beyond
    /// rounding); a step that stays outside is left alone; a step that passes right
    /// through the shape ends on the side it came from.
    #[test]
    fn no_result_is_inside_and_a_step_through_is_caught() {
        let mut rng = SplitMix64::new(7);
        let mut u = |lo: f32, hi: f32| rng.range_f32(lo, hi);
        let mut through = 0;
        for case in 0..20_000 {
            let a = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
            let dir = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)).normalize_or(Vec3::Y);
            let s = Tapered {
                a,
                b: a + dir * u(0.0, 0.6),
                radius0: u(0.0, 0.3),
                radius1: u(0.0, 0.3),
                point: u(0.0, 0.03),
            };
            let m = (s.a + s.b) * 0.5;
            let (prev, p) = if case % 3 == 0 {
                // Right through the middle of the axis, across it.
                let w = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
                let w = (w - dir * w.dot(dir)).normalize_or(dir.any_orthonormal_vector());
                let w = w * u(0.4, 1.0);
                (m + w, m - w)
            } else {
                let prev = a + Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
                (
                    prev,
                    a + Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)),
                )
            };
            let out = push_out_of_tapered_capsule(p, prev, &s, Vec3::X);
            // f32 rounding of the axis parameter, times the taper's slope.
            let limit = s.at(out).1;
            let slope = (s.radius1 - s.radius0).abs() / (s.b - s.a).length().max(1e-6);
            assert!(
                s.penetration(out) <= 2e-6 * (1.0 + limit) * (1.0 + slope),
                "case {case}: {} inside (prev {prev} p {p} -> {out}) {s:?}",
                s.penetration(out)
            );
            // Well outside all the way (sampled finely enough for the shape's slope: a
            // taper over at least 0.1 m changes the radius by at most 3 per metre).
            if (s.b - s.a).length() > 0.1
                && (0..=256).all(|k| s.penetration(prev + (p - prev) * (k as f32 / 256.0)) < -0.06)
            {
                assert_eq!(out, p, "case {case}: a step outside is left alone");
            }
            if case % 3 == 0 && s.penetration(prev) < -1e-3 && s.penetration(m) > 0.0 {
                // Across the shape's middle: it ends on the side it came from.
                through += 1;
                assert!(
                    (out - m).dot(prev - m) > 0.0,
                    "case {case}: passed through (prev {prev} -> {out}), p {p}, shape {s:?}"
                );
            }
        }
        assert!(through > 1_000, "only {through} steps through");
    }
}
