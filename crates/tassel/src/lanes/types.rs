//! The lane types: one `f32` per lane (a character of a crowd, a chain or spring of one
//! character), [`LANES`] lanes side by side, so that one instruction advances several.
//!
//! Every operation repeats, lane by lane, the exact sequence of IEEE operations that glam
//! 0.32 (SSE2 build) and [`crate::math`] perform for one character: the same products,
//! summed in the same order, the same square roots and divisions. That is what lets the
//! crowd path give the single-character path's results bit for bit.
//!
//! [`V3`], [`Q`] and [`Trs`] are generic over their per-lane type ([`Lane`]): [`F`],
//! whose per-element loops are left to the compiler to vectorise (plain stable Rust,
//! every target), and on x86_64 the private explicit types, used inside the lane
//! steps' AVX-512 and AVX2 functions only: `lanes/avx512.rs` (one 512-bit instruction per
//! operation) and `lanes/avx.rs` (two 256-bit ones). [`crate::lanes::Isa::of`] chooses
//! at run time. State stays in [`F`]; `of` and `f` convert (the same bytes).

use crate::math::Transform;
use glam::{Quat, Vec3};
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Characters per lane group: 16 on x86_64, where one AVX-512 register holds them (a CPU
/// with AVX2 only takes them in two registers, `lanes/avx.rs`), 8 elsewhere (the
/// portable lane type over arrays, which the compiler splits into the target's vectors:
/// sixteen would need more registers than SSE or NEON have, measured 1.4x slower on
/// x86_64 without AVX).
pub const LANES: usize = if cfg!(target_arch = "x86_64") { 16 } else { 8 };

/// One `f32` per lane.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct F(pub [f32; LANES]);

/// A per-lane condition (all bits set when true).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C, align(64))]
pub struct M(pub [u32; LANES]);

/// `[e(0), e(1), .., e(LANES - 1)]`, written out lane by lane: `each!(i => expr)` with `i` a
/// constant index in each element. No loop: the lane steps inline thousands of these
/// operations into one function, and as loops (even ones the compiler unrolls in the end)
/// they made LLVM's loop passes quadratic in that function's size — 10 000 loops in the
/// portable chain step, 10 of the 11 minutes of a release build of this crate (measured
/// with `-Z llvm-time-trace`). The operations per lane are the same.
#[cfg(target_arch = "x86_64")]
macro_rules! each {
    ($i:ident => $e:expr) => {
        each!(@ $i => $e; 0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15)
    };
    (@ $i:ident => $e:expr; $($n:literal)*) => {
        [$({ let $i: usize = $n; $e }),*]
    };
}
#[cfg(not(target_arch = "x86_64"))]
macro_rules! each {
    ($i:ident => $e:expr) => {
        each!(@ $i => $e; 0 1 2 3 4 5 6 7)
    };
    (@ $i:ident => $e:expr; $($n:literal)*) => {
        [$({ let $i: usize = $n; $e }),*]
    };
}
/// `a[0] op a[1] op .. op a[LANES - 1]` (pairwise), written out as `each!` is: no loop.
#[cfg(target_arch = "x86_64")]
macro_rules! reduce {
    ($a:expr, $op:tt) => {{
        let a = $a;
        (((a[0] $op a[1]) $op (a[2] $op a[3])) $op ((a[4] $op a[5]) $op (a[6] $op a[7])))
            $op (((a[8] $op a[9]) $op (a[10] $op a[11])) $op ((a[12] $op a[13]) $op (a[14] $op a[15])))
    }};
}
#[cfg(not(target_arch = "x86_64"))]
macro_rules! reduce {
    ($a:expr, $op:tt) => {{
        let a = $a;
        ((a[0] $op a[1]) $op (a[2] $op a[3])) $op ((a[4] $op a[5]) $op (a[6] $op a[7]))
    }};
}
const _: () = assert!(LANES == if cfg!(target_arch = "x86_64") { 16 } else { 8 });

macro_rules! lanewise {
    ($a:expr, $b:expr, $op:tt) => {{
        let (a, b) = ($a.0, $b.0);
        F(each!(i => a[i] $op b[i]))
    }};
}

impl Add for F {
    type Output = F;
    #[inline(always)]
    fn add(self, o: F) -> F {
        lanewise!(self, o, +)
    }
}
impl Sub for F {
    type Output = F;
    #[inline(always)]
    fn sub(self, o: F) -> F {
        lanewise!(self, o, -)
    }
}
impl Mul for F {
    type Output = F;
    #[inline(always)]
    fn mul(self, o: F) -> F {
        lanewise!(self, o, *)
    }
}
impl Div for F {
    type Output = F;
    #[inline(always)]
    fn div(self, o: F) -> F {
        lanewise!(self, o, /)
    }
}
impl Neg for F {
    type Output = F;
    #[inline(always)]
    fn neg(self) -> F {
        F(each!(i => -self.0[i]))
    }
}

impl F {
    /// Every lane `v`.
    #[inline(always)]
    pub fn splat(v: f32) -> F {
        F([v; LANES])
    }

    /// Lane-wise square root.
    #[inline(always)]
    pub fn sqrt(self) -> F {
        F(each!(i => self.0[i].sqrt()))
    }

    /// `self < o` per lane.
    #[inline(always)]
    pub fn lt(self, o: F) -> M {
        M(each!(i => if self.0[i] < o.0[i] { !0 } else { 0 }))
    }

    /// `self <= o` per lane.
    #[inline(always)]
    pub fn le(self, o: F) -> M {
        M(each!(i => if self.0[i] <= o.0[i] { !0 } else { 0 }))
    }

    /// `self != o` per lane (IEEE: `-0 == 0`, NaN differs from everything).
    #[inline(always)]
    pub fn ne(self, o: F) -> M {
        M(each!(i => if self.0[i] != o.0[i] { !0 } else { 0 }))
    }

    /// `self > o` per lane.
    #[inline(always)]
    pub fn gt(self, o: F) -> M {
        o.lt(self)
    }

    /// Finite per lane (not NaN, not infinite).
    #[inline(always)]
    pub fn finite(self) -> M {
        M(
            each!(i => if (self.0[i].to_bits() & 0x7f80_0000) != 0x7f80_0000 {
                !0
            } else {
                0
            }),
        )
    }

    /// `m ? a : b` per lane.
    #[inline(always)]
    pub fn select(m: M, a: F, b: F) -> F {
        F(each!(i => f32::from_bits((a.0[i].to_bits() & m.0[i]) | (b.0[i].to_bits() & !m.0[i]))))
    }
}

impl M {
    /// No lane.
    pub const NONE: M = M([0; LANES]);
    /// Every lane.
    pub const ALL: M = M([!0; LANES]);

    /// Both conditions.
    #[inline(always)]
    pub fn and(self, o: M) -> M {
        M(each!(i => self.0[i] & o.0[i]))
    }

    /// Either condition.
    #[inline(always)]
    pub fn or(self, o: M) -> M {
        M(each!(i => self.0[i] | o.0[i]))
    }

    /// The opposite condition.
    #[inline(always)]
    #[allow(clippy::should_implement_trait)]
    pub fn not(self) -> M {
        M(each!(i => !self.0[i]))
    }

    /// Any lane set.
    #[inline(always)]
    pub fn any(self) -> bool {
        // An OR over the lanes, without a branch per lane (one vector test). A loop, unlike
        // the other operations (`each!`): written out pairwise, the portable chain crowd
        // ran 14 % slower (`tassel bench --crowd 200 --simd portable`), and the steps hold
        // few of these.
        self.0.iter().fold(0, |a, &b| a | b) != 0
    }

    /// Lane `i` set.
    #[inline(always)]
    pub fn get(self, i: usize) -> bool {
        self.0[i] != 0
    }

    /// From one `bool` per lane.
    pub fn from_bools(b: [bool; LANES]) -> M {
        M(each!(i => if b[i] { !0 } else { 0 }))
    }
}

/// What the lane types ([`V3`], [`Q`], [`Trs`]) need of their per-lane `f32`: [`F`]
/// (plain arrays the compiler vectorises, every target) and, on x86_64, the crowd's AVX
/// type (explicit 256-bit instructions, used only after the CPU was found to have AVX2).
/// Every operation is the IEEE operation per lane, so both give the same bits.
pub trait Lane:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// The per-lane condition of this type.
    type M: Mask;
    /// Which instructions this type's values need (an explicit type's exist only inside
    /// functions compiled with them, after the CPU was found to have them).
    const ISA: super::Isa = super::Isa::Portable;
    /// How many lanes it holds: [`LANES`], or fewer (the first of [`F`]'s).
    const WIDTH: usize = LANES;
    /// Every lane `v`.
    fn splat(v: f32) -> Self;
    /// From [`F`] (the same lanes).
    fn of(f: F) -> Self;
    /// As [`F`] (the same lanes).
    fn f(self) -> F;
    /// Lane-wise square root.
    fn sqrt(self) -> Self;
    /// `|self|` per lane.
    fn abs(self) -> Self;
    /// `self < o` per lane.
    fn lt(self, o: Self) -> Self::M;
    /// `self <= o` per lane.
    fn le(self, o: Self) -> Self::M;
    /// `self != o` per lane.
    fn ne(self, o: Self) -> Self::M;
    /// `self > o` per lane.
    #[inline(always)]
    fn gt(self, o: Self) -> Self::M {
        o.lt(self)
    }
    /// Finite per lane.
    fn finite(self) -> Self::M;
    /// `m ? a : b` per lane.
    fn select(m: Self::M, a: Self, b: Self) -> Self;
    /// `self > o ? self : o` per lane (glam's `max`: `o` where either is NaN or both are
    /// zeros), one instruction in the explicit types.
    #[inline(always)]
    fn max_gt(self, o: Self) -> Self {
        Self::select(self.gt(o), self, o)
    }
    /// `self < o ? self : o` per lane (glam's `min`), one instruction in the explicit
    /// types.
    #[inline(always)]
    fn min_lt(self, o: Self) -> Self {
        Self::select(self.lt(o), self, o)
    }
    /// `f32::clamp(self, 0, 1)` per lane.
    #[inline(always)]
    fn clamp01(self) -> Self {
        Self::of(self.f().clamp01())
    }
    /// `f32::max` per lane.
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Self::of(self.f().max(o.f()))
    }
    /// `f32::signum` per lane.
    #[inline(always)]
    fn signum(self) -> Self {
        let a = self.f().0;
        Self::of(F(each!(i => a[i].signum())))
    }
    /// Whether the lanes hold the same bits (unlike `==`: `-0` and `0` differ, a NaN
    /// matches its own bits), as `f32::to_bits` compared.
    #[inline(always)]
    fn bits_eq(self, o: Self) -> Self::M {
        let (a, b) = (self.f(), o.f());
        Self::M::of(M(
            each!(i => if a.0[i].to_bits() == b.0[i].to_bits() { !0 } else { 0 }),
        ))
    }
    /// [`LANES`] transforms as lanes: lane `l` of the result is `ts[l]`.
    #[inline(always)]
    fn transforms(ts: &[&Transform; LANES]) -> Trs<Self> {
        let mut t = Trs::<F>::splat(&Transform::IDENTITY);
        for (l, x) in ts.iter().enumerate() {
            t.set(l, x);
        }
        Trs::of(&t)
    }
    /// Lane `i`.
    #[inline(always)]
    fn get(self, i: usize) -> f32 {
        self.f().0[i]
    }
    /// Sets lane `i`.
    #[inline(always)]
    fn set(&mut self, i: usize, v: f32) {
        let mut f = self.f();
        f.0[i] = v;
        *self = Self::of(f);
    }
}

