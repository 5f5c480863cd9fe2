//! Clips and their sampling.

use crate::error::{Error, Result};
use crate::math::{slerp_shortest, Transform};
use glam::{Quat, Vec3};

/// How values between keys are found (glTF `sampler.interpolation`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interpolation {
    /// Hold the value of the last key at or before the time.
    Step,
    /// Linear (translation, scale) or spherical linear (rotation) between keys.
    Linear,
    /// Cubic Hermite spline; each key stores in-tangent, value, out-tangent.
    CubicSpline,
}

/// Keyframes of one property. For [`Interpolation::CubicSpline`] `values` holds three
/// entries per key: in-tangent, value, out-tangent.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel<T> {
    /// Interpolation mode.
    pub interpolation: Interpolation,
    /// Key times in seconds, strictly increasing.
    pub times: Vec<f32>,
    /// Key values (three per key for cubic splines).
    pub values: Vec<T>,
}

/// Values a channel can hold.
pub trait Animatable: Copy {
    /// Linear blend.
    fn lerp_value(a: Self, b: Self, t: f32) -> Self;
    /// `a·x + b·y` for the Hermite basis.
    fn combine(terms: [(f32, Self); 4]) -> Self;
    /// Final clean-up (normalise quaternions).
    fn finish(self) -> Self {
        self
    }
    /// Whether a key value is one Tassel accepts: finite, and for translations and scales
    /// within [`crate::limits::MAX_COORDINATE`].
    fn acceptable(&self) -> bool;
}

impl Animatable for Vec3 {
    fn acceptable(&self) -> bool {
        self.is_finite() && self.abs().max_element() <= crate::limits::MAX_COORDINATE
    }
    fn lerp_value(a: Self, b: Self, t: f32) -> Self {
        a.lerp(b, t)
    }
    fn combine(terms: [(f32, Self); 4]) -> Self {
        terms.iter().map(|(w, v)| *v * *w).sum()
    }
}

impl Animatable for Quat {
    fn acceptable(&self) -> bool {
        self.is_finite()
    }
    fn lerp_value(a: Self, b: Self, t: f32) -> Self {
        slerp_shortest(a, b, t)
    }
    fn combine(terms: [(f32, Self); 4]) -> Self {
        let mut acc = glam::Vec4::ZERO;
        for (w, q) in terms {
            acc += glam::Vec4::from(q) * w;
        }
        Quat::from_vec4(acc)
    }
    fn finish(self) -> Self {
        self.normalize()
    }
}

impl<T: Animatable> Channel<T> {
    /// Checks key counts and time order.
    pub fn validate(&self, what: &str) -> Result<()> {
        let per_key = if self.interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        if self.times.is_empty() || self.values.len() != self.times.len() * per_key {
            return Err(Error::InvalidParameter(format!(
                "{what}: {} keys but {} values",
                self.times.len(),
                self.values.len()
            )));
        }
        if self.times.iter().any(|t| !t.is_finite()) || self.times.windows(2).any(|w| w[1] < w[0]) {
            return Err(Error::InvalidParameter(format!(
                "{what}: key times are not increasing"
            )));
        }
        let max = crate::limits::MAX_CLIP_SECONDS;
        if let Some(t) = self.times.iter().find(|t| !(0.0..=max).contains(*t)) {
            return Err(Error::InvalidParameter(format!(
                "{what}: key time {t} s is outside 0..={max} s (the limit on clip length)"
            )));
        }
        if let Some(k) = self.values.iter().position(|v| !v.acceptable()) {
            return Err(Error::InvalidParameter(format!(
                "{what}: value {k} is not finite or is beyond the limit of {:e}",
                crate::limits::MAX_COORDINATE
            )));
        }
        Ok(())
    }

    fn value(&self, k: usize) -> T {
        match self.interpolation {
            Interpolation::CubicSpline => self.values[3 * k + 1],
            _ => self.values[k],
        }
    }

