//! The checks each explicit lane type (`lanes/avx.rs`, `lanes/avx512.rs`) runs: every
//! operation against [`F`]'s, the reference, bit for bit.

use super::{Lane, Mask, F, LANES, M};
use crate::rng::SplitMix64 as Rng;

fn same(a: F, b: F) -> bool {
    a.0.iter()
        .zip(b.0.iter())
        .all(|(x, y)| x.to_bits() == y.to_bits())
}

/// Values with every special case: ±0, ±∞, NaN, subnormals, huge, tiny, ordinary.
fn values(rng: &mut Rng) -> F {
    let special = [
        0.0,
        -0.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        1e-40,
        -1e-40,
        3.4e38,
        -3.4e38,
        1e-30,
        1.0,
        -1.0,
    ];
    F(std::array::from_fn(|_| {
        let r = rng.next_u64();
        if r.is_multiple_of(4) {
            special[(r >> 8) as usize % special.len()]
        } else {
            let x = (rng.next_u64() % 2_000_000) as f32 / 1000.0 - 1000.0;
            if r % 4 == 1 {
                x * 1e-3
            } else {
                x
            }
        }
    }))
}

/// Every operation of the lane type `T` gives [`F`]'s bits, on values with every special
/// case. Run only where the CPU has `T`'s instructions.
pub(super) fn operations_give_the_bits_of_f<T: Lane>() {
    let mut rng = Rng::new(0xA5A5);
    for _ in 0..20_000 {
        let (a, b) = (values(&mut rng), values(&mut rng));
        let (x, y) = (T::of(a), T::of(b));
        assert!(same((x + y).f(), a + b), "{a:?} + {b:?}");
        assert!(same((x - y).f(), a - b), "{a:?} - {b:?}");
        assert!(same((x * y).f(), a * b), "{a:?} * {b:?}");
        assert!(same((x / y).f(), a / b), "{a:?} / {b:?}");
        assert!(same((-x).f(), -a), "-{a:?}");
        assert!(same(x.sqrt().f(), a.sqrt()), "sqrt {a:?}");
        assert!(same(x.abs().f(), a.abs()), "abs {a:?}");
        assert!(same(x.clamp01().f(), a.clamp01()), "clamp01 {a:?}");
        assert!(same(x.max(y).f(), a.max(b)), "max {a:?} {b:?}");
        let (gt, lt) = (a.gt(b), a.lt(b));
        assert!(
            same(x.max_gt(y).f(), F::select(gt, a, b)),
            "max_gt {a:?} {b:?}"
        );
        assert!(
            same(x.min_lt(y).f(), F::select(lt, a, b)),
            "min_lt {a:?} {b:?}"
        );
        assert!(
            same(y.max_gt(x).f(), F::select(b.gt(a), b, a)),
            "max_gt {b:?} {a:?}"
        );
        assert!(same(x.signum().f(), F(a.0.map(f32::signum))));
        assert_eq!(x.lt(y).m(), a.lt(b), "{a:?} < {b:?}");
        assert_eq!(x.le(y).m(), a.le(b), "{a:?} <= {b:?}");
        assert_eq!(x.gt(y).m(), a.gt(b), "{a:?} > {b:?}");
        assert_eq!(x.ne(y).m(), a.ne(b), "{a:?} != {b:?}");
        assert_eq!(x.finite().m(), a.finite(), "finite {a:?}");
        assert_eq!(x.bits_eq(y).m(), Lane::bits_eq(a, b), "{a:?} bits {b:?}");
        assert_eq!(x.bits_eq(x).m(), M::ALL, "{a:?} bits itself");
        let m = a.lt(b);
        let (mx, ma) = (<T::M as Mask>::of(m), m);
        assert!(same(T::select(mx, x, y).f(), F::select(ma, a, b)));
        let n = b.finite();
        let nx = <T::M as Mask>::of(n);
        assert_eq!(mx.and(nx).m(), ma.and(n));
        assert_eq!(mx.or(nx).m(), ma.or(n));
        assert_eq!(mx.not().m(), ma.not());
        assert_eq!(mx.any(), ma.any());
        assert_eq!(mx.several(), Mask::several(ma));
        assert_eq!(mx == <T::M as Mask>::ALL, ma == M::ALL);
        assert_eq!(mx == <T::M as Mask>::NONE, ma == M::NONE);
        for l in [0, 3, LANES / 2 + 1, LANES - 1] {
            assert_eq!(x.get(l).to_bits(), a.0[l].to_bits());
        }
    }
}

/// `several` is "more than one lane set", for no lane, every single lane and every pair.
pub(super) fn several_means_more_than_one_lane<T: Lane>() {
    assert!(!<T::M as Mask>::NONE.several());
    for i in 0..LANES {
        let mut one = M::NONE;
        one.0[i] = !0;
        assert!(!<T::M as Mask>::of(one).several(), "lane {i} alone");
        assert!(!Mask::several(one), "lane {i} alone");
        for j in (0..LANES).filter(|&j| j != i) {
            let mut two = one;
            two.0[j] = !0;
            assert!(<T::M as Mask>::of(two).several(), "lanes {i} and {j}");
            assert!(Mask::several(two), "lanes {i} and {j}");
        }
    }
}

/// [`Lane::transforms`] puts each transform's ten values in its own lane, each field in
/// its place, with their bits (special values too), for several sets of transforms.
pub(super) fn transforms_are_the_lanes_of_each<T: Lane>() {
    use crate::math::Transform;
    use glam::{Quat, Vec3};
    let mut rng = Rng::new(0x7E57);
    for _ in 0..200 {
        let v: [F; 10] = std::array::from_fn(|_| values(&mut rng));
        let ts: [Transform; LANES] = std::array::from_fn(|l| Transform {
            translation: Vec3::new(v[0].0[l], v[1].0[l], v[2].0[l]),
            rotation: Quat::from_xyzw(v[3].0[l], v[4].0[l], v[5].0[l], v[6].0[l]),
            scale: Vec3::new(v[7].0[l], v[8].0[l], v[9].0[l]),
        });
        let refs: [&Transform; LANES] = std::array::from_fn(|l| &ts[l]);
        let t = T::transforms(&refs);
        let got = [
            t.t.x, t.t.y, t.t.z, t.r.x, t.r.y, t.r.z, t.r.w, t.s.x, t.s.y, t.s.z,
        ];
        for (i, (g, want)) in got.iter().zip(v).enumerate() {
            assert!(same(g.f(), want), "field {i}: {:?} for {want:?}", g.f());
        }
    }
}
