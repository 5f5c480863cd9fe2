//! Root motion: the horizontal travel of a clip's root joint, extracted so that the
//! character controller (not the pose) moves the character, and blended with the same
//! weights as the poses.

use super::clip::Clip;
use crate::math::Transform;
use glam::Vec3;

/// Which joint carries the motion and which way is up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RootMotion {
    /// The joint whose translation holds the travel (e.g. the hips or a root bone).
    pub joint: usize,
    /// Up direction in the joint's parent space; motion along it stays in the pose.
    pub up: Vec3,
}

impl RootMotion {
    fn horizontal(&self, v: Vec3) -> Vec3 {
        let up = self.up.normalize_or(Vec3::Y);
        v - up * v.dot(up)
    }

    fn translation_at(&self, clip: &Clip, t: f32) -> Vec3 {
        let mut one = [Transform::IDENTITY];
        if let Some(tr) = clip.tracks.iter().find(|tr| tr.joint == self.joint) {
            if let Some(c) = &tr.translation {
                one[0].translation = c.sample(t);
            }
        }
        one[0].translation
    }

    /// Horizontal travel of the root from `t0` to `t1` (seconds, `t1 ≥ t0`). With
    /// `looping`, whole cycles and the wrap at the end are counted: travel keeps growing
    /// however many times the clip loops.
    pub fn delta(&self, clip: &Clip, t0: f32, t1: f32, looping: bool) -> Vec3 {
        let d = clip.duration;
        if !looping || d <= 0.0 {
            let (a, b) = (t0.clamp(0.0, d.max(0.0)), t1.clamp(0.0, d.max(0.0)));
            return self.horizontal(self.translation_at(clip, b) - self.translation_at(clip, a));
        }
        let cycle = self.horizontal(self.translation_at(clip, d) - self.translation_at(clip, 0.0));
        let (c0, c1) = ((t0 / d).floor(), (t1 / d).floor());
        let p0 = self.translation_at(clip, t0 - c0 * d);
        let p1 = self.translation_at(clip, t1 - c1 * d);
        self.horizontal(p1 - p0) + cycle * (c1 - c0)
    }

    /// Removes the horizontal travel from a sampled pose: the root keeps its height (and
    /// its start position), the controller applies the travel.
    pub fn strip(&self, clip: &Clip, locals: &mut [Transform]) {
        if let Some(l) = locals.get_mut(self.joint) {
            let start = self.translation_at(clip, 0.0);
            let travel = self.horizontal(l.translation - start);
            l.translation -= travel;
        }
    }

    /// The weighted sum of several clips' travel: `(clip, t0, t1, looping, weight)` per
    /// layer, weights as in the pose blend (they should sum to 1).
    pub fn blended_delta(&self, clips: &[Clip], layers: &[(usize, f32, f32, bool, f32)]) -> Vec3 {
        layers
            .iter()
            .filter(|l| l.0 < clips.len())
            .map(|&(c, t0, t1, looping, w)| self.delta(&clips[c], t0, t1, looping) * w)
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn walker(name: &str, speed: f32, duration: f32) -> Clip {
        // The root moves forward at `speed` and bobs 5 cm up and down.
        let keys = (0..=20).map(|k| {
            let t = k as f32 * duration / 20.0;
            (t, Vec3::new(0.0, 0.9 + 0.05 * (t * 10.0).sin(), speed * t))
        });
        Clip::linear_translation(name, duration, 0, keys)
    }

    #[test]
    fn travel_across_loops_and_blending() {
        let rm = RootMotion {
            joint: 0,
            up: Vec3::Y,
        };
        let walk = walker("walk", 1.4, 1.0);
        // By hand: 0.9 → 0.1 over the loop is 0.2 s, 0.28 m; 0.5 → 3.5 is 3 s, 4.2 m.
        assert!(rm
            .delta(&walk, 0.9, 1.1, true)
            .abs_diff_eq(Vec3::new(0.0, 0.0, 0.28), 1e-5));
        assert!(rm
            .delta(&walk, 0.5, 3.5, true)
            .abs_diff_eq(Vec3::new(0.0, 0.0, 4.2), 1e-4));
        assert!(rm
            .delta(&walk, 0.5, 3.5, false)
            .abs_diff_eq(Vec3::new(0.0, 0.0, 0.7), 1e-5));
        let run = walker("run", 4.0, 0.7);
        let both = [walk.clone(), run];
        let d = rm.blended_delta(&both, &[(0, 0.0, 0.1, true, 0.5), (1, 0.0, 0.1, true, 0.5)]);
        assert!(d.abs_diff_eq(Vec3::new(0.0, 0.0, 0.5 * 0.14 + 0.5 * 0.4), 1e-5));
        // Stripped: the root stays over its start point but keeps its bob.
        let mut locals = [Transform::IDENTITY];
        walk.sample(0.5, &mut locals);
        rm.strip(&walk, &mut locals);
        assert!(locals[0].translation.z.abs() < 1e-6);
        assert!((locals[0].translation.y - (0.9 + 0.05 * 5.0f32.sin())).abs() < 1e-3);
    }
}
