//! The AVX2 lane type: [`Fa`], two `__m256` per [`F`] (its sixteen lanes in two
//! halves), every operation two 256-bit instructions.
//!
//! Why it exists: the lane types over [`F`] (arrays of `f32`) leave vectorisation to
//! LLVM, which does it well in small functions but, in a whole inlined VRM step, splits a
//! good part of it into 128-bit halves and per-lane shuffles (measured: in `step_avx2` a
//! third of the arithmetic was 128-bit, with ~1 000 shuffles and inserts). Written with
//! the intrinsics, every lane operation is one instruction per half whatever the
//! context. A CPU with AVX-512 runs `lanes/avx512.rs`'s type instead (one instruction
//! for all sixteen lanes); this one is how the others run ([`crate::lanes::SimdUse::Avx2`]
//! forces it).
//!
//! Each operation is the IEEE operation per lane that [`F`]'s is (add, subtract,
//! multiply, divide, square root: correctly rounded; negation and `abs`: the sign bit;
//! comparisons: ordered, `!=` unordered as Rust's; select: bitwise), so both types give
//! the same bits; `tests` checks it operation by operation.
//!
//! **Soundness.** The intrinsics need AVX2. [`Fa`] and [`Ma`] are private to the crate
//! and only ever created inside functions compiled with `#[target_feature(enable =
//! "avx2")]` that are called where [`crate::lanes::Isa::of`] said
//! [`crate::lanes::Isa::Avx2`], which it says only after `is_x86_feature_detected!("avx2")`
//! said yes (the `*_avx2` functions of `lanes/types.rs`, `dynamics/chain/lanes/`,
//! `dynamics/vrm/lanes/` and `dynamics/cloth/lanes.rs`; `entry_avx2` in
//! `collide/entry_lanes.rs`, called only where an [`Fa`] exists already; the tests below
//! check the same first), so no AVX instruction runs on a CPU without it. The operations are `#[inline(always)]` so that they are
//! compiled inside those functions.
#![allow(unsafe_code)]

use super::Isa;
use super::{Lane, Mask, F, M};
use std::arch::x86_64::*;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Sixteen `f32` lanes in two AVX registers (lanes 0–7, 8–15).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Fa(__m256, __m256);

/// A per-lane condition of [`Fa`] (all bits set when true), in the same two halves.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ma(__m256, __m256);

impl PartialEq for Ma {
    #[inline(always)]
    fn eq(&self, o: &Ma) -> bool {
        // SAFETY: see the module's documentation. Every lane of a mask is all ones or all
        // zeros (comparisons, and `M`'s, make them so), so its sign bits are the mask.
        unsafe {
            _mm256_movemask_ps(self.0) == _mm256_movemask_ps(o.0)
                && _mm256_movemask_ps(self.1) == _mm256_movemask_ps(o.1)
        }
    }
}

/// `$intr` on both halves.
macro_rules! halves {
    ($intr:ident, $a:expr, $b:expr) => {
        // SAFETY: see the module's documentation (only run where AVX2 is).
        unsafe { ($intr($a.0, $b.0), $intr($a.1, $b.1)) }
    };
}

macro_rules! binary {
    ($tr:ident, $f:ident, $intr:ident) => {
        impl $tr for Fa {
            type Output = Fa;
            #[inline(always)]
            fn $f(self, o: Fa) -> Fa {
                let (lo, hi) = halves!($intr, self, o);
                Fa(lo, hi)
            }
        }
    };
}
binary!(Add, add, _mm256_add_ps);
binary!(Sub, sub, _mm256_sub_ps);
binary!(Mul, mul, _mm256_mul_ps);
binary!(Div, div, _mm256_div_ps);

impl Neg for Fa {
    type Output = Fa;
    #[inline(always)]
    fn neg(self) -> Fa {
        // Flips the sign bit, as `-x` does.
        let (lo, hi) = halves!(_mm256_xor_ps, self, Fa::splat(-0.0));
        Fa(lo, hi)
    }
}

