//! The AVX-512 lane type: [`Fz`], one `__m512` per [`F`], every operation one
//! 512-bit instruction, its conditions ([`Mz`]) one bit per lane in a mask register.
//!
//! Why it exists: on a CPU with AVX-512 (this project's 2-core AMD EPYC has it, at full
//! width), one instruction advances all sixteen lanes of a group where the AVX2 type
//! (`lanes/avx.rs`) needs two; conditions live in mask registers, so `select` is one
//! blend and `any` one test of a general register.
//!
//! Each operation is the IEEE operation per lane that [`F`]'s is (add, subtract,
//! multiply, divide, square root: correctly rounded; negation and `abs`: the sign bit;
//! comparisons: ordered, `!=` unordered as Rust's; select: per lane), so both types give
//! the same bits; `tests` checks it operation by operation.
//!
//! **Soundness.** The intrinsics need AVX-512 (F, and DQ/VL/BW enabled alongside). [`Fz`]
//! and [`Mz`] are private to the crate and only ever created inside functions compiled
//! with `#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]` that are
//! called where [`crate::lanes::Isa::of`] said [`crate::lanes::Isa::Avx512`], which it
//! says only after `is_x86_feature_detected!` found all four (the `*_avx512` functions
//! beside each `*_avx2` one; `entry_avx512` in `collide/entry_lanes.rs`, called only where an
//! [`Fz`] exists already; the tests below check the same first), so no AVX-512
//! instruction runs on a CPU without it. The operations are `#[inline(always)]` so that
//! they are compiled inside those functions.
#![allow(unsafe_code)]

use super::Isa;
use super::{Lane, Mask, Trs, F, M, Q, V3};
use crate::math::Transform;
use std::arch::x86_64::*;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Sixteen `f32` lanes in one AVX-512 register.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Fz(__m512);

/// A per-lane condition of [`Fz`]: one bit per lane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Mz(__mmask16);

macro_rules! binary {
    ($tr:ident, $f:ident, $intr:ident) => {
        impl $tr for Fz {
            type Output = Fz;
            #[inline(always)]
            fn $f(self, o: Fz) -> Fz {
                // SAFETY: see the module's documentation (only run where AVX-512 is).
                Fz(unsafe { $intr(self.0, o.0) })
            }
        }
    };
}
binary!(Add, add, _mm512_add_ps);
binary!(Sub, sub, _mm512_sub_ps);
binary!(Mul, mul, _mm512_mul_ps);
binary!(Div, div, _mm512_div_ps);

impl Neg for Fz {
    type Output = Fz;
    #[inline(always)]
    fn neg(self) -> Fz {
        // SAFETY: see the module's documentation. Flips the sign bit, as `-x` does.
        Fz(unsafe {
            _mm512_castsi512_ps(_mm512_xor_si512(
                _mm512_castps_si512(self.0),
                _mm512_set1_epi32(i32::MIN),
            ))
        })
    }
}

