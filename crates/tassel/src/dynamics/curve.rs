//! Piecewise-linear curves over the normalised length of a chain (0 at the root, 1 at the
//! farthest tip), used as multipliers of chain parameters.

use serde::{Deserialize, Serialize};

/// Keys `(x, y)` with increasing `x`; evaluated by linear interpolation and clamped at
/// both ends. An empty curve is the constant 1.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Curve {
    /// The keys, `[x, y]` pairs.
    pub keys: Vec<[f32; 2]>,
}

impl Curve {
    /// A curve from keys.
    pub fn new(keys: Vec<[f32; 2]>) -> Self {
        Self { keys }
    }

    /// The value at `x`.
    pub fn eval(&self, x: f32) -> f32 {
        let k = &self.keys;
        match k.len() {
            0 => 1.0,
            _ if x <= k[0][0] => k[0][1],
            n if x >= k[n - 1][0] => k[n - 1][1],
            _ => {
                let i = k.partition_point(|key| key[0] <= x).max(1);
                let (a, b) = (k[i - 1], k[i]);
                let w = if b[0] > a[0] {
                    (x - a[0]) / (b[0] - a[0])
                } else {
                    0.0
                };
                a[1] + (b[1] - a[1]) * w
            }
        }
    }

    /// Rejects non-finite keys and decreasing `x`.
    pub fn validate(&self, what: &str) -> Result<(), crate::Error> {
        for (i, key) in self.keys.iter().enumerate() {
            if !key[0].is_finite() || !key[1].is_finite() {
                return Err(crate::Error::InvalidParameter(format!(
                    "{what}: key {i} is not finite"
                )));
            }
            if i > 0 && key[0] < self.keys[i - 1][0] {
                return Err(crate::Error::InvalidParameter(format!(
                    "{what}: key {i} has x {} below the previous key's",
                    key[0]
                )));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_and_clamps() {
        let c = Curve::new(vec![[0.0, 1.0], [0.5, 3.0], [1.0, 0.0]]);
        assert_eq!(c.eval(-1.0), 1.0);
        assert_eq!(c.eval(0.25), 2.0);
        assert_eq!(c.eval(0.75), 1.5);
        assert_eq!(c.eval(2.0), 0.0);
        assert_eq!(Curve::default().eval(0.3), 1.0);
        assert!(Curve::new(vec![[0.5, 1.0], [0.2, 1.0]])
            .validate("c")
            .is_err());
    }
}