impl Fa {
    /// `cmp` on both halves.
    #[inline(always)]
    fn cmp<const P: i32>(self, o: Fa) -> Ma {
        // SAFETY: see the module's documentation.
        unsafe {
            Ma(
                _mm256_cmp_ps::<P>(self.0, o.0),
                _mm256_cmp_ps::<P>(self.1, o.1),
            )
        }
    }
}

impl Lane for Fa {
    type M = Ma;
    const ISA: Isa = Isa::Avx2;
    #[inline(always)]
    fn splat(v: f32) -> Fa {
        // SAFETY: see the module's documentation.
        let h = unsafe { _mm256_set1_ps(v) };
        Fa(h, h)
    }
    #[inline(always)]
    fn of(f: F) -> Fa {
        // SAFETY: `F` is sixteen `f32` aligned to 64 bytes; two aligned loads of its halves
        // (the second 32 bytes on). (A load needs no AVX state beyond what the module's
        // documentation guarantees.)
        unsafe {
            Fa(
                _mm256_load_ps(f.0.as_ptr()),
                _mm256_load_ps(f.0.as_ptr().add(8)),
            )
        }
    }
    #[inline(always)]
    fn f(self) -> F {
        let mut f = F([0.0; 16]);
        // SAFETY: two aligned stores into `F`'s halves (64-byte aligned, 32 bytes each).
        unsafe {
            _mm256_store_ps(f.0.as_mut_ptr(), self.0);
            _mm256_store_ps(f.0.as_mut_ptr().add(8), self.1);
        }
        f
    }
    #[inline(always)]
    fn sqrt(self) -> Fa {
        // SAFETY: see the module's documentation.
        unsafe { Fa(_mm256_sqrt_ps(self.0), _mm256_sqrt_ps(self.1)) }
    }
    #[inline(always)]
    fn abs(self) -> Fa {
        // Clears the sign bit, as `f32::abs`.
        let (lo, hi) = halves!(_mm256_andnot_ps, Fa::splat(-0.0), self);
        Fa(lo, hi)
    }
    #[inline(always)]
    fn lt(self, o: Fa) -> Ma {
        // Ordered: false with NaN, as `<`.
        self.cmp::<_CMP_LT_OQ>(o)
    }
    #[inline(always)]
    fn le(self, o: Fa) -> Ma {
        // Ordered: false with NaN, as `<=`.
        self.cmp::<_CMP_LE_OQ>(o)
    }
    #[inline(always)]
    fn ne(self, o: Fa) -> Ma {
        // Unordered: true with NaN, as `!=`.
        self.cmp::<_CMP_NEQ_UQ>(o)
    }
    #[inline(always)]
    fn finite(self) -> Ma {
        // |x| < ∞: false for NaN (ordered) and for ±∞, true for every finite value.
        self.abs().lt(Fa::splat(f32::INFINITY))
    }
    #[inline(always)]
    fn bits_eq(self, o: Fa) -> Ma {
        // SAFETY: see the module's documentation (`_mm256_cmpeq_epi32` is AVX2, which the
        // functions that use `Fa` enable). The casts only reinterpret the bits; equal
        // 32-bit integers are equal `f32::to_bits`. (No closure: one is compiled without
        // its caller's target features.)
        unsafe {
            Ma(
                _mm256_castsi256_ps(_mm256_cmpeq_epi32(
                    _mm256_castps_si256(self.0),
                    _mm256_castps_si256(o.0),
                )),
                _mm256_castsi256_ps(_mm256_cmpeq_epi32(
                    _mm256_castps_si256(self.1),
                    _mm256_castps_si256(o.1),
                )),
            )
        }
    }
    #[inline(always)]
    fn select(m: Ma, a: Fa, b: Fa) -> Fa {
        // SAFETY: see the module's documentation. `m` is all ones or all zeros per lane,
        // so the sign-bit blend picks whole lanes, as `F::select`'s bitwise choice.
        unsafe {
            Fa(
                _mm256_blendv_ps(b.0, a.0, m.0),
                _mm256_blendv_ps(b.1, a.1, m.1),
            )
        }
    }
    #[inline(always)]
    fn max_gt(self, o: Fa) -> Fa {
        // SAFETY: see the module's documentation. `vmaxps` is `a > b ? a : b` exactly
        // (the second operand where either is NaN, and of two zeros).
        unsafe { Fa(_mm256_max_ps(self.0, o.0), _mm256_max_ps(self.1, o.1)) }
    }
    #[inline(always)]
    fn min_lt(self, o: Fa) -> Fa {
        // SAFETY: see the module's documentation. `vminps` is `a < b ? a : b` exactly.
        unsafe { Fa(_mm256_min_ps(self.0, o.0), _mm256_min_ps(self.1, o.1)) }
    }
}

