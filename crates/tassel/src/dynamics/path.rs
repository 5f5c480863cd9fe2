//! The character's world transform between rendered frames, for the fixed-step solvers.
//!
//! A solver that steps at a fixed rate needs the character's transform at each step's
//! time, which falls between two rendered frames. A straight line (and a slerp) between
//! the last two frames cuts the corners of a curved path: for a character swaying
//! ±0.3 m at 1 Hz seen at 30 Hz the chords miss the path by up to 1.6 mm, and a skirt or
//! a charm moves differently at 30 and at 144 Hz by that much. So the path is a cubic
//! through the last four frames (non-uniform in time; the rotation as a cubic of its
//! rotation vector relative to the newest frame), which misses the same sway by 0.02 mm.
//! It falls back to a quadratic or a line with fewer frames known, and to a line when
//! the frame times are uneven (a hitch) or the motion jumps (a teleport), where a cubic
//! through the history would swing wide.

use crate::math::{slerp_shortest, Transform};
use glam::{Quat, Vec3};

/// The last frames' character transforms and their times.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CharacterPath {
    /// Oldest first; the last `known` are valid (0..=4; 0: nowhere yet, the next frame
    /// is the first known).
    frames: [Transform; 4],
    /// `dts[i]`: seconds from `frames[i]` to `frames[i + 1]`.
    dts: [f32; 3],
    known: usize,
}

impl Default for CharacterPath {
    /// A path that knows nothing yet: its first frame is where the character starts,
    /// whatever time step it comes with (so a first frame of `dt > 0` is a first frame of
    /// `dt = 0`: no motion from a made-up earlier place).
    fn default() -> Self {
        Self {
            frames: [Transform::IDENTITY; 4],
            dts: [0.0; 3],
            known: 0,
        }
    }
}

impl CharacterPath {
    /// A path that has only been at `at`.
    pub fn new(at: Transform) -> Self {
        Self {
            frames: [at; 4],
            dts: [0.0; 3],
            known: 1,
        }
    }

    /// Forgets the history: the character is at `at` (a solver that resets and steps in
    /// the same frame must not step along a path through the old place).
    pub fn reset(&mut self, at: Transform) {
        *self = Self::new(at);
    }

    /// This frame's transform, `dt` seconds after the last one (`dt = 0` replaces it).
    pub fn push(&mut self, at: Transform, dt: f32) {
        if dt <= 0.0 || self.known == 0 {
            if self.known <= 1 {
                self.known = 1;
                self.frames = [at; 4];
            } else {
                self.frames[3] = at;
            }
            return;
        }
        self.frames.copy_within(1..4, 0);
        self.dts.copy_within(1..3, 0);
        self.frames[3] = at;
        self.dts[2] = dt;
        self.known = (self.known + 1).min(4);
    }

    /// The transform a share `w` (0..=1) of the way through the newest frame: 0 = the
    /// frame before, 1 = the newest.
    pub fn at(&self, w: f32) -> Transform {
        let (a, b) = (self.frames[2], self.frames[3]);
        if w >= 1.0 {
            // The newest frame itself (a step that ends on the frame): no history read.
            return b;
        }
        let linear = || {
            Transform::from_translation_rotation(
                a.translation.lerp(b.translation, w),
                slerp_shortest(a.rotation, b.rotation, w),
            )
        };
        let order = self.usable_order();
        if order < 2 || w >= 1.0 {
            return if w >= 1.0 { b } else { linear() };
        }
        // Times relative to the newest frame; evaluate at τ.
        let n = order + 1;
        let first = 4 - n;
        let mut times = [0.0f32; 4];
        let mut t = 0.0;
        for i in (first..3).rev() {
            t -= self.dts[i];
            times[i] = t;
        }
        let tau = -self.dts[2] * (1.0 - w);
        // Lagrange weights over the nodes first..=3.
        let mut weights = [0.0f32; 4];
        for i in first..4 {
            let mut l = 1.0;
            for j in first..4 {
                if j != i {
                    l *= (tau - times[j]) / (times[i] - times[j]);
                }
            }
            weights[i] = l;
        }
        let base_q = b.rotation;
        let inv = base_q.inverse();
        let (mut offset, mut turn) = (Vec3::ZERO, Vec3::ZERO);
        for i in first..3 {
            offset += (self.frames[i].translation - b.translation) * weights[i];
            turn += rotation_vector(inv * self.frames[i].rotation) * weights[i];
        }
        Transform::from_translation_rotation(
            b.translation + offset,
            (base_q * Quat::from_scaled_axis(turn)).normalize(),
        )
    }

