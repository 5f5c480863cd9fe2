//! The swept entry of keep-out spheres and capsules per lane: where a step that entered
//! the shape (from outside its entry surface) is stopped and slid on, as
//! [`crate::collide::push_out_of_sphere`] and [`crate::collide::push_out_of_capsule`] do
//! it, operation for operation. A point resting on a shape enters it again at every step
//! that pulls it inward, so this is common, not an edge case.
//!
//! The capsule's closed-form entry is computed in `f64` as the scalar function does ([`D`],
//! per-lane loops the compiler vectorises). A lane whose closed form finds no root (a
//! graze lost to rounding, where the scalar function bisects) is reported `hard` and left
//! to the scalar narrow phase.
//!
//! [`capsule_entry_out_of_line`] runs the capsule's out of line (in AVX2 where the
//! caller's lane type is the AVX one): inlined into every copy of the solver step, its
//! `f64` code tripled the crate's release build time. The sphere's ([`sphere_entry`], a
//! few `f32` operations) is inlined where it is asked: out of line, the call and its
//! arguments' trip through memory cost one character about 2 %.

use super::lanes::{entry_radius_lanes, LaneContact};
#[cfg(target_arch = "x86_64")]
use crate::lanes::Isa;
use crate::lanes::{closest_point_on_segment, Lane, Mask, F, LANES, M, V3};

/// One `f64` per lane.
#[derive(Clone, Copy)]
struct D([f64; LANES]);

macro_rules! d_lanewise {
    ($a:expr, $b:expr, $op:tt) => {{
        let mut r = [0.0f64; LANES];
        for i in 0..LANES {
            r[i] = $a.0[i] $op $b.0[i];
        }
        D(r)
    }};
}

impl std::ops::Add for D {
    type Output = D;
    #[inline(always)]
    fn add(self, o: D) -> D {
        d_lanewise!(self, o, +)
    }
}
impl std::ops::Sub for D {
    type Output = D;
    #[inline(always)]
    fn sub(self, o: D) -> D {
        d_lanewise!(self, o, -)
    }
}
impl std::ops::Mul for D {
    type Output = D;
    #[inline(always)]
    fn mul(self, o: D) -> D {
        d_lanewise!(self, o, *)
    }
}
impl std::ops::Div for D {
    type Output = D;
    #[inline(always)]
    fn div(self, o: D) -> D {
        d_lanewise!(self, o, /)
    }
}

impl D {
    #[inline(always)]
    fn splat(v: f64) -> D {
        D([v; LANES])
    }
    /// The `f32` lanes widened (exact).
    #[inline(always)]
    fn of(f: F) -> D {
        D(f.0.map(f64::from))
    }
    #[inline(always)]
    fn map(self, f: impl Fn(f64) -> f64) -> D {
        D(self.0.map(f))
    }
    #[inline(always)]
    fn test(self, o: D, f: impl Fn(f64, f64) -> bool) -> M {
        M(std::array::from_fn(|i| {
            if f(self.0[i], o.0[i]) {
                !0
            } else {
                0
            }
        }))
    }
    /// `f64::min` per lane.
    #[inline(always)]
    fn min(self, o: D) -> D {
        let mut r = [0.0f64; LANES];
        for i in 0..LANES {
            r[i] = self.0[i].min(o.0[i]);
        }
        D(r)
    }
    #[inline(always)]
    fn select(m: M, a: D, b: D) -> D {
        D(std::array::from_fn(|i| {
            if m.0[i] != 0 {
                a.0[i]
            } else {
                b.0[i]
            }
        }))
    }
}

/// glam's `DVec3` per lane (only what the entry needs).
#[derive(Clone, Copy)]
struct D3 {
    x: D,
    y: D,
    z: D,
}