    /// The value at time `t` (clamped to the first and last keys).
    pub fn sample(&self, t: f32) -> T {
        let mut hint = 0;
        self.sample_with_hint(t, &mut hint)
    }

    /// Like [`Channel::sample`], starting the key search at `*hint` (the key found last
    /// time) and updating it: forward playback walks at most a key or two, no search.
    pub fn sample_with_hint(&self, t: f32, hint: &mut u32) -> T {
        let n = self.times.len();
        if n == 1 || t <= self.times[0] {
            *hint = 0;
            return self.value(0).finish();
        }
        if t >= self.times[n - 1] {
            *hint = (n - 1) as u32;
            return self.value(n - 1).finish();
        }
        // Last key at or before t: walk forward from the hint, search when going back.
        let mut k = (*hint as usize).min(n - 2);
        if self.times[k] > t {
            k = self.times.partition_point(|&x| x <= t) - 1;
        } else {
            while self.times[k + 1] <= t {
                k += 1;
            }
        }
        *hint = k as u32;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let td = t1 - t0;
        let s = if td > 0.0 { (t - t0) / td } else { 0.0 };
        match self.interpolation {
            Interpolation::Step => self.values[k].finish(),
            Interpolation::Linear => T::lerp_value(self.values[k], self.values[k + 1], s).finish(),
            Interpolation::CubicSpline => {
                let (s2, s3) = (s * s, s * s * s);
                let v0 = self.values[3 * k + 1];
                let b0 = self.values[3 * k + 2];
                let a1 = self.values[3 * (k + 1)];
                let v1 = self.values[3 * (k + 1) + 1];
                T::combine([
                    (2.0 * s3 - 3.0 * s2 + 1.0, v0),
                    ((s3 - 2.0 * s2 + s) * td, b0),
                    (-2.0 * s3 + 3.0 * s2, v1),
                    ((s3 - s2) * td, a1),
                ])
                .finish()
            }
        }
    }
}

/// The animated properties of one joint.
#[derive(Debug, Clone, PartialEq)]
pub struct JointTrack {
    /// The joint index in the skeleton.
    pub joint: usize,
    /// Translation keys, if animated.
    pub translation: Option<Channel<Vec3>>,
    /// Rotation keys, if animated.
    pub rotation: Option<Channel<Quat>>,
    /// Scale keys, if animated.
    pub scale: Option<Channel<Vec3>>,
}

/// A named animation clip.
///
/// ```
/// use tassel::anim::Clip;
/// use tassel::glam::Vec3;
/// use tassel::Transform;
///
/// // Joint 0 walks 2 m along Z in 1 s, keyed LINEAR at its ends.
/// let walk = Clip::linear_translation("walk", 1.0, 0, [(0.0, Vec3::ZERO), (1.0, Vec3::Z * 2.0)]);
/// let mut locals = vec![Transform::IDENTITY; 2];
/// walk.sample(0.25, &mut locals);
/// assert_eq!(locals[0].translation, Vec3::new(0.0, 0.0, 0.5));
/// // Looping wraps the time: 1.75 s plays as 0.75 s.
/// walk.sample_looped(1.75, &mut locals);
/// assert_eq!(locals[0].translation, Vec3::new(0.0, 0.0, 1.5));
/// // Joint 1 is not animated: left as it was.
/// assert_eq!(locals[1], Transform::IDENTITY);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Clip {
    /// Name (the glTF animation's name, or `animation_<i>`).
    pub name: String,
    /// Length in seconds: the last key time of any channel.
    pub duration: f32,
    /// Tracks, at most one per joint.
    pub tracks: Vec<JointTrack>,
}

