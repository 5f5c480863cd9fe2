//! The sampling job: a clip at a time (or ratio), looping or clamped, with a per-clip key
//! cursor so that forward playback does no search.

use super::clip::Clip;
use crate::error::{Error, Result};
use crate::math::Transform;

/// How time outside `[0, duration]` maps into the clip.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Playback {
    /// Wrap around (cycles).
    #[default]
    Loop,
    /// Hold the first / last pose.
    Clamp,
}

/// The last key used per channel of one clip (translation, rotation, scale per track).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SamplingCursor {
    keys: Vec<[u32; 3]>,
}

impl SamplingCursor {
    /// A cursor at the start of `clip`.
    pub fn new(clip: &Clip) -> Self {
        Self {
            keys: vec![[0; 3]; clip.tracks.len()],
        }
    }

    /// Back to the first keys.
    pub fn reset(&mut self) {
        self.keys.iter_mut().for_each(|k| *k = [0; 3]);
    }
}

/// Samples one clip into local transforms (only the animated properties are written).
#[derive(Debug)]
pub struct SamplingJob<'a> {
    /// The clip.
    pub clip: &'a Clip,
    /// Its cursor (made by [`SamplingCursor::new`] for this clip).
    pub cursor: &'a mut SamplingCursor,
    /// Time in seconds.
    pub time: f32,
    /// Looping or clamped.
    pub playback: Playback,
    /// Output local transforms (prefill with the rest pose).
    pub locals: &'a mut [Transform],
}

impl SamplingJob<'_> {
    /// The time in seconds for a ratio 0..=1 of `clip`.
    pub fn time_of_ratio(clip: &Clip, ratio: f32) -> f32 {
        ratio * clip.duration
    }

    /// Checks the cursor, the time and the output size.
    pub fn validate(&self) -> Result<()> {
        if self.cursor.keys.len() != self.clip.tracks.len() {
            return Err(Error::InvalidParameter(format!(
                "sampling cursor was made for another clip than '{}'",
                self.clip.name
            )));
        }
        if !self.time.is_finite() {
            return Err(Error::InvalidParameter(format!(
                "sampling time {} is not finite",
                self.time
            )));
        }
        if let Some(t) = self
            .clip
            .tracks
            .iter()
            .find(|t| t.joint >= self.locals.len())
        {
            return Err(Error::LengthMismatch {
                what: "sampling output",
                expected: t.joint + 1,
                got: self.locals.len(),
            });
        }
        Ok(())
    }

    /// Validates, then samples. Never allocates.
    pub fn run(self) -> Result<()> {
        self.validate()?;
        let d = self.clip.duration;
        let t = match self.playback {
            Playback::Loop if d > 0.0 => self.time.rem_euclid(d),
            Playback::Loop => 0.0,
            Playback::Clamp => self.time.clamp(0.0, d.max(0.0)),
        };
        for (tr, keys) in self.clip.tracks.iter().zip(self.cursor.keys.iter_mut()) {
            let l = &mut self.locals[tr.joint];
            if let Some(c) = &tr.translation {
                l.translation = c.sample_with_hint(t, &mut keys[0]);
            }
            if let Some(c) = &tr.rotation {
                l.rotation = c.sample_with_hint(t, &mut keys[1]);
            }
            if let Some(c) = &tr.scale {
                l.scale = c.sample_with_hint(t, &mut keys[2]);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn ramp() -> Clip {
        // x goes 0 → 10 over 10 s in 1 s keys: x(t) = t.
        let keys = (0..=10).map(|k| (k as f32, Vec3::new(k as f32, 0.0, 0.0)));
        Clip::linear_translation("ramp", 10.0, 0, keys)
    }

    #[test]
    fn cursor_matches_search_forward_backward_and_wrapping() {
        let clip = ramp();
        let mut cursor = SamplingCursor::new(&clip);
        let mut out = [Transform::IDENTITY];
        for t in [0.0, 0.5, 2.25, 2.3, 7.9, 3.1, 12.5, -1.5, 9.99] {
            SamplingJob {
                clip: &clip,
                cursor: &mut cursor,
                time: t,
                playback: Playback::Loop,
                locals: &mut out,
            }
            .run()
            .unwrap();
            let expected = t.rem_euclid(10.0);
            assert!(
                (out[0].translation.x - expected).abs() < 1e-5,
                "t {t}: {}",
                out[0].translation.x
            );
        }
        SamplingJob {
            clip: &clip,
            cursor: &mut cursor,
            time: 12.5,
            playback: Playback::Clamp,
            locals: &mut out,
        }
        .run()
        .unwrap();
        assert_eq!(out[0].translation.x, 10.0);
        let t = SamplingJob::time_of_ratio(&clip, 0.25);
        SamplingJob {
            clip: &clip,
            cursor: &mut cursor,
            time: t,
            playback: Playback::Clamp,
            locals: &mut out,
        }
        .run()
        .unwrap();
        assert!((out[0].translation.x - 2.5).abs() < 1e-6);
        let mut other = SamplingCursor { keys: vec![] };
        assert!(SamplingJob {
            clip: &clip,
            cursor: &mut other,
            time: 0.0,
            playback: Playback::Loop,
            locals: &mut out
        }
        .run()
        .is_err());
    }
}