impl D3 {
    #[inline(always)]
    fn of(v: V3) -> D3 {
        D3 {
            x: D::of(v.x),
            y: D::of(v.y),
            z: D::of(v.z),
        }
    }
    #[inline(always)]
    fn sub(self, o: D3) -> D3 {
        D3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
    #[inline(always)]
    fn add(self, o: D3) -> D3 {
        D3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
    #[inline(always)]
    fn scale(self, s: D) -> D3 {
        D3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    #[inline(always)]
    fn div(self, s: D) -> D3 {
        D3 {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
    /// glam's `DVec3::dot`: `(x·x' + y·y') + z·z'`.
    #[inline(always)]
    fn dot(self, o: D3) -> D {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
}

/// The entry root of `t²·qa + 2t·half_b + qc = 0` per lane, as `capsule_entry`'s
/// `entry`, and the lanes that have one.
#[inline(always)]
fn entry_root(qa: D, half_b: D, qc: D) -> (D, M) {
    let h = half_b * half_b - qa * qc;
    // `h.is_nan() || h < 0.0` is no root: `h >= 0` is the rest.
    let far = half_b.map(|x| -x) + h.map(f64::sqrt);
    let found = h
        .test(D::splat(0.0), |a, b| a >= b)
        .and(far.test(D::splat(0.0), |a, b| a > b));
    ((qc / far).map(|t| t.max(0.0)), found)
}

/// `capsule_entry` of `crate::collide::capsule` per lane: the first share of the step
/// `o` → `o + v` at which the path is `rho` from the segment `a`–`b`, and the lanes where
/// the closed form found one.
#[inline(always)]
fn capsule_entry(o: V3, v: V3, a: V3, b: V3, rho: F) -> (F, M) {
    let (o, v, a, b) = (D3::of(o), D3::of(v), D3::of(a), D3::of(b));
    let rho2 = D::of(rho) * D::of(rho);
    let vv = v.dot(v);
    // An end ball at `c`: |o − c + v·t|² = ρ².
    #[inline(always)]
    fn ball(o: D3, v: D3, vv: D, c: D3, rho2: D) -> (D, M) {
        let oc = o.sub(c);
        entry_root(vv, v.dot(oc), oc.dot(oc) - rho2)
    }
    let min = D::min;
    let mut first = D::splat(f64::INFINITY);
    let (t, found) = ball(o, v, vv, a, rho2);
    first = D::select(found, min(first, t), first);
    let ba = b.sub(a);
    let baba = ba.dot(ba);
    let long = baba.test(D::splat(1e-20), |a, b| a > b);
    let (t, found) = ball(o, v, vv, b, rho2);
    first = D::select(long.and(found), min(first, t), first);
    // The infinite cylinder, from the parts of the start and the step across the axis.
    let n = ba.div(baba.map(f64::sqrt));
    let oa = o.sub(a);
    let v_across = v.sub(n.scale(n.dot(v)));
    let oa_across = oa.sub(n.scale(n.dot(oa)));
    let (t, found) = entry_root(
        v_across.dot(v_across),
        v_across.dot(oa_across),
        oa_across.dot(oa_across) - rho2,
    );
    // Only where the side is: between the ends.
    let y = ba.dot(oa.add(v.scale(t)));
    let side = long
        .and(found)
        .and(y.test(D::splat(0.0), |a, b| a > b))
        .and(y.test(baba, |a, b| a < b));
    first = D::select(side, min(first, t), first);
    let found = M(std::array::from_fn(|i| {
        if first.0[i].is_finite() {
            !0
        } else {
            0
        }
    }));
    (F(first.0.map(|t| t as f32)), found)
}

/// `f32::min` per lane.
#[inline(always)]
fn min_f<T: Lane>(a: T, b: T) -> T {
    let (a, b) = (a.f(), b.f());
    T::of(F(std::array::from_fn(|i| a.0[i].min(b.0[i]))))
}

/// The rest of a step from `contact` to `p`, slid along a surface of normal `n`: its part
/// into the surface removed (`contact + rest - n * min(rest·n, 0)`).
#[inline(always)]
fn slide<T: Lane>(contact: V3<T>, p: V3<T>, n: V3<T>) -> V3<T> {
    let rest = p - contact;
    contact + rest - n * min_f(rest.dot(n), T::splat(0.0))
}

/// [`crate::collide::push_out_of_sphere`] per lane for a step that entered the sphere
/// (`center`, `limit`): stopped where it met the entry surface, slid on, then kept
/// outside. For the lanes [`super::lanes::sphere_contact`] found `entered`.
#[inline(always)]
pub(crate) fn sphere_entry<T: Lane>(
    p: V3<T>,
    prev: V3<T>,
    center: V3<T>,
    limit: T,
    contact: &LaneContact<T>,
) -> V3<T> {
    let inner = entry_radius_lanes(limit);
    let inner2 = inner * inner;
    let (o, v) = (prev - center, p - prev);
    let (vv, ov) = (v.dot(v), o.dot(v));
    let zero = T::splat(0.0);
    let disc = (ov * ov - vv * (o.dot(o) - inner2)).max(zero);
    let t = T::select(vv.gt(zero), ((-ov - disc.sqrt()) / vv).clamp01(), zero);
    let at = prev + v * t;
    // The fallback `(prev - center).normalize_or(Y)`, as the contact computed it.
    let n = (at - center).normalize_or(contact.fallback());
    let slid = slide(at, p, n);
    outside_sphere(slid, center, limit, n)
}

/// `outside_sphere` of `crate::collide::sphere` per lane.
#[inline(always)]
fn outside_sphere<T: Lane>(p: V3<T>, center: V3<T>, limit: T, fallback: V3<T>) -> V3<T> {
    let d = p - center;
    let inside = d.dot(d).lt(limit * limit);
    V3::select(inside, center + d.normalize_or(fallback) * limit, p)
}

/// `outside_capsule` of `crate::collide::capsule` per lane.
#[inline(always)]
fn outside_capsule<T: Lane>(p: V3<T>, a: V3<T>, b: V3<T>, limit: T, fallback: V3<T>) -> V3<T> {
    let c = closest_point_on_segment(p, a, b);
    let d = p - c;
    let inside = d.dot(d).lt(limit * limit);
    V3::select(inside, c + d.normalize_or(fallback) * limit, p)
}

/// [`crate::collide::push_out_of_capsule`] per lane for a step that entered the capsule
/// `a`–`b` (`limit`): stopped where it met the entry surface (found in closed form, in
/// `f64`), slid on, then kept outside. For the lanes
/// [`super::lanes::capsule_contact`] found `entered`; also returns the lanes whose
/// closed form found no root (`hard`: the scalar function bisects there), whose point is
/// not answered. The step's start's distance from the axis, the share of the step at
/// its closest approach and the fallback direction are `contact`'s (the same operations).
#[inline(always)]
pub(crate) fn capsule_entry_push<T: Lane>(
    p: V3<T>,
    prev: V3<T>,
    a: V3<T>,
    b: V3<T>,
    limit: T,
    contact: &LaneContact<T>,
) -> (V3<T>, T::M) {
    let inner = entry_radius_lanes(limit);
    let (prev_dist, prev_fallback, s) = (contact.prev_dist, contact.fallback(), contact.along);
    let (t, found) = capsule_entry(prev.f(), (p - prev).f(), a.f(), b.f(), inner.f());
    let beyond = inner.lt(prev_dist);
    let lo = T::select(beyond, min_f(T::of(t), s), T::splat(0.0));
    let hard = beyond.and(<T::M as Mask>::of(found).not());
    let at = prev + (p - prev) * lo;
    let n = (at - closest_point_on_segment(at, a, b)).normalize_or(prev_fallback);
    let slid = slide(at, p, n);
    (outside_capsule(slid, a, b, limit, n), hard)
}

/// [`capsule_entry_push`] for the lanes of `need`: the point each gives, and the lanes
/// left to the scalar narrow phase. Out of line: in AVX2 for the AVX lane type, else in
/// the portable one (the same bits).
#[inline(always)]
pub(crate) fn capsule_entry_out_of_line<T: Lane>(
    p: V3<T>,
    prev: V3<T>,
    a: V3<T>,
    b: V3<T>,
    limit: T,
    contact: &LaneContact<T>,
    need: T::M,
) -> (V3<T>, T::M) {
    let args = (
        p.f(),
        prev.f(),
        a.f(),
        b.f(),
        limit.f(),
        contact.f(),
        need.m(),
    );
    // SAFETY (both): a value of an explicit lane type exists only inside functions
    // compiled with its instructions after the CPU was found to have them
    // (`lanes/avx.rs`, `lanes/avx512.rs`), so the CPU has them.
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    match T::ISA {
        Isa::Avx512 => {
            let (e, h) = unsafe { entry_avx512(args) };
            return (V3::of(e), <T::M as Mask>::of(h));
        }
        Isa::Avx2 => {
            let (e, h) = unsafe { entry_avx2(args) };
            return (V3::of(e), <T::M as Mask>::of(h));
        }
        Isa::Portable => {}
    }
    let (e, h) = entry_portable(args);
    (V3::of(e), <T::M as Mask>::of(h))
}

/// [`capsule_entry_out_of_line`]'s arguments in the portable lane type.
type EntryArgs = (V3, V3, V3, V3, F, LaneContact<F>, M);

#[inline(never)]
fn entry_portable(args: EntryArgs) -> (V3, M) {
    entry_in::<F>(args)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline(never)]
fn entry_avx2(args: EntryArgs) -> (V3, M) {
    entry_in::<crate::lanes::avx::Fa>(args)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
#[inline(never)]
fn entry_avx512(args: EntryArgs) -> (V3, M) {
    entry_in::<crate::lanes::avx512::Fz>(args)
}

#[inline(always)]
fn entry_in<T: Lane>((p, prev, a, b, limit, contact, need): EntryArgs) -> (V3, M) {
    let (p, prev, limit) = (V3::<T>::of(p), V3::<T>::of(prev), T::of(limit));
    let contact = LaneContact::<T>::of(&contact);
    let (a, b) = (V3::<T>::of(a), V3::<T>::of(b));
    let (e, h) = capsule_entry_push(p, prev, a, b, limit, &contact);
    (e.f(), h.and(<T::M as Mask>::of(need)).m())
}