impl Clip {
    /// A clip that moves one joint's translation through LINEAR `keys` (`(time, value)`),
    /// lasting `duration` seconds: a root that walks, a test ramp.
    pub fn linear_translation(
        name: &str,
        duration: f32,
        joint: usize,
        keys: impl IntoIterator<Item = (f32, Vec3)>,
    ) -> Clip {
        let (times, values) = keys.into_iter().unzip();
        Clip {
            name: name.into(),
            duration,
            tracks: vec![JointTrack {
                joint,
                translation: Some(Channel {
                    interpolation: Interpolation::Linear,
                    times,
                    values,
                }),
                rotation: None,
                scale: None,
            }],
        }
    }

    /// Overwrites the animated properties of `locals` with their values at `t` seconds
    /// (clamped to the clip). Properties the clip does not animate are left as they are.
    pub fn sample(&self, t: f32, locals: &mut [Transform]) {
        for tr in &self.tracks {
            let Some(l) = locals.get_mut(tr.joint) else {
                continue;
            };
            if let Some(c) = &tr.translation {
                l.translation = c.sample(t);
            }
            if let Some(c) = &tr.rotation {
                l.rotation = c.sample(t);
            }
            if let Some(c) = &tr.scale {
                l.scale = c.sample(t);
            }
        }
    }

    /// Samples at `t` wrapped into the clip's length (looping playback).
    pub fn sample_looped(&self, t: f32, locals: &mut [Transform]) {
        let t = if self.duration > 0.0 {
            t.rem_euclid(self.duration)
        } else {
            0.0
        };
        self.sample(t, locals);
    }

    /// Checks every channel.
    pub fn validate(&self, joint_count: usize) -> Result<()> {
        for tr in &self.tracks {
            let what = format!("clip '{}' joint {}", self.name, tr.joint);
            if tr.joint >= joint_count {
                return Err(Error::InvalidParameter(format!("{what}: no such joint")));
            }
            if let Some(c) = &tr.translation {
                c.validate(&what)?;
            }
            if let Some(c) = &tr.rotation {
                c.validate(&what)?;
            }
            if let Some(c) = &tr.scale {
                c.validate(&what)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_linear_cubic_by_hand() {
        let ch = |interpolation, values: Vec<Vec3>| Channel {
            interpolation,
            times: vec![0.0, 1.0, 3.0],
            values,
        };
        let v = vec![Vec3::ZERO, Vec3::X, Vec3::new(3.0, 0.0, 0.0)];
        assert_eq!(ch(Interpolation::Step, v.clone()).sample(0.9), Vec3::ZERO);
        assert_eq!(ch(Interpolation::Step, v.clone()).sample(1.0), Vec3::X);
        assert_eq!(
            ch(Interpolation::Linear, v.clone()).sample(2.0),
            Vec3::new(2.0, 0.0, 0.0)
        );
        assert_eq!(
            ch(Interpolation::Linear, v.clone()).sample(9.0),
            Vec3::new(3.0, 0.0, 0.0)
        );
        // Hermite with zero tangents at s = 0.5: (v0 + v1) / 2.
        let mut c = Vec::new();
        for x in &v {
            c.extend([Vec3::ZERO, *x, Vec3::ZERO]);
        }
        let cubic = ch(Interpolation::CubicSpline, c.clone());
        assert!(cubic
            .sample(0.5)
            .abs_diff_eq(Vec3::new(0.5, 0.0, 0.0), 1e-6));
        // Out-tangent 1 at key 0 (td = 1), s = 0.5: h10 = 0.125 → 0.5 + 0.125.
        c[2] = Vec3::X;
        let cubic = ch(Interpolation::CubicSpline, c);
        assert!(cubic
            .sample(0.5)
            .abs_diff_eq(Vec3::new(0.625, 0.0, 0.0), 1e-6));
    }

    #[test]
    fn rotation_linear_is_slerp() {
        let c = Channel {
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![Quat::IDENTITY, Quat::from_rotation_y(1.0)],
        };
        assert!(c
            .sample(0.25)
            .abs_diff_eq(Quat::from_rotation_y(0.25), 1e-6));
    }
}
