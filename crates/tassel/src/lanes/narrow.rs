//! The narrow lane type: [`F4`], four `f32` lanes in plain Rust (one 128-bit register:
//! WebAssembly's `v128`, SSE's, NEON's), for one character's springs side by side where
//! [`F`]'s eight lanes are two registers and a row of few springs pays for all eight.
//!
//! Why it exists: in WebAssembly one character's VRM springs ran in [`F`] (eight lanes,
//! every operation two `v128` instructions), and the built-in avatar's 13 springs filled
//! 40 of its rows' 56 lanes; the crowd keeps eight (a lane per character, its rows full).
//! A plan of at most four columns a group (`dynamics/vrm/lanes/springs.rs`) runs in this
//! type: the same work in fewer wasted lanes.
//!
//! [`F4`] holds [`F`]'s first four lanes ([`Lane::of`]); as [`F`] ([`Lane::f`]) its
//! lanes past the fourth repeat lane 0, as a plan's unused lanes repeat lane 0's link,
//! and [`M4`]'s are clear. Every operation is [`F`]'s per lane (the same IEEE
//! operations, the same bitwise select), so both give the same bits; `tests` checks it
//! operation by operation.

use super::{Lane, Mask, Trs, F, LANES, M};
use crate::math::Transform;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Four `f32` lanes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub(crate) struct F4(pub(crate) [f32; 4]);

/// A per-lane condition of [`F4`] (all bits set when true).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C, align(16))]
pub(crate) struct M4(pub(crate) [u32; 4]);

/// `[e(0), e(1), e(2), e(3)]`: written out, no loop (as `types.rs`'s `each!`).
macro_rules! four {
    ($i:ident => $e:expr) => {
        [
            {
                let $i: usize = 0;
                $e
            },
            {
                let $i: usize = 1;
                $e
            },
            {
                let $i: usize = 2;
                $e
            },
            {
                let $i: usize = 3;
                $e
            },
        ]
    };
}

macro_rules! binary {
    ($tr:ident, $f:ident, $op:tt) => {
        impl $tr for F4 {
            type Output = F4;
            #[inline(always)]
            fn $f(self, o: F4) -> F4 {
                let (a, b) = (self.0, o.0);
                F4(four!(i => a[i] $op b[i]))
            }
        }
    };
}
binary!(Add, add, +);
binary!(Sub, sub, -);
binary!(Mul, mul, *);
binary!(Div, div, /);

impl Neg for F4 {
    type Output = F4;
    #[inline(always)]
    fn neg(self) -> F4 {
        F4(four!(i => -self.0[i]))
    }
}

/// A condition as a mask lane.
#[inline(always)]
fn lane_mask(c: bool) -> u32 {
    if c {
        !0
    } else {
        0
    }
}

impl Lane for F4 {
    type M = M4;
    const WIDTH: usize = 4;

    #[inline(always)]
    fn splat(v: f32) -> F4 {
        F4([v; 4])
    }

    #[inline(always)]
    fn of(f: F) -> F4 {
        F4(four!(i => f.0[i]))
    }

    #[inline(always)]
    fn f(self) -> F {
        let mut f = F::splat(self.0[0]);
        f.0[..4].copy_from_slice(&self.0);
        f
    }

    #[inline(always)]
    fn sqrt(self) -> F4 {
        F4(four!(i => self.0[i].sqrt()))
    }

    #[inline(always)]
    fn abs(self) -> F4 {
        F4(four!(i => self.0[i].abs()))
    }

    #[inline(always)]
    fn lt(self, o: F4) -> M4 {
        M4(four!(i => lane_mask(self.0[i] < o.0[i])))
    }

    #[inline(always)]
    fn le(self, o: F4) -> M4 {
        M4(four!(i => lane_mask(self.0[i] <= o.0[i])))
    }

    #[inline(always)]
    fn ne(self, o: F4) -> M4 {
        M4(four!(i => lane_mask(self.0[i] != o.0[i])))
    }

    #[inline(always)]
    fn finite(self) -> M4 {
        M4(four!(i => lane_mask((self.0[i].to_bits() & 0x7f80_0000) != 0x7f80_0000)))
    }

    #[inline(always)]
    fn select(m: M4, a: F4, b: F4) -> F4 {
        F4(four!(i => f32::from_bits((a.0[i].to_bits() & m.0[i]) | (b.0[i].to_bits() & !m.0[i]))))
    }

    #[inline(always)]
    fn clamp01(self) -> F4 {
        F4(four!(i => self.0[i].clamp(0.0, 1.0)))
    }

    #[inline(always)]
    fn max(self, o: F4) -> F4 {
        F4(four!(i => self.0[i].max(o.0[i])))
    }

    /// Only the four lanes: the others of the array are never read.
    #[inline(always)]
    fn transforms(ts: &[&Transform; LANES]) -> Trs<F4> {
        let mut t = Trs::<F4>::splat(&Transform::IDENTITY);
        for (l, x) in ts.iter().take(4).enumerate() {
            t.t.x.0[l] = x.translation.x;
            t.t.y.0[l] = x.translation.y;
            t.t.z.0[l] = x.translation.z;
            t.r.x.0[l] = x.rotation.x;
            t.r.y.0[l] = x.rotation.y;
            t.r.z.0[l] = x.rotation.z;
            t.r.w.0[l] = x.rotation.w;
            t.s.x.0[l] = x.scale.x;
            t.s.y.0[l] = x.scale.y;
            t.s.z.0[l] = x.scale.z;
        }
        t
    }