impl Lane for Fz {
    type M = Mz;
    const ISA: Isa = Isa::Avx512;
    #[inline(always)]
    fn splat(v: f32) -> Fz {
        // SAFETY: see the module's documentation.
        Fz(unsafe { _mm512_set1_ps(v) })
    }
    #[inline(always)]
    fn of(f: F) -> Fz {
        // SAFETY: `F` is sixteen `f32` aligned to 64 bytes; an aligned load of them.
        Fz(unsafe { _mm512_load_ps(f.0.as_ptr()) })
    }
    #[inline(always)]
    fn f(self) -> F {
        let mut f = F([0.0; 16]);
        // SAFETY: an aligned store into `F`'s sixteen `f32`, aligned to 64 bytes.
        unsafe { _mm512_store_ps(f.0.as_mut_ptr(), self.0) };
        f
    }
    #[inline(always)]
    fn sqrt(self) -> Fz {
        // SAFETY: see the module's documentation.
        Fz(unsafe { _mm512_sqrt_ps(self.0) })
    }
    #[inline(always)]
    fn abs(self) -> Fz {
        // SAFETY: see the module's documentation. Clears the sign bit, as `f32::abs`.
        Fz(unsafe { _mm512_abs_ps(self.0) })
    }
    #[inline(always)]
    fn lt(self, o: Fz) -> Mz {
        // SAFETY: see the module's documentation. Ordered: false with NaN, as `<`.
        Mz(unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(self.0, o.0) })
    }
    #[inline(always)]
    fn le(self, o: Fz) -> Mz {
        // SAFETY: see the module's documentation. Ordered: false with NaN, as `<=`.
        Mz(unsafe { _mm512_cmp_ps_mask::<_CMP_LE_OQ>(self.0, o.0) })
    }
    #[inline(always)]
    fn ne(self, o: Fz) -> Mz {
        // SAFETY: see the module's documentation. Unordered: true with NaN, as `!=`.
        Mz(unsafe { _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(self.0, o.0) })
    }
    #[inline(always)]
    fn finite(self) -> Mz {
        // |x| < ∞: false for NaN (ordered) and for ±∞, true for every finite value.
        self.abs().lt(Fz::splat(f32::INFINITY))
    }
    #[inline(always)]
    fn bits_eq(self, o: Fz) -> Mz {
        // SAFETY: see the module's documentation. Equal 32-bit integers are equal
        // `f32::to_bits`.
        Mz(unsafe {
            _mm512_cmpeq_epi32_mask(_mm512_castps_si512(self.0), _mm512_castps_si512(o.0))
        })
    }
    #[inline(always)]
    fn select(m: Mz, a: Fz, b: Fz) -> Fz {
        // SAFETY: see the module's documentation. Picks `a` where the lane's bit is set.
        Fz(unsafe { _mm512_mask_blend_ps(m.0, b.0, a.0) })
    }
    /// Each transform's ten `f32` in one masked load (a row), then the 16×16
    /// transposition of the rows: 64 shuffles where setting the lanes one by one takes
    /// 160 scalar loads and stores (and the wide loads after them wait for those stores).
    #[inline(always)]
    fn transforms(ts: &[&Transform; 16]) -> Trs<Fz> {
        // Where the fields lie, in `f32` (Rust chooses the order: asked, not assumed;
        // glam's `Vec3` is `x, y, z` and its `Quat` `x, y, z, w`).
        const T: usize = std::mem::offset_of!(Transform, translation) / 4;
        const R: usize = std::mem::offset_of!(Transform, rotation) / 4;
        const S: usize = std::mem::offset_of!(Transform, scale) / 4;
        const _: () = assert!(T + 3 <= 16 && R + 4 <= 16 && S + 3 <= 16);
        const _: () = assert!(std::mem::size_of::<Transform>() <= 64);
        const MASK: u16 = (0b111 << T) | (0b1111 << R) | (0b111 << S);
        let mut rows = [Fz::splat(0.0).0; 16];
        for (row, t) in rows.iter_mut().zip(ts) {
            // SAFETY: see the module's documentation. The load reads only the masked
            // elements, the ten `f32` of one `Transform` behind a reference (its padding
            // and whatever follows it are not read: masked-out elements are not
            // accessed and cannot fault).
            *row = unsafe { _mm512_maskz_loadu_ps(MASK, std::ptr::from_ref(*t).cast::<f32>()) };
        }
        let c = transpose(&rows).map(Fz);
        Trs {
            t: V3 {
                x: c[T],
                y: c[T + 1],
                z: c[T + 2],
            },
            r: Q {
                x: c[R],
                y: c[R + 1],
                z: c[R + 2],
                w: c[R + 3],
            },
            s: V3 {
                x: c[S],
                y: c[S + 1],
                z: c[S + 2],
            },
        }
    }
    #[inline(always)]
    fn max_gt(self, o: Fz) -> Fz {
        // SAFETY: see the module's documentation. `vmaxps` is `a > b ? a : b` exactly
        // (the second operand where either is NaN, and of two zeros).
        Fz(unsafe { _mm512_max_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn min_lt(self, o: Fz) -> Fz {
        // SAFETY: see the module's documentation. `vminps` is `a < b ? a : b` exactly.
        Fz(unsafe { _mm512_min_ps(self.0, o.0) })
    }
}

/// The 16×16 transposition: element `l` of column `e` is element `e` of row `l`.
/// Interleaves of 32-bit and 64-bit elements gather four rows' columns in each 128-bit
/// block, then two shuffles of blocks put each column's four blocks together.
#[inline(always)]
fn transpose(r: &[__m512; 16]) -> [__m512; 16] {
    // Rows 2i and 2i+1 interleaved: [2i] holds their columns 0, 1 (4, 5 in the next
    // block, and so on), [2i+1] their columns 2, 3.
    let mut t = [r[0]; 16];
    for i in (0..16).step_by(2) {
        t[i] = unpack(r[i], r[i + 1], false);
        t[i + 1] = unpack(r[i], r[i + 1], true);
    }
    // Rows 4g..4g+4: [4g+k] holds column k of the four rows in block 0 (column 4b+k in
    // block b).
    let mut u = [r[0]; 16];
    for g in (0..16).step_by(4) {
        u[g] = unpack64(t[g], t[g + 2], false);
        u[g + 1] = unpack64(t[g], t[g + 2], true);
        u[g + 2] = unpack64(t[g + 1], t[g + 3], false);
        u[g + 3] = unpack64(t[g + 1], t[g + 3], true);
    }
    // Column 4b+k: block b of u[k], u[4+k], u[8+k], u[12+k], in that order.
    let mut c = [r[0]; 16];
    for k in 0..4 {
        let (v0, w0) = (
            blocks(u[k], u[4 + k], false),
            blocks(u[8 + k], u[12 + k], false),
        );
        let (v1, w1) = (
            blocks(u[k], u[4 + k], true),
            blocks(u[8 + k], u[12 + k], true),
        );
        c[k] = blocks(v0, w0, false);
        c[8 + k] = blocks(v0, w0, true);
        c[4 + k] = blocks(v1, w1, false);
        c[12 + k] = blocks(v1, w1, true);
    }
    c
}

/// The 32-bit elements of `a` and `b` interleaved in each 128-bit block: the low two
/// (`vunpcklps`) or the high two. (Functions, not closures: see `collide::lanes::select_max`.)
#[inline(always)]
fn unpack(a: __m512, b: __m512, high: bool) -> __m512 {
    // SAFETY: see the module's documentation; register operations only.
    unsafe {
        match high {
            false => _mm512_unpacklo_ps(a, b),
            true => _mm512_unpackhi_ps(a, b),
        }
    }
}

/// [`unpack`] of 64-bit elements.
#[inline(always)]
fn unpack64(a: __m512, b: __m512, high: bool) -> __m512 {
    // SAFETY: see the module's documentation; register operations only.
    unsafe {
        let (a, b) = (_mm512_castps_pd(a), _mm512_castps_pd(b));
        _mm512_castpd_ps(match high {
            false => _mm512_unpacklo_pd(a, b),
            true => _mm512_unpackhi_pd(a, b),
        })
    }
}

/// The even 128-bit blocks (0, 2) of `a` then of `b`, or the odd ones (1, 3).
#[inline(always)]
fn blocks(a: __m512, b: __m512, odd: bool) -> __m512 {
    // SAFETY: see the module's documentation; register operations only.
    unsafe {
        match odd {
            false => _mm512_shuffle_f32x4::<0x88>(a, b),
            true => _mm512_shuffle_f32x4::<0xDD>(a, b),
        }
    }
}

impl Mask for Mz {
    const NONE: Mz = Mz(0);
    const ALL: Mz = Mz(0xffff);
    #[inline(always)]
    fn and(self, o: Mz) -> Mz {
        Mz(self.0 & o.0)
    }
    #[inline(always)]
    fn or(self, o: Mz) -> Mz {
        Mz(self.0 | o.0)
    }
    #[inline(always)]
    fn not(self) -> Mz {
        Mz(!self.0)
    }
    #[inline(always)]
    fn any(self) -> bool {
        self.0 != 0
    }
    #[inline(always)]
    fn several(self) -> bool {
        self.0 & self.0.wrapping_sub(1) != 0
    }
    #[inline(always)]
    fn of(m: M) -> Mz {
        // SAFETY: `M` is sixteen `u32` aligned to 64 bytes: an aligned load; a lane is
        // set where its bits are not zero (they are all ones or all zeros).
        Mz(unsafe {
            let v = _mm512_load_si512(m.0.as_ptr().cast());
            _mm512_test_epi32_mask(v, v)
        })
    }
    #[inline(always)]
    fn m(self) -> M {
        let mut m = M([0; 16]);
        // SAFETY: all ones in the set lanes, stored aligned into `M` (64 bytes).
        unsafe {
            _mm512_store_si512(
                m.0.as_mut_ptr().cast(),
                _mm512_maskz_mov_epi32(self.0, _mm512_set1_epi32(-1)),
            )
        };
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lanes::check as lane_check;

    /// Runs `f` only where the CPU has AVX-512 (the type's precondition), saying so else.
    fn with_avx512(f: impl FnOnce()) {
        if Isa::of(crate::lanes::SimdUse::Auto) == Isa::Avx512 {
            f()
        } else {
            eprintln!("skipped: this CPU has no AVX-512, the AVX-512 lane type cannot run here");
        }
    }

    #[test]
    fn avx512_lane_operations_give_the_bits_of_f() {
        with_avx512(lane_check::operations_give_the_bits_of_f::<Fz>);
    }

    #[test]
    fn avx512_transforms_are_the_lanes_of_each() {
        with_avx512(lane_check::transforms_are_the_lanes_of_each::<Fz>);
    }

    /// `several` is "more than one lane set", for every single lane and pair of lanes.
    #[test]
    fn several_means_more_than_one_lane() {
        with_avx512(lane_check::several_means_more_than_one_lane::<Fz>);
    }
}