impl Mask for Ma {
    // All bits clear / all bits set, as `M`'s constants. SAFETY: any 32 bytes are a valid
    // `__m256`; the transmute only reinterprets the bits.
    const NONE: Ma = {
        let h = unsafe { std::mem::transmute::<[u32; 8], __m256>([0; 8]) };
        Ma(h, h)
    };
    const ALL: Ma = {
        let h = unsafe { std::mem::transmute::<[u32; 8], __m256>([!0; 8]) };
        Ma(h, h)
    };
    #[inline(always)]
    fn and(self, o: Ma) -> Ma {
        let (lo, hi) = halves!(_mm256_and_ps, self, o);
        Ma(lo, hi)
    }
    #[inline(always)]
    fn or(self, o: Ma) -> Ma {
        let (lo, hi) = halves!(_mm256_or_ps, self, o);
        Ma(lo, hi)
    }
    #[inline(always)]
    fn not(self) -> Ma {
        let (lo, hi) = halves!(_mm256_xor_ps, self, Ma::ALL);
        Ma(lo, hi)
    }
    #[inline(always)]
    fn any(self) -> bool {
        // SAFETY: see the module's documentation. Lanes are all ones or all zeros, so a
        // lane is set exactly when its sign bit is.
        unsafe { _mm256_movemask_ps(_mm256_or_ps(self.0, self.1)) != 0 }
    }
    #[inline(always)]
    fn several(self) -> bool {
        // SAFETY: as in `any`: the sign bits are the mask, one bit per lane.
        let bits = unsafe { _mm256_movemask_ps(self.0) | _mm256_movemask_ps(self.1) << 8 };
        bits & bits.wrapping_sub(1) != 0
    }
    #[inline(always)]
    fn of(m: M) -> Ma {
        // SAFETY: `M` is sixteen `u32` aligned to 64 bytes: two aligned loads of its
        // halves' bits.
        unsafe {
            let p = m.0.as_ptr().cast::<f32>();
            Ma(_mm256_load_ps(p), _mm256_load_ps(p.add(8)))
        }
    }
    #[inline(always)]
    fn m(self) -> M {
        let mut m = M([0; 16]);
        // SAFETY: two aligned stores of the halves' bits into `M` (64-byte aligned).
        unsafe {
            let p = m.0.as_mut_ptr().cast::<f32>();
            _mm256_store_ps(p, self.0);
            _mm256_store_ps(p.add(8), self.1);
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lanes::check as lane_check;

    /// Runs `f` only where the CPU has AVX2 (the type's precondition), saying so else.
    fn with_avx2(f: impl FnOnce()) {
        if std::arch::is_x86_feature_detected!("avx2") {
            f()
        } else {
            eprintln!("skipped: this CPU has no AVX2, the AVX lane type cannot run here");
        }
    }

    #[test]
    fn avx_lane_operations_give_the_bits_of_f() {
        with_avx2(lane_check::operations_give_the_bits_of_f::<Fa>);
    }

    #[test]
    fn avx_transforms_are_the_lanes_of_each() {
        with_avx2(lane_check::transforms_are_the_lanes_of_each::<Fa>);
    }

    /// `several` is "more than one lane set", for every single lane and pair of lanes.
    #[test]
    fn several_means_more_than_one_lane() {
        with_avx2(lane_check::several_means_more_than_one_lane::<Fa>);
    }
}