    #[inline(always)]
    fn get(self, i: usize) -> f32 {
        self.0[i]
    }

    #[inline(always)]
    fn set(&mut self, i: usize, v: f32) {
        self.0[i] = v;
    }
}

impl Mask for M4 {
    const NONE: M4 = M4([0; 4]);
    const ALL: M4 = M4([!0; 4]);

    #[inline(always)]
    fn and(self, o: M4) -> M4 {
        M4(four!(i => self.0[i] & o.0[i]))
    }

    #[inline(always)]
    fn or(self, o: M4) -> M4 {
        M4(four!(i => self.0[i] | o.0[i]))
    }

    #[inline(always)]
    fn not(self) -> M4 {
        M4(four!(i => !self.0[i]))
    }

    #[inline(always)]
    fn any(self) -> bool {
        (self.0[0] | self.0[1] | self.0[2] | self.0[3]) != 0
    }

    #[inline(always)]
    fn of(m: M) -> M4 {
        M4(four!(i => m.0[i]))
    }

    /// The four lanes, the others clear.
    #[inline(always)]
    fn m(self) -> M {
        let mut m = M::NONE;
        m.0[..4].copy_from_slice(&self.0);
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values that exercise every case: signs, zeros of both signs, tiny and huge
    /// magnitudes, infinities, NaN.
    fn samples() -> Vec<f32> {
        vec![
            0.0,
            -0.0,
            1.0,
            -2.5,
            3.25e-3,
            -7.0e5,
            1.0e-40,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            0.1,
            -0.3,
            2.0,
        ]
    }

    /// Lanes of `F` from `v` starting at `k`, wrapping.
    fn lanes(v: &[f32], k: usize) -> F {
        let mut f = F::splat(0.0);
        for (l, x) in f.0.iter_mut().enumerate() {
            *x = v[(k + l * 3) % v.len()];
        }
        f
    }

    fn same_bits(a: F4, b: F, what: &str) {
        for l in 0..4 {
            assert_eq!(a.0[l].to_bits(), b.0[l].to_bits(), "{what}, lane {l}");
        }
    }

    /// Every operation of [`F4`] gives [`F`]'s bits in its four lanes, and the
    /// conversions keep lanes 0-3 (the others of `f()` repeat lane 0, of `m()` are clear).
    #[test]
    fn every_operation_is_the_wide_types_per_lane() {
        let v = samples();
        for k in 0..v.len() {
            let (a, b) = (lanes(&v, k), lanes(&v, k + 5));
            let (a4, b4) = (F4::of(a), F4::of(b));
            same_bits(a4 + b4, a + b, "add");
            same_bits(a4 - b4, a - b, "sub");
            same_bits(a4 * b4, a * b, "mul");
            same_bits(a4 / b4, a / b, "div");
            same_bits(-a4, -a, "neg");
            same_bits(a4.sqrt(), a.sqrt(), "sqrt");
            same_bits(Lane::abs(a4), Lane::abs(a), "abs");
            same_bits(Lane::clamp01(a4), Lane::clamp01(a), "clamp01");
            same_bits(Lane::max(a4, b4), Lane::max(a, b), "max");
            for (m4, m, what) in [
                (a4.lt(b4), a.lt(b), "lt"),
                (a4.le(b4), a.le(b), "le"),
                (Lane::ne(a4, b4), a.ne(b), "ne"),
                (Lane::finite(a4), a.finite(), "finite"),
            ] {
                assert_eq!(m4.0, m.0[..4], "{what}");
                same_bits(F4::select(m4, a4, b4), F::select(m, a, b), "select");
                assert_eq!(m4.m().0[..4], m.0[..4]);
                assert!(m4.m().0[4..].iter().all(|&x| x == 0), "{what}: m() clears");
                assert_eq!(M4::of(m), m4);
                assert_eq!(m4.any(), m.0[..4].iter().any(|&x| x != 0), "{what}: any");
                assert_eq!(m4.not().0, m4.0.map(|x| !x));
            }
            let back = a4.f();
            same_bits(F4::of(back), a, "f() keeps the lanes");
            assert!(back.0[4..].iter().all(|x| x.to_bits() == a.0[0].to_bits()));
            let mut s = a4;
            s.set(2, 9.5);
            assert_eq!((s.get(2), s.get(1).to_bits()), (9.5, a.0[1].to_bits()));
        }
    }

    /// Gathering transforms fills the four lanes as [`F`]'s gather fills its first four.
    #[test]
    fn transforms_fill_the_four_lanes() {
        let ts: Vec<Transform> = (0..LANES)
            .map(|i| {
                let f = i as f32;
                Transform::new(
                    glam::Vec3::new(f, -f, 0.5 * f),
                    glam::Quat::from_rotation_y(0.1 * f),
                    glam::Vec3::splat(1.0 + f),
                )
            })
            .collect();
        let refs: [&Transform; LANES] = std::array::from_fn(|l| &ts[l]);
        let narrow = F4::transforms(&refs);
        let wide = <F as Lane>::transforms(&refs);
        assert_eq!(Trs::<F4>::of(&wide), narrow);
    }
}