    /// The polynomial order the history supports: 1 (a line) unless the last frames are
    /// known, evenly timed (within a factor of 2) and moving smoothly (no frame's move or
    /// turn more than four times the largest of the others, beyond 1 mm and 0.01 rad).
    fn usable_order(&self) -> usize {
        let mut order = self.known.saturating_sub(1).min(3);
        while order >= 2 {
            let first = 4 - (order + 1);
            let dts = &self.dts[first..3];
            let (lo, hi) = dts
                .iter()
                .fold((f32::MAX, 0.0f32), |(lo, hi), &d| (lo.min(d), hi.max(d)));
            let even = lo > 0.0 && hi <= 2.0 * lo;
            // Each frame's move and turn against the largest of the window's others: a
            // teleport stands out, a reversal (one move near zero between two large
            // ones, as when frames fall either side of a sway's extreme) does not.
            let mut moves = [0.0f32; 3];
            let mut turns = [0.0f32; 3];
            for i in first..3 {
                let (q, r) = (self.frames[i], self.frames[i + 1]);
                moves[i] = (r.translation - q.translation).length();
                turns[i] = r.rotation.angle_between(q.rotation);
            }
            let smooth = (first..3).all(|i| {
                let others = |v: &[f32; 3]| {
                    (first..3)
                        .filter(|&j| j != i)
                        .fold(0.0f32, |m, j| m.max(v[j]))
                };
                moves[i] <= 4.0 * others(&moves) + 1e-3 && turns[i] <= 4.0 * others(&turns) + 0.01
            });
            if even && smooth {
                return order;
            }
            order -= 1;
        }
        1
    }
}

/// Time left over after a frame's fixed steps, as a share of a step, below which it is
/// dropped: the last step then ends on the frame (the same tolerance the step count
/// takes the other way, where a frame short of a step by this much still takes it).
pub(crate) const ON_FRAME: f32 = 1e-4;

/// A fixed-step solver's clock for one frame: how many steps of `h` it takes, where each
/// ends, and the time left over for the next frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FixedClock {
    /// Steps this frame.
    pub steps: u32,
    /// Seconds left over after them (0 when the last step ends on the frame).
    pub left: f32,
    acc_old: f32,
    skipped: f32,
    dt: f32,
    h: f32,
}

impl FixedClock {
    /// The steps of a frame of `dt` after `acc_old` seconds left over, at most `max_steps`
    /// (a hitch drops the time it cannot afford and keeps the most recent steps).
    pub fn new(acc_old: f32, dt: f32, h: f32, max_steps: u32) -> Self {
        let mut total = acc_old + dt;
        let mut steps = (total / h + ON_FRAME).floor() as u32;
        if steps > max_steps {
            total -= (steps - max_steps) as f32 * h;
            steps = max_steps;
        }
        let mut left = (total - steps as f32 * h).max(0.0);
        if steps > 0 && left < ON_FRAME * h {
            left = 0.0;
        }
        Self {
            steps,
            left,
            acc_old,
            skipped: acc_old + dt - total,
            dt,
            h,
        }
    }

    /// Where step `k` (1..=steps) ends between last frame (0) and this frame (1): exactly
    /// 1 for the last step when nothing is left over.
    pub fn end(&self, k: u32) -> f32 {
        if k == self.steps && self.left == 0.0 {
            return 1.0;
        }
        let end = k as f32 * self.h - self.acc_old + self.skipped;
        if self.dt > 0.0 {
            (end / self.dt).clamp(0.0, 1.0)
        } else {
            1.0
        }
    }

    /// Whether the last step ends on the frame (then nothing is left over).
    pub fn on_frame(&self) -> bool {
        self.steps > 0 && self.left == 0.0
    }
}

