//! A 1D blend space (e.g. idle / walk / run by speed) with phase synchronisation: all its
//! clips share one normalised phase, so feet stay in step across clips of different
//! lengths.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Clips placed along one parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BlendSpace1D {
    /// `(parameter value, clip index)`, strictly increasing in the value.
    pub points: Vec<(f32, usize)>,
}

/// Phase state of a playing blend space.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BlendSpacePhase {
    /// Normalised phase in `[0, 1)`.
    pub phase: f32,
}

impl BlendSpace1D {
    /// Checks that points are finite and increasing.
    pub fn validate(&self) -> Result<()> {
        if self.points.is_empty() {
            return Err(Error::InvalidParameter("blend space has no clips".into()));
        }
        if self.points.iter().any(|p| !p.0.is_finite())
            || self.points.windows(2).any(|w| w[1].0 <= w[0].0)
        {
            return Err(Error::InvalidParameter(
                "blend space values must be finite and increasing".into(),
            ));
        }
        Ok(())
    }

    /// Weights of each point for parameter `x` (clamped to the ends). They sum to 1; at
    /// most two are non-zero. Writes into `weights` (one per point).
    pub fn weights(&self, x: f32, weights: &mut [f32]) {
        weights.iter_mut().for_each(|w| *w = 0.0);
        let p = &self.points;
        let n = p.len();
        if n == 1 || !x.is_finite() || x <= p[0].0 {
            weights[0] = 1.0;
            return;
        }
        if x >= p[n - 1].0 {
            weights[n - 1] = 1.0;
            return;
        }
        let i = p.partition_point(|q| q.0 <= x) - 1;
        let s = (x - p[i].0) / (p[i + 1].0 - p[i].0);
        weights[i] = 1.0 - s;
        weights[i + 1] = s;
    }

    /// Advances the shared phase by `dt` at parameter `x`: the cycle length is the
    /// weighted mean of the clips' durations. Returns nothing; read `phase` and sample each
    /// clip `i` at `phase · duration_i`.
    pub fn advance(
        &self,
        phase: &mut BlendSpacePhase,
        x: f32,
        dt: f32,
        durations: &[f32],
        weights: &mut [f32],
    ) {
        self.weights(x, weights);
        let cycle: f32 = self
            .points
            .iter()
            .zip(weights.iter())
            .map(|(p, w)| w * durations[p.1])
            .sum();
        if cycle > 1e-6 && dt.is_finite() {
            phase.phase = (phase.phase + dt / cycle).rem_euclid(1.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_phase_is_continuous_across_a_ramp() {
        let space = BlendSpace1D {
            points: vec![(0.0, 0), (1.4, 1), (4.0, 2)],
        };
        space.validate().unwrap();
        let durations = [2.0, 1.0, 0.7];
        let mut w = [0.0; 3];
        for k in 0..=100 {
            let x = -1.0 + k as f32 * 0.06;
            space.weights(x, &mut w);
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6, "x {x}: {w:?}");
            assert!(w.iter().all(|&v| v >= 0.0));
        }
        space.weights(2.7, &mut w);
        assert!((w[1] - 0.5).abs() < 1e-6 && (w[2] - 0.5).abs() < 1e-6);
        // Ramp speed 0 → 4 m/s over 4 s at 60 Hz: the phase advances by a small step every
        // frame (never jumps, never runs backwards), by at most dt / shortest cycle.
        let mut phase = BlendSpacePhase::default();
        let dt = 1.0 / 60.0;
        for f in 0..240 {
            let before = phase.phase;
            space.advance(&mut phase, f as f32 * dt, dt, &durations, &mut w);
            let step = (phase.phase - before).rem_euclid(1.0);
            assert!(
                step > 0.0 && step <= dt / 0.7 + 1e-6,
                "frame {f}: step {step}"
            );
        }
        assert!(BlendSpace1D {
            points: vec![(1.0, 0), (1.0, 1)]
        }
        .validate()
        .is_err());
    }
}