/// A per-lane condition of a [`Lane`] type.
pub trait Mask: Copy + PartialEq {
    /// No lane.
    const NONE: Self;
    /// Every lane.
    const ALL: Self;
    /// Both conditions.
    fn and(self, o: Self) -> Self;
    /// Either condition.
    fn or(self, o: Self) -> Self;
    /// The opposite condition.
    fn not(self) -> Self;
    /// Any lane set.
    fn any(self) -> bool;
    /// More than one lane set.
    #[inline(always)]
    fn several(self) -> bool {
        let a = self.m().0;
        reduce!(each!(i => (a[i] != 0) as u32), +) > 1
    }
    /// From [`M`] (the same lanes).
    fn of(m: M) -> Self;
    /// As [`M`] (the same lanes).
    fn m(self) -> M;
}

impl Lane for F {
    type M = M;
    #[inline(always)]
    fn splat(v: f32) -> F {
        F::splat(v)
    }
    #[inline(always)]
    fn of(f: F) -> F {
        f
    }
    #[inline(always)]
    fn f(self) -> F {
        self
    }
    #[inline(always)]
    fn sqrt(self) -> F {
        F::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> F {
        F::abs(self)
    }
    #[inline(always)]
    fn lt(self, o: F) -> M {
        F::lt(self, o)
    }
    #[inline(always)]
    fn le(self, o: F) -> M {
        F::le(self, o)
    }
    #[inline(always)]
    fn ne(self, o: F) -> M {
        F::ne(self, o)
    }
    #[inline(always)]
    fn finite(self) -> M {
        F::finite(self)
    }
    #[inline(always)]
    fn select(m: M, a: F, b: F) -> F {
        F::select(m, a, b)
    }
    #[inline(always)]
    fn clamp01(self) -> F {
        F::clamp01(self)
    }
    #[inline(always)]
    fn max(self, o: F) -> F {
        F::max(self, o)
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

impl Mask for M {
    const NONE: M = M([0; LANES]);
    const ALL: M = M([!0; LANES]);
    #[inline(always)]
    fn and(self, o: M) -> M {
        M::and(self, o)
    }
    #[inline(always)]
    fn or(self, o: M) -> M {
        M::or(self, o)
    }
    #[inline(always)]
    fn not(self) -> M {
        M::not(self)
    }
    #[inline(always)]
    fn any(self) -> bool {
        M::any(self)
    }
    #[inline(always)]
    fn of(m: M) -> M {
        m
    }
    #[inline(always)]
    fn m(self) -> M {
        self
    }
}

/// A `Vec3` per lane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<T = F> {
    /// X per lane.
    pub x: T,
    /// Y per lane.
    pub y: T,
    /// Z per lane.
    pub z: T,
}

impl<T: Lane> Add for V3<T> {
    type Output = V3<T>;
    #[inline(always)]
    fn add(self, o: V3<T>) -> V3<T> {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}
impl<T: Lane> Sub for V3<T> {
    type Output = V3<T>;
    #[inline(always)]
    fn sub(self, o: V3<T>) -> V3<T> {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}
impl<T: Lane> Neg for V3<T> {
    type Output = V3<T>;
    #[inline(always)]
    fn neg(self) -> V3<T> {
        V3 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}
/// Component-wise product.
impl<T: Lane> Mul for V3<T> {
    type Output = V3<T>;
    #[inline(always)]
    fn mul(self, o: V3<T>) -> V3<T> {
        V3 {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }
}
/// Component-wise quotient.
impl<T: Lane> Div for V3<T> {
    type Output = V3<T>;
    #[inline(always)]
    fn div(self, o: V3<T>) -> V3<T> {
        V3 {
            x: self.x / o.x,
            y: self.y / o.y,
            z: self.z / o.z,
        }
    }
}
impl<T: Lane> Mul<T> for V3<T> {
    type Output = V3<T>;
    #[inline(always)]
    fn mul(self, s: T) -> V3<T> {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}
impl<T: Lane> Div<T> for V3<T> {
    type Output = V3<T>;
    #[inline(always)]
    fn div(self, s: T) -> V3<T> {
        V3 {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
}

impl<T: Lane> V3<T> {
    /// Every lane `v`.
    #[inline(always)]
    pub fn splat(v: Vec3) -> V3<T> {
        V3 {
            x: T::splat(v.x),
            y: T::splat(v.y),
            z: T::splat(v.z),
        }
    }

    /// glam's `Vec3::dot`: `(x·x' + y·y') + z·z'`.
    #[inline(always)]
    pub fn dot(self, o: V3<T>) -> T {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// glam's `Vec3::cross`.
    #[inline(always)]
    pub fn cross(self, o: V3<T>) -> V3<T> {
        V3 {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }

    /// glam's `Vec3::length`.
    #[inline(always)]
    pub fn length(self) -> T {
        self.dot(self).sqrt()
    }

    /// [`crate::math::normalize_or`] per lane.
    #[inline(always)]
    pub fn normalize_or(self, fallback: V3<T>) -> V3<T> {
        let len2 = self.dot(self);
        let ok = len2.gt(T::splat(1e-20)).and(len2.finite());
        V3::select(ok, self / len2.sqrt(), fallback)
    }

    /// Every component `v` (a vector plus or minus a scalar, as glam's `Vec3 ± f32`).
    #[inline(always)]
    pub fn splat_f(v: T) -> V3<T> {
        V3 { x: v, y: v, z: v }
    }

    /// glam's `Vec3::abs`.
    #[inline(always)]
    pub fn abs(self) -> V3<T> {
        V3 {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }

    /// `m ? a : b` per lane.
    #[inline(always)]
    pub fn select(m: T::M, a: V3<T>, b: V3<T>) -> V3<T> {
        V3 {
            x: T::select(m, a.x, b.x),
            y: T::select(m, a.y, b.y),
            z: T::select(m, a.z, b.z),
        }
    }

    /// The same bits in every component, per lane ([`Lane::bits_eq`]).
    #[inline(always)]
    pub fn bits_eq(self, o: V3<T>) -> T::M {
        self.x
            .bits_eq(o.x)
            .and(self.y.bits_eq(o.y))
            .and(self.z.bits_eq(o.z))
    }

    /// Finite in every component, per lane.
    #[inline(always)]
    pub fn finite(self) -> T::M {
        self.x.finite().and(self.y.finite()).and(self.z.finite())
    }

    /// Lane `i`.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Vec3 {
        Vec3::new(self.x.get(i), self.y.get(i), self.z.get(i))
    }

    /// Sets lane `i`.
    #[inline(always)]
    pub fn set(&mut self, i: usize, v: Vec3) {
        self.x.set(i, v.x);
        self.y.set(i, v.y);
        self.z.set(i, v.z);
    }
}

impl V3 {
    /// Every lane zero.
    pub const ZERO: V3 = V3 {
        x: F([0.0; LANES]),
        y: F([0.0; LANES]),
        z: F([0.0; LANES]),
    };
}

/// A `Quat` per lane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Q<T = F> {
    /// X per lane.
    pub x: T,
    /// Y per lane.
    pub y: T,
    /// Z per lane.
    pub z: T,
    /// W per lane.
    pub w: T,
}

impl<T: Lane> Q<T> {
    /// Every lane `q`.
    #[inline(always)]
    pub fn splat(q: Quat) -> Q<T> {
        Q {
            x: T::splat(q.x),
            y: T::splat(q.y),
            z: T::splat(q.z),
            w: T::splat(q.w),
        }
    }

    /// glam's SSE2 `Quat::mul_quat`: `(w·r + x·r_wzyx·±) + (y·r_zwxy·± + z·r_yxwz·±)`.
    #[inline(always)]
    pub fn mul_quat(self, r: Q<T>) -> Q<T> {
        let l = self;
        // The four partial products, lane by lane as glam's shuffled vectors hold them.
        let tw = [l.w * r.x, l.w * r.y, l.w * r.z, l.w * r.w];
        let tx = [l.x * r.w, -(l.x * r.z), l.x * r.y, -(l.x * r.x)];
        let ty = [l.y * r.z, l.y * r.w, -(l.y * r.x), -(l.y * r.y)];
        let tz = [-(l.z * r.y), l.z * r.x, l.z * r.w, -(l.z * r.z)];
        // (No closure: one is compiled without its caller's target features.)
        Q {
            x: (tw[0] + tx[0]) + (ty[0] + tz[0]),
            y: (tw[1] + tx[1]) + (ty[1] + tz[1]),
            z: (tw[2] + tx[2]) + (ty[2] + tz[2]),
            w: (tw[3] + tx[3]) + (ty[3] + tz[3]),
        }
    }

    /// glam's SSE2 `Quat::mul_vec3`:
    /// `(v·(w² − b·b) + b·(2(v·b))) + (b × v)·(2w)`.
    #[inline(always)]
    pub fn mul_vec3(self, v: V3<T>) -> V3<T> {
        let b = V3 {
            x: self.x,
            y: self.y,
            z: self.z,
        };
        let w = self.w;
        let two = T::splat(2.0);
        let k = w * w - b.dot(b);
        let d2 = v.dot(b) * two;
        let w2 = w * two;
        let c = sse_cross(b, v);
        (v * k + b * d2) + c * w2
    }

    /// glam's SSE2 `Quat::normalize`: divided by `sqrt((x² + z²) + (y² + w²))`.
    #[inline(always)]
    pub fn normalize(self) -> Q<T> {
        let len = self.dot(self).sqrt();
        Q {
            x: self.x / len,
            y: self.y / len,
            z: self.z / len,
            w: self.w / len,
        }
    }

    /// glam's SSE2 four-component dot product: `(x·x' + z·z') + (y·y' + w·w')`.
    #[inline(always)]
    pub fn dot(self, o: Q<T>) -> T {
        (self.x * o.x + self.z * o.z) + (self.y * o.y + self.w * o.w)
    }

    /// The conjugate (the inverse of a unit quaternion).
    #[inline(always)]
    pub fn conjugate(self) -> Q<T> {
        Q {
            x: -self.x,
            y: -self.y,
            z: -self.z,
            w: self.w,
        }
    }

    /// `m ? a : b` per lane.
    #[inline(always)]
    pub fn select(m: T::M, a: Q<T>, b: Q<T>) -> Q<T> {
        Q {
            x: T::select(m, a.x, b.x),
            y: T::select(m, a.y, b.y),
            z: T::select(m, a.z, b.z),
            w: T::select(m, a.w, b.w),
        }
    }

    /// Finite in every component, per lane.
    #[inline(always)]
    pub fn finite(self) -> T::M {
        self.x
            .finite()
            .and(self.y.finite())
            .and(self.z.finite())
            .and(self.w.finite())
    }

    /// Lane `i`.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Quat {
        Quat::from_xyzw(self.x.get(i), self.y.get(i), self.z.get(i), self.w.get(i))
    }

    /// Sets lane `i`.
    #[inline(always)]
    pub fn set(&mut self, i: usize, q: Quat) {
        self.x.set(i, q.x);
        self.y.set(i, q.y);
        self.z.set(i, q.z);
        self.w.set(i, q.w);
    }
}

/// glam's SSE2 `Vec3A::cross` (the same products as `Vec3::cross`, so the same bits).
#[inline(always)]
fn sse_cross<T: Lane>(a: V3<T>, b: V3<T>) -> V3<T> {
    V3 {
        x: a.y * b.z - b.y * a.z,
        y: a.z * b.x - b.z * a.x,
        z: a.x * b.y - b.x * a.y,
    }
}

/// A [`Transform`] per lane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs<T = F> {
    /// Translation.
    pub t: V3<T>,
    /// Rotation.
    pub r: Q<T>,
    /// Scale.
    pub s: V3<T>,
}

impl<T: Lane> Trs<T> {
    /// Every lane `t`.
    #[inline(always)]
    pub fn splat(t: &Transform) -> Trs<T> {
        Trs {
            t: V3::splat(t.translation),
            r: Q::splat(t.rotation),
            s: V3::splat(t.scale),
        }
    }

    /// [`Transform::transform_point`].
    #[inline(always)]
    pub fn transform_point(&self, p: V3<T>) -> V3<T> {
        self.t + self.r.mul_vec3(self.s * p)
    }

    /// [`Transform::inverse_transform_point`].
    #[inline(always)]
    pub fn inverse_transform_point(&self, p: V3<T>) -> V3<T> {
        self.r.conjugate().mul_vec3(p - self.t) / self.s
    }

    /// [`Transform::mul_transform`]: `self * child`.
    #[inline(always)]
    pub fn mul(&self, child: &Trs<T>) -> Trs<T> {
        Trs {
            t: self.transform_point(child.t),
            r: self.r.mul_quat(child.r).normalize(),
            s: self.s * child.s,
        }
    }

    /// `m ? a : b` per lane.
    #[inline(always)]
    pub fn select(m: T::M, a: &Trs<T>, b: &Trs<T>) -> Trs<T> {
        Trs {
            t: V3::select(m, a.t, b.t),
            r: Q::select(m, a.r, b.r),
            s: V3::select(m, a.s, b.s),
        }
    }

    /// Lane `i`.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Transform {
        Transform::new(self.t.get(i), self.r.get(i), self.s.get(i))
    }

    /// Sets lane `i`.
    #[inline(always)]
    pub fn set(&mut self, i: usize, t: &Transform) {
        self.t.set(i, t.translation);
        self.r.set(i, t.rotation);
        self.s.set(i, t.scale);
    }
}

impl<T: Lane> V3<T> {
    /// From [`V3`] over [`F`] (the same lanes).
    #[inline(always)]
    pub fn of(v: V3) -> V3<T> {
        V3 {
            x: T::of(v.x),
            y: T::of(v.y),
            z: T::of(v.z),
        }
    }

    /// As [`V3`] over [`F`] (the same lanes).
    #[inline(always)]
    pub fn f(self) -> V3 {
        V3 {
            x: self.x.f(),
            y: self.y.f(),
            z: self.z.f(),
        }
    }
}

impl<T: Lane> Q<T> {
    /// From [`Q`] over [`F`] (the same lanes).
    #[inline(always)]
    pub fn of(q: Q) -> Q<T> {
        Q {
            x: T::of(q.x),
            y: T::of(q.y),
            z: T::of(q.z),
            w: T::of(q.w),
        }
    }

    /// As [`Q`] over [`F`] (the same lanes).
    #[inline(always)]
    pub fn f(self) -> Q {
        Q {
            x: self.x.f(),
            y: self.y.f(),
            z: self.z.f(),
            w: self.w.f(),
        }
    }
}

impl<T: Lane> Trs<T> {
    /// From [`Trs`] over [`F`] (the same lanes).
    #[inline(always)]
    pub fn of(t: &Trs) -> Trs<T> {
        Trs {
            t: V3::of(t.t),
            r: Q::of(t.r),
            s: V3::of(t.s),
        }
    }

    /// As [`Trs`] over [`F`] (the same lanes).
    #[inline(always)]
    pub fn f(&self) -> Trs {
        Trs {
            t: self.t.f(),
            r: self.r.f(),
            s: self.s.f(),
        }
    }
}

/// [`crate::math::rotation_arc`] per lane.
#[inline(always)]
pub fn rotation_arc<T: Lane>(from: V3<T>, to: V3<T>) -> Q<T> {
    let a = from.normalize_or(V3::splat(Vec3::Y));
    let b = to.normalize_or(a);
    let w = T::splat(1.0) + a.dot(b);
    let axis = a.any_orthonormal();
    let c = a.cross(b);
    let q = Q {
        x: c.x,
        y: c.y,
        z: c.z,
        w,
    }
    .normalize();
    let half_turn = Q {
        x: axis.x,
        y: axis.y,
        z: axis.z,
        w: T::splat(0.0),
    };
    Q::select(w.lt(T::splat(1e-7)), half_turn, q)
}

/// [`crate::math::rotation_arc`] per lane from a direction shared by all lanes: `a` is
/// `normalize_or(from, Y)` and `half_turn` its 180° quaternion, both precomputed with the
/// scalar code.
#[inline(always)]
pub fn rotation_arc_from<T: Lane>(a: Vec3, half_turn: Quat, to: V3<T>) -> Q<T> {
    rotation_arc_from_lanes(V3::splat(a), Q::splat(half_turn), to)
}

/// [`rotation_arc_from`] with `a` and `half_turn` per lane (each precomputed with the
/// scalar code for its lane).
#[inline(always)]
pub fn rotation_arc_from_lanes<T: Lane>(av: V3<T>, half_turn: Q<T>, to: V3<T>) -> Q<T> {
    let b = to.normalize_or(av);
    let w = T::splat(1.0) + av.dot(b);
    let c = av.cross(b);
    let q = Q {
        x: c.x,
        y: c.y,
        z: c.z,
        w,
    }
    .normalize();
    Q::select(w.lt(T::splat(1e-7)), half_turn, q)
}

impl F {
    /// `|self|` per lane.
    #[inline(always)]
    pub fn abs(self) -> F {
        F(each!(i => self.0[i].abs()))
    }

    /// `f32::clamp(self, 0, 1)` per lane (NaN stays NaN).
    #[inline(always)]
    pub fn clamp01(self) -> F {
        F(each!(i => self.0[i].clamp(0.0, 1.0)))
    }

    /// `f32::max` per lane.
    #[inline(always)]
    pub fn max(self, o: F) -> F {
        F(each!(i => self.0[i].max(o.0[i])))
    }

    /// Lane `i`.
    #[inline(always)]
    pub fn get(self, i: usize) -> f32 {
        self.0[i]
    }
}

/// glam's scalar `acos_approx` (DirectXMath's 7th-degree minimax), per lane, with glam's
/// constants as glam writes them.
#[allow(clippy::approx_constant)]
#[inline(always)]
fn acos_approx<T: Lane>(v: T) -> T {
    let nonnegative = T::splat(0.0).le(v);
    let x = v.abs();
    let omx = T::splat(1.0) - x;
    let omx = T::select(omx.lt(T::splat(0.0)), T::splat(0.0), omx);
    let root = omx.sqrt();
    let c = T::splat;
    let r = c(-0.001_262_491_1) * x + c(0.006_670_09);
    let r = r * x - c(0.017_088_126);
    let r = r * x + c(0.030_891_88);
    let r = r * x - c(0.050_174_303);
    let r = r * x + c(0.088_978_99);
    let r = r * x - c(0.214_598_8);
    let result = r * x + c(1.570_796_3);
    let result = result * root;
    T::select(nonnegative, result, c(std::f32::consts::PI) - result)
}

/// glam's `Vec3::angle_between` per lane (its `acos` approximation included).
#[inline(always)]
pub(crate) fn angle_between<T: Lane>(a: V3<T>, b: V3<T>) -> T {
    acos_approx(a.dot(b) / (a.dot(a) * b.dot(b)).sqrt())
}

/// The direction `limit` radians (the same in every lane) from `from`, turned toward
/// `toward`, as the scalar cone limits compute it: `Quat::from_axis_angle(normalize_or(from
/// × toward, from.any_orthonormal_vector()), limit) * unit_from`, where `unit_from` is
/// `from` normalised with the caller's fallback.
#[inline(always)]
pub(crate) fn turned_toward<T: Lane>(
    from: V3<T>,
    toward: V3<T>,
    unit_from: V3<T>,
    limit: f32,
) -> V3<T> {
    // `Quat::from_axis_angle(axis, limit)` is `axis * sin, cos` of half the limit: the
    // scalar function's own sine and cosine, read from its quaternion about X.
    let half = Quat::from_axis_angle(Vec3::X, limit);
    let (sin, cos) = (T::splat(half.x), T::splat(half.w));
    let axis = from.cross(toward).normalize_or(from.any_orthonormal());
    let turn = Q {
        x: axis.x * sin,
        y: axis.y * sin,
        z: axis.z * sin,
        w: cos,
    };
    turn.mul_vec3(unit_from)
}

/// `x < 0` per lane.
#[inline(always)]
fn is_negative<T: Lane>(x: T) -> T::M {
    x.lt(T::splat(0.0))
}

/// glam's SSE2 `m128_sin` (DirectXMath's 11th-degree minimax after reduction to
/// [-π, π] and reflection into [-π/2, π/2]), per lane.
///
/// glam takes the sign of `x` by its bits where this compares with zero: they differ
/// only for -0 and NaN. Rounding -0 with either sign of 2²³ gives +0; a NaN rounds to
/// itself either way; and the reflection never takes π's sign for -0 (|-0| ≤ π/2) and
/// gives the NaN for a NaN (`π − NaN`).
#[inline(always)]
fn sin_approx<T: Lane>(v: T) -> T {
    let c = T::splat;
    // (A function, not a closure: see `collide::lanes::select_max`.)
    let negative = is_negative::<T>;
    // m128_mod_angles: v − 2π·round(v / 2π), rounding by the 2^23 trick.
    let q = v * c(0.159_154_94);
    let magic = T::select(negative(q), c(-8_388_608.0), c(8_388_608.0));
    let rounded = T::select(q.abs().le(c(8_388_608.0)), (q + magic) - magic, q);
    let x = v - c(std::f32::consts::TAU) * rounded;
    let pi = T::select(
        negative(x),
        c(-std::f32::consts::PI),
        c(std::f32::consts::PI),
    );
    let x = T::select(x.abs().le(c(std::f32::consts::FRAC_PI_2)), x, pi - x);
    let x2 = x * x;
    let r = c(-2.388_985_9e-8) * x2 + c(2.752_556_2e-6);
    let r = r * x2 + c(-0.000_198_408_74);
    let r = r * x2 + c(0.008_333_331);
    let r = r * x2 + c(-0.166_666_67);
    let r = r * x2 + c(1.0);
    r * x
}

impl<T: Lane> Q<T> {
    /// Scaled per lane.
    #[inline(always)]
    fn scale(self, s: T) -> Q<T> {
        Q {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
            w: self.w * s,
        }
    }

    #[inline(always)]
    fn add(self, o: Q<T>) -> Q<T> {
        Q {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
            w: self.w + o.w,
        }
    }

    #[inline(always)]
    fn neg(self) -> Q<T> {
        Q {
            x: -self.x,
            y: -self.y,
            z: -self.z,
            w: -self.w,
        }
    }

    /// glam's SSE2 `Quat::slerp`, per lane.
    #[inline(always)]
    pub fn slerp(self, end: Q<T>, s: T) -> Q<T> {
        let dot = self.dot(end);
        let flip = dot.lt(T::splat(0.0));
        let end = Q::select(flip, end.neg(), end);
        let dot = T::select(flip, -dot, dot);
        let one = T::splat(1.0);
        let near = dot.gt(T::splat(1.0 - f32::EPSILON));
        let lerped = self.scale(one - s).add(end.scale(s)).normalize();
        let theta = acos_approx(dot);
        let scale1 = sin_approx(theta * (one - s));
        let scale2 = sin_approx(theta * s);
        let theta_sin = sin_approx(theta * one);
        let a = self.scale(scale1).add(end.scale(scale2));
        let slerped = Q {
            x: a.x / theta_sin,
            y: a.y / theta_sin,
            z: a.z / theta_sin,
            w: a.w / theta_sin,
        };
        Q::select(near, lerped, slerped)
    }

    /// [`crate::math::slerp_shortest`] per lane.
    #[inline(always)]
    pub fn slerp_shortest(self, b: Q<T>, t: T) -> Q<T> {
        let b = Q::select(self.dot(b).lt(T::splat(0.0)), b.neg(), b);
        self.slerp(b, t).normalize()
    }
}

impl<T: Lane> V3<T> {
    /// glam's `Vec3::lerp`: `self·(1 − s) + rhs·s`.
    #[inline(always)]
    pub fn lerp(self, rhs: V3<T>, s: T) -> V3<T> {
        self * (T::splat(1.0) - s) + rhs * s
    }
}

impl<T: Lane> V3<T> {
    /// glam's `Vec3::any_orthonormal_vector` per lane.
    #[inline(always)]
    pub fn any_orthonormal(self) -> V3<T> {
        let sign = self.z.signum();
        let a = T::splat(-1.0) / (sign + self.z);
        let b = self.x * self.y * a;
        V3 {
            x: b,
            y: sign + self.y * self.y * a,
            z: -self.y,
        }
    }
}

/// glam's `Vec3::min` per lane (`a < b ? a : b`, glam's NaN rule).
#[inline(always)]
pub(crate) fn vmin<T: Lane>(a: V3<T>, b: V3<T>) -> V3<T> {
    V3 {
        x: a.x.min_lt(b.x),
        y: a.y.min_lt(b.y),
        z: a.z.min_lt(b.z),
    }
}

/// glam's `Vec3::max` per lane (`a > b ? a : b`).
#[inline(always)]
pub(crate) fn vmax<T: Lane>(a: V3<T>, b: V3<T>) -> V3<T> {
    V3 {
        x: a.x.max_gt(b.x),
        y: a.y.max_gt(b.y),
        z: a.z.max_gt(b.z),
    }
}

/// `out[k] = a[k].lerp(&b[k], t)` for every `k` in `joints` ([`Transform::lerp`]'s bits),
/// [`LANES`] at a time, in the lane type `isa` chose.
pub(crate) fn lerp_transforms_at(
    a: &[Transform],
    b: &[Transform],
    t: f32,
    joints: &[usize],
    out: &mut [Transform],
    isa: super::Isa,
) {
    #[cfg(target_arch = "x86_64")]
    use super::Isa;
    // SAFETY (both): the function only requires the instructions of its lane type, and
    // `Isa::of` chose that type because the CPU has them.
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    match isa {
        Isa::Avx512 => return unsafe { lerp_transforms_at_avx512(a, b, t, joints, out) },
        Isa::Avx2 => return unsafe { lerp_transforms_at_avx2(a, b, t, joints, out) },
        Isa::Portable => {}
    }
    let _ = isa;
    lerp_transforms_at_lanes::<F>(a, b, t, joints, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn lerp_transforms_at_avx2(
    a: &[Transform],
    b: &[Transform],
    t: f32,
    joints: &[usize],
    out: &mut [Transform],
) {
    // The explicit AVX2 lane type only inside this function, after the CPU was found to
    // have AVX2 (the condition of its soundness, `lanes/avx.rs`).
    lerp_transforms_at_lanes::<super::avx::Fa>(a, b, t, joints, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
fn lerp_transforms_at_avx512(
    a: &[Transform],
    b: &[Transform],
    t: f32,
    joints: &[usize],
    out: &mut [Transform],
) {
    // The explicit AVX-512 lane type only inside this function, after the CPU was found
    // to have it (the condition of its soundness, `lanes/avx512.rs`).
    lerp_transforms_at_lanes::<super::avx512::Fz>(a, b, t, joints, out)
}

#[inline(always)]
fn lerp_transforms_at_lanes<T: Lane>(
    a: &[Transform],
    b: &[Transform],
    t: f32,
    joints: &[usize],
    out: &mut [Transform],
) {
    let t = T::splat(t);
    for chunk in joints.chunks(LANES) {
        let (mut la, mut lb) = (
            Trs::splat(&Transform::IDENTITY),
            Trs::splat(&Transform::IDENTITY),
        );
        for (l, &j) in chunk.iter().enumerate() {
            la.set(l, &a[j]);
            lb.set(l, &b[j]);
        }
        let r = Trs::<T>::of(&la).lerp(&Trs::of(&lb), t).f();
        for (l, &j) in chunk.iter().enumerate() {
            out[j] = r.get(l);
        }
    }
}

impl<T: Lane> Trs<T> {
    /// [`Transform::lerp`] per lane.
    #[inline(always)]
    pub fn lerp(&self, other: &Trs<T>, t: T) -> Trs<T> {
        Trs {
            t: self.t.lerp(other.t, t),
            r: self.r.slerp_shortest(other.r, t),
            s: self.s.lerp(other.s, t),
        }
    }
}

/// Whether two per-lane vectors differ (as `Vec3 != Vec3`: by value, `-0 == 0`).
#[inline(always)]
pub fn differs<T: Lane>(a: V3<T>, b: V3<T>) -> T::M {
    // Per component and then OR-ed, not `||` per lane: the short circuit made a branch per
    // lane and component out of what is three vector compares.
    a.x.ne(b.x).or(a.y.ne(b.y)).or(a.z.ne(b.z))
}

/// [`crate::math::closest_point_on_segment`] per lane.
#[inline(always)]
pub fn closest_point_on_segment<T: Lane>(p: V3<T>, a: V3<T>, b: V3<T>) -> V3<T> {
    let ab = b - a;
    let len2 = ab.dot(ab);
    let t = ((p - a).dot(ab) / len2).clamp01();
    V3::select(len2.le(T::splat(1e-20)), a, a + ab * t)
}

/// [`crate::math::closest_params_segment_segment`] per lane: every branch computed, the
/// scalar function's choice made per lane in the same order (both segments degenerate,
/// the first, the second, then the general case with its two clamps).
#[inline(always)]
pub fn closest_params_segment_segment<T: Lane>(
    p1: V3<T>,
    q1: V3<T>,
    p2: V3<T>,
    q2: V3<T>,
) -> (T, T) {
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let a = d1.dot(d1);
    let e = d2.dot(d2);
    let f = d2.dot(r);
    let eps = T::splat(1e-12);
    let (zero, one) = (T::splat(0.0), T::splat(1.0));
    let c = d1.dot(r);
    let b = d1.dot(d2);
    let denom = a * e - b * b;
    let s0 = T::select(denom.gt(eps), ((b * f - c * e) / denom).clamp01(), zero);
    let t0 = (b * s0 + f) / e;
    let below = t0.lt(zero);
    let above = t0.gt(one);
    let s = T::select(
        below,
        (-c / a).clamp01(),
        T::select(above, ((b - c) / a).clamp01(), s0),
    );
    let t = T::select(below, zero, T::select(above, one, t0));
    let a_small = a.le(eps);
    let e_small = e.le(eps);
    let s = T::select(e_small, (-c / a).clamp01(), s);
    let t = T::select(e_small, zero, t);
    let s = T::select(a_small, zero, s);
    let t = T::select(a_small, T::select(e_small, zero, (f / e).clamp01()), t);
    (s, t)
}

/// Asks the processor to bring every 64-byte line of `data` into its second-level cache
/// (the T1 hint; a hint only: it changes no value, and does nothing on targets without
/// the instruction).
#[inline]
pub(crate) fn prefetch<D>(data: &[D]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T1};
        let bytes = std::mem::size_of_val(data);
        let start = data.as_ptr() as *const i8;
        for at in (0..bytes).step_by(64) {
            // SAFETY: a prefetch is only a hint: it never faults and reads nothing into
            // the program (SSE, which every x86_64 has); `at` is inside `data` anyway.
            #[allow(unsafe_code)]
            unsafe {
                _mm_prefetch::<_MM_HINT_T1>(start.add(at))
            };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = data;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{normalize_or, rotation_arc};
    use crate::rng::SplitMix64 as Rng;

    fn rand_vec(r: &mut Rng, s: f32) -> Vec3 {
        Vec3::new(r.range_f32(-s, s), r.range_f32(-s, s), r.range_f32(-s, s))
    }
    fn rand_quat(r: &mut Rng) -> Quat {
        Quat::from_xyzw(
            r.range_f32(-1.0, 1.0),
            r.range_f32(-1.0, 1.0),
            r.range_f32(-1.0, 1.0),
            r.range_f32(-1.0, 1.0),
        )
        .normalize()
    }
    fn rand_transform(r: &mut Rng) -> Transform {
        Transform::new(
            rand_vec(r, 3.0),
            rand_quat(r),
            Vec3::new(
                r.range_f32(0.5, 2.0),
                r.range_f32(0.5, 2.0),
                r.range_f32(0.5, 2.0),
            ),
        )
    }
    fn bits3(v: Vec3) -> [u32; 3] {
        v.to_array().map(f32::to_bits)
    }
    fn bits4(q: Quat) -> [u32; 4] {
        q.to_array().map(f32::to_bits)
    }

    /// Each lane operation against glam and `crate::math` on random inputs: the same
    /// bits (what the crowd path's equality with the single-character path rests on).
    #[test]
    fn lane_operations_give_the_scalar_bits() {
        let mut r = Rng::new(7);
        for _ in 0..2000 {
            let ta: [Transform; LANES] = std::array::from_fn(|_| rand_transform(&mut r));
            let tb: [Transform; LANES] = std::array::from_fn(|_| rand_transform(&mut r));
            let p: [Vec3; LANES] = std::array::from_fn(|_| rand_vec(&mut r, 2.0));
            let mut la = Trs::<F>::splat(&Transform::IDENTITY);
            let mut lb = la;
            let mut lp = V3::splat(Vec3::ZERO);
            for i in 0..LANES {
                la.set(i, &ta[i]);
                lb.set(i, &tb[i]);
                lp.set(i, p[i]);
            }
            let m = la.mul(&lb);
            let tp = la.transform_point(lp);
            let itp = la.inverse_transform_point(lp);
            let qv = la.r.mul_vec3(lp);
            let qq = la.r.mul_quat(lb.r);
            let n = lp.normalize_or(V3::splat(Vec3::Y));
            let from = rand_vec(&mut r, 1.0);
            let a = normalize_or(from, Vec3::Y);
            let half = {
                let o = a.any_orthonormal_vector();
                Quat::from_xyzw(o.x, o.y, o.z, 0.0)
            };
            let arc = rotation_arc_from(a, half, lp);
            for i in 0..LANES {
                let want = ta[i] * tb[i];
                assert_eq!(bits3(m.t.get(i)), bits3(want.translation));
                assert_eq!(bits4(m.r.get(i)), bits4(want.rotation));
                assert_eq!(bits3(m.s.get(i)), bits3(want.scale));
                assert_eq!(bits3(tp.get(i)), bits3(ta[i].transform_point(p[i])));
                assert_eq!(
                    bits3(itp.get(i)),
                    bits3(ta[i].inverse_transform_point(p[i]))
                );
                assert_eq!(bits3(qv.get(i)), bits3(ta[i].rotation * p[i]));
                assert_eq!(bits4(qq.get(i)), bits4(ta[i].rotation * tb[i].rotation));
                assert_eq!(bits3(n.get(i)), bits3(normalize_or(p[i], Vec3::Y)));
                assert_eq!(bits4(arc.get(i)), bits4(rotation_arc(from, p[i])));
            }
        }
    }

    /// The portable type's [`Lane::transforms`] (the trait's own) puts each transform in
    /// its lane.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn portable_transforms_are_the_lanes_of_each() {
        crate::lanes::check::transforms_are_the_lanes_of_each::<F>();
    }

    /// The segment–segment closest parameters per lane against the scalar function, with
    /// every branch taken: general segments, parallel ones (denominator 0), each segment
    /// a point, both points, both clamps, NaN input.
    #[test]
    fn lane_segment_segment_gives_the_scalar_bits() {
        use crate::math::closest_params_segment_segment as scalar;
        let mut r = Rng::new(23);
        let mut kinds = [0usize; 6];
        for round in 0..4000 {
            let mut ends: [[Vec3; 4]; LANES] =
                std::array::from_fn(|_| std::array::from_fn(|_| rand_vec(&mut r, 1.0)));
            for (l, e) in ends.iter_mut().enumerate() {
                match (round + l) % 6 {
                    0 => e[1] = e[0],
                    1 => e[3] = e[2],
                    2 => (e[1], e[3]) = (e[0], e[2]),
                    3 => e[3] = e[2] + (e[1] - e[0]) * 0.5,
                    4 if round % 97 == 0 => e[0].x = f32::NAN,
                    _ => {}
                }
                kinds[(round + l) % 6] += 1;
            }
            let lane = |k: usize| {
                let mut v = V3::<F>::splat(Vec3::ZERO);
                for (l, e) in ends.iter().enumerate() {
                    v.set(l, e[k]);
                }
                v
            };
            let (s, t) = closest_params_segment_segment(lane(0), lane(1), lane(2), lane(3));
            for (l, e) in ends.iter().enumerate() {
                let (ws, wt) = scalar(e[0], e[1], e[2], e[3]);
                // NaN as NaN (its payload is not part of the promise: the crowd turns
                // non-finite input away before it reaches a step).
                let same = |a: f32, b: f32| a.to_bits() == b.to_bits() || a.is_nan() && b.is_nan();
                assert!(same(s.0[l], ws), "round {round} lane {l} s");
                assert!(same(t.0[l], wt), "round {round} lane {l} t");
            }
        }
        assert!(kinds.iter().all(|&k| k > 1000));
    }

    /// Interpolation as the fixed-step path uses it: glam's slerp (its own acos and sine
    /// approximations), the shortest-way slerp, transform lerp, and the other helpers.
    #[test]
    fn lane_interpolation_gives_the_scalar_bits() {
        use crate::math::{closest_point_on_segment as cps, slerp_shortest};
        let mut r = Rng::new(11);
        for round in 0..3000 {
            let ta: [Transform; LANES] = std::array::from_fn(|_| rand_transform(&mut r));
            let mut tb: [Transform; LANES] = std::array::from_fn(|_| rand_transform(&mut r));
            // Nearly equal and opposite rotations too: the lerp branch and the flip.
            if round % 3 == 0 {
                for (b, a) in tb.iter_mut().zip(&ta) {
                    b.rotation = (a.rotation
                        * Quat::from_rotation_x(1e-4 * r.range_f32(-1.0, 1.0)))
                    .normalize();
                }
            }
            if round % 3 == 1 {
                tb[0].rotation = -ta[0].rotation;
            }
            let w: [f32; LANES] = std::array::from_fn(|i| match i {
                0 => 0.0,
                1 => 1.0,
                _ => r.range_f32(0.0, 1.0),
            });
            let (mut la, mut lb) = (
                Trs::splat(&Transform::IDENTITY),
                Trs::splat(&Transform::IDENTITY),
            );
            for i in 0..LANES {
                la.set(i, &ta[i]);
                lb.set(i, &tb[i]);
            }
            let lw = F(w);
            let l = la.lerp(&lb, lw);
            let sl = la.r.slerp(lb.r, lw);
            let ortho = la.t.normalize_or(V3::splat(Vec3::Y)).any_orthonormal();
            let seg = closest_point_on_segment(lb.t, la.t, la.t + lb.s);
            for i in 0..LANES {
                let want = ta[i].lerp(&tb[i], w[i]);
                assert_eq!(bits3(l.t.get(i)), bits3(want.translation));
                assert_eq!(
                    bits4(l.r.get(i)),
                    bits4(want.rotation),
                    "round {round} lane {i}"
                );
                assert_eq!(bits3(l.s.get(i)), bits3(want.scale));
                assert_eq!(
                    bits4(sl.get(i)),
                    bits4(ta[i].rotation.slerp(tb[i].rotation, w[i]))
                );
                assert_eq!(
                    bits4(la.r.slerp_shortest(lb.r, lw).get(i)),
                    bits4(slerp_shortest(ta[i].rotation, tb[i].rotation, w[i]))
                );
                let n = normalize_or(ta[i].translation, Vec3::Y);
                assert_eq!(bits3(ortho.get(i)), bits3(n.any_orthonormal_vector()));
                assert_eq!(
                    bits3(seg.get(i)),
                    bits3(cps(
                        tb[i].translation,
                        ta[i].translation,
                        ta[i].translation + tb[i].scale
                    ))
                );
            }
        }
    }

    /// The special cases: a zero vector falls back, and antiparallel directions turn half
    /// way round, as the scalar code does.
    #[test]
    fn lane_fallbacks_match_the_scalar_code() {
        let a = Vec3::Y;
        let o = a.any_orthonormal_vector();
        let half = Quat::from_xyzw(o.x, o.y, o.z, 0.0);
        let mut to = V3::<F>::splat(Vec3::new(0.3, 0.2, 0.1));
        to.set(1, -Vec3::Y);
        to.set(2, Vec3::ZERO);
        to.set(3, Vec3::new(f32::NAN, 0.0, 0.0));
        let q = rotation_arc_from(a, half, to);
        for (i, v) in [
            Vec3::new(0.3, 0.2, 0.1),
            -Vec3::Y,
            Vec3::ZERO,
            Vec3::new(f32::NAN, 0.0, 0.0),
        ]
        .into_iter()
        .enumerate()
        {
            assert_eq!(bits4(q.get(i)), bits4(rotation_arc(a, v)), "lane {i}");
        }
        assert_eq!(q.get(1).w, 0.0);
    }

    /// `differs` and `any` answer as `Vec3 != Vec3` and "some lane": by value (`-0 == 0`),
    /// NaN differing from itself, a difference in any one component.
    #[test]
    fn lane_differs_and_any_answer_as_the_scalar_tests() {
        let values = [0.0, -0.0, 1.0, f32::NAN, f32::INFINITY, -1e-30];
        let mut rng = crate::rng::SplitMix64::new(3);
        let mut pick = || values[(rng.next_u64() % values.len() as u64) as usize];
        let (mut same, mut differ) = (0, 0);
        for _ in 0..2000 {
            let (mut a, mut b) = (V3::ZERO, V3::ZERO);
            for l in 0..LANES {
                a.set(l, Vec3::new(pick(), pick(), pick()));
                let mut v = a.get(l);
                // Mostly equal vectors, with one component changed now and then.
                if l % 3 == 0 {
                    v[(l / 3) % 3] = pick();
                }
                b.set(l, v);
            }
            let m = differs(a, b);
            for l in 0..LANES {
                let want = a.get(l) != b.get(l);
                assert_eq!(m.get(l), want, "{:?} {:?}", a.get(l), b.get(l));
                same += usize::from(!want);
                differ += usize::from(want);
            }
            assert_eq!(m.any(), (0..LANES).any(|l| m.get(l)));
        }
        assert!(same > 1000 && differ > 1000, "{same} {differ}");
        let mut one = M::NONE;
        one.0[7] = !0;
        assert!(one.any() && !M::NONE.any() && M::ALL.any());
    }
}
