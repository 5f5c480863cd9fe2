//! A tiny seeded random generator (SplitMix64): Tassel never touches a global RNG, so the
//! same seed always gives the same gusts, bit for bit.

/// SplitMix64: fast, seedable, good enough for wind gusts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator starting from `seed`.
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A float uniformly in `[lo, hi)`.
    pub fn range_f32(&mut self, lo: f32, hi: f32) -> f32 {
        let unit = (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * unit
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_is_bounded_and_mean_is_centred() {
        let mut r = SplitMix64::new(7);
        let mut sum = 0.0f64;
        for _ in 0..100_000 {
            let x = r.range_f32(0.0, 2.0);
            assert!((0.0..2.0).contains(&x));
            sum += x as f64;
        }
        let mean = sum / 100_000.0;
        assert!((mean - 1.0).abs() < 0.01, "mean {mean}");
    }
}
