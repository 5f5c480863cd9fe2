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
        match bracket(&self.keys, x, |k| k[0]) {
            None => 1.0,
            Some((i, j, w)) => {
                let (a, b) = (self.keys[i][1], self.keys[j][1]);
                a + (b - a) * w
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

/// Where `x` falls among `keys` (ordered by `key_x`): the two keys to blend and the weight
/// of the second, the value being `a + (b − a) · w`; held at both ends (one key twice,
/// weight 0); `None` without keys. Shared by every piecewise-linear curve.
pub(crate) fn bracket<K>(
    keys: &[K],
    x: f32,
    key_x: impl Fn(&K) -> f32,
) -> Option<(usize, usize, f32)> {
    let n = keys.len();
    if n == 0 {
        return None;
    }
    if x <= key_x(&keys[0]) {
        return Some((0, 0, 0.0));
    }
    if x >= key_x(&keys[n - 1]) {
        return Some((n - 1, n - 1, 0.0));
    }
    let i = keys.partition_point(|k| key_x(k) <= x).max(1);
    let (a, b) = (key_x(&keys[i - 1]), key_x(&keys[i]));
    let w = if b > a { (x - a) / (b - a) } else { 0.0 };
    Some((i - 1, i, w))
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