/// The rotation vector (axis · angle, angle in [0, π]) of `q`, on the shortest way.
fn rotation_vector(q: Quat) -> Vec3 {
    let q = if q.w < 0.0 { -q } else { q };
    q.to_scaled_axis()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sway(t: f32) -> Transform {
        Transform::from_translation_rotation(
            Vec3::new(0.3 * (std::f32::consts::TAU * t).sin(), 0.1 * t, 0.0),
            Quat::from_rotation_y(0.5 * (std::f32::consts::TAU * 0.7 * t).sin()),
        )
    }

    /// Along a smooth sway seen at 30 Hz, the path between frames follows the true one
    /// to the cubic's error (≈ A·ω⁴·h⁴/26 = 0.02 mm here), 70 times closer than a line.
    #[test]
    fn follows_a_smooth_path_between_frames() {
        let h = 1.0 / 30.0;
        let mut path = CharacterPath::new(sway(0.0));
        let (mut worst, mut worst_line, mut worst_angle) = (0.0f32, 0.0f32, 0.0f32);
        for f in 1..90 {
            path.push(sway(f as f32 * h), h);
            if f < 4 {
                continue;
            }
            for k in 1..10 {
                let w = k as f32 / 10.0;
                let truth = sway((f as f32 - 1.0 + w) * h);
                let got = path.at(w);
                worst = worst.max((got.translation - truth.translation).length());
                // The angle between them from the vector part (angle_between's acos
                // cannot tell angles under ≈ 7e-4 rad apart in f32).
                let d = got.rotation.inverse() * truth.rotation;
                let angle = 2.0 * Vec3::new(d.x, d.y, d.z).length().min(1.0).asin();
                worst_angle = worst_angle.max(angle);
                let line = sway((f - 1) as f32 * h)
                    .translation
                    .lerp(sway(f as f32 * h).translation, w);
                worst_line = worst_line.max((line - truth.translation).length());
            }
        }
        assert!(worst < 5e-5, "cubic path off by {worst} m");
        assert!(worst_angle < 2e-5, "rotation off by {worst_angle} rad");
        assert!(
            worst_line > 1e-3,
            "the line should miss by mm: {worst_line}"
        );
        // Exact at the frames themselves.
        assert_eq!(path.at(1.0), sway(89.0 * h));
    }

    /// Uneven frames, a teleport or too little history fall back to a line.
    #[test]
    fn falls_back_to_a_line() {
        let line = |a: Transform, b: Transform, w: f32| a.translation.lerp(b.translation, w);
        let h = 1.0 / 60.0;
        let mut path = CharacterPath::new(sway(0.0));
        path.push(sway(h), h);
        assert_eq!(path.at(0.5).translation, line(sway(0.0), sway(h), 0.5));
        // A teleport: 10 m in one frame after slow motion.
        let mut path = CharacterPath::new(sway(0.0));
        for f in 1..4 {
            path.push(sway(f as f32 * h), h);
        }
        let far = Transform::from_translation(Vec3::new(10.0, 0.0, 0.0));
        path.push(far, h);
        let mid = path.at(0.5).translation;
        assert!((mid - line(sway(3.0 * h), far, 0.5)).length() < 1e-5);
        // A hitch: a 0.5 s frame after 1/60 s ones.
        let mut path = CharacterPath::new(sway(0.0));
        for f in 1..4 {
            path.push(sway(f as f32 * h), h);
        }
        path.push(sway(3.0 * h + 0.5), 0.5);
        let mid = path.at(0.5).translation;
        assert!((mid - line(sway(3.0 * h), sway(3.0 * h + 0.5), 0.5)).length() < 1e-5);
    }

    /// Whole steps end on the frame (60 Hz frames of 60 Hz steps, 30 Hz frames of two),
    /// with a last share of exactly 1; 144 Hz frames carry time over; a hitch keeps the
    /// most recent steps; the time is all accounted for.
    #[test]
    fn fixed_clock_counts_steps_and_time() {
        let h = 1.0 / 60.0;
        let c = FixedClock::new(0.0, 1.0 / 60.0, h, 8);
        assert_eq!((c.steps, c.left, c.end(1)), (1, 0.0, 1.0));
        assert!(c.on_frame());
        let c = FixedClock::new(0.0, 1.0 / 30.0, h, 8);
        assert_eq!((c.steps, c.left), (2, 0.0));
        assert!((c.end(1) - 0.5).abs() < 1e-6 && c.end(2) == 1.0);
        // A frame a hair longer or shorter than a step still ends on it.
        for dt in [h * (1.0 - 5e-5), h * (1.0 + 5e-5)] {
            let c = FixedClock::new(0.0, dt, h, 8);
            assert_eq!((c.steps, c.left), (1, 0.0), "dt = {dt}");
        }
        // 144 Hz: 0, 1, 0 steps... with the remainder carried.
        let (mut acc, mut steps) = (0.0f32, 0);
        for _ in 0..144 {
            let c = FixedClock::new(acc, 1.0 / 144.0, h, 8);
            assert!(c.left < h && c.left >= 0.0);
            if c.steps > 0 {
                assert!(c.end(1) > 0.0 && c.end(1) <= 1.0);
            }
            steps += c.steps;
            acc = c.left;
        }
        assert_eq!(steps, 60, "one second of 144 Hz frames is 60 steps");
        // A hitch of 1 s at most 8 steps: the last 8, ending on the frame.
        let c = FixedClock::new(0.0, 1.0, h, 8);
        assert_eq!(c.steps, 8);
        assert_eq!(c.end(8), 1.0);
        assert!((c.end(1) - (1.0 - 7.0 * h)).abs() < 1e-5);
        // No step: nothing dropped.
        let c = FixedClock::new(0.0, 1e-7, h, 8);
        assert_eq!((c.steps, c.left), (0, 1e-7));
        assert!(!c.on_frame());
    }
}
