//! Point-vs-shape contacts: sliding never sticks, tunnelling is still caught (issue 20).

use glam::Vec3;
use tassel::collide::{push_out_of_capsule, push_out_of_sphere};
use tassel::rng::SplitMix64;

fn unit(rng: &mut SplitMix64) -> Vec3 {
    loop {
        let v = Vec3::new(
            rng.range_f32(-1.0, 1.0),
            rng.range_f32(-1.0, 1.0),
            rng.range_f32(-1.0, 1.0),
        );
        if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    }
}

/// A point on the surface (as the previous push left it) moves 2 mm tangentially: half of
/// the time only that, else also up to 0.5 mm into the shape (as gravity or stiffness
/// would push it) or 0.2 mm away. The result must be outside (to
/// f32 rounding), and must keep most of the tangential motion: counted as "put back" when
/// it keeps less than half of it. Before, the swept test fired on rounding and put back
/// 3.7 % of these slides on the sphere and 4.2 % on the capsule (measured by this test;
/// the issue measured 56 % for slides in world coordinates).
fn slides(
    name: &str,
    resolve: impl Fn(Vec3, Vec3) -> Vec3,
    surface: impl Fn(&mut SplitMix64) -> (Vec3, Vec3),
    dist: impl Fn(Vec3) -> f32,
    limit: f32,
) {
    let mut rng = SplitMix64::new(20);
    let mut put_back = 0;
    let mut deepest = 0.0f32;
    for _ in 0..100_000 {
        let (prev, n) = surface(&mut rng);
        let tangent = (unit(&mut rng) - n * unit(&mut rng).dot(n)).normalize_or_zero();
        let tangent = (tangent - n * tangent.dot(n)).normalize_or_zero();
        if tangent == Vec3::ZERO {
            continue;
        }
        // Half of them purely tangential: the case that stuck most.
        let inward = if rng.next_u64().is_multiple_of(2) {
            0.0
        } else {
            rng.range_f32(-0.2e-3, 0.5e-3)
        };
        let p = prev + tangent * 2e-3 - n * inward;
        let q = resolve(p, prev);
        deepest = deepest.max(limit - dist(q));
        if (q - prev).dot(tangent) < 0.5 * 2e-3 {
            put_back += 1;
        }
    }
    println!("{name}: {put_back} of 100000 slides put back; deepest {deepest:.2e} m");
    assert_eq!(put_back, 0, "{name}");
    assert!(deepest < 1e-6, "{name}: ended {deepest} m inside");
}

#[test]
fn sliding_along_a_sphere_never_sticks() {
    let (center, limit) = (Vec3::new(0.3, 1.6, -0.2), 0.11);
    slides(
        "sphere",
        |p, prev| push_out_of_sphere(p, prev, center, limit),
        |rng| {
            let n = unit(rng);
            (center + n * limit, n)
        },
        |q| (q - center).length(),
        limit,
    );
}

#[test]
fn sliding_along_a_capsule_never_sticks() {
    let (a, b, limit) = (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.1, 1.4, 0.05), 0.08);
    let axis_point = |q: Vec3| {
        let ab = b - a;
        a + ab * ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    };
    slides(
        "capsule",
        |p, prev| push_out_of_capsule(p, prev, a, b, limit),
        |rng| {
            let c = a.lerp(b, rng.range_f32(-0.2, 1.2));
            let c = axis_point(c);
            let n = unit(rng);
            let on = c + n * limit;
            // The surface point's own normal (at the caps it is radial from the end).
            let n = (on - axis_point(on)).normalize();
            (axis_point(on) + n * limit, n)
        },
        |q| (q - axis_point(q)).length(),
        limit,
    );
}

/// A point crossing a thin capsule (a 1 cm rod) at 10 m/s in one 1/60 s step, from every
/// direction and at every offset from the axis, never passes through it: the straight
/// path from where it was to where it is put stays outside the rod (it may slide around a
/// rod it only grazed), and a head-on hit stops on the side it came from.
#[test]
fn a_fast_point_through_a_thin_capsule_is_caught() {
    let (a, b, limit) = (Vec3::new(0.0, -0.5, 0.0), Vec3::new(0.0, 0.5, 0.0), 0.01);
    let axis_dist = |p: Vec3, q: Vec3| {
        // Closest approach of the segment p–q to the axis segment, by dense sampling (an
        // independent check of the solver's own closest-point code).
        (0..=2000)
            .map(|k| {
                let x = p.lerp(q, k as f32 / 2000.0);
                (x - Vec3::new(0.0, x.y.clamp(-0.5, 0.5), 0.0)).length()
            })
            .fold(f32::MAX, f32::min)
    };
    let mut rng = SplitMix64::new(3);
    let mut head_on = 0;
    for _ in 0..10_000 {
        let heading = rng.range_f32(0.0, std::f32::consts::TAU);
        let dir = Vec3::new(heading.cos(), rng.range_f32(-0.3, 0.3), heading.sin()).normalize();
        let side = dir.cross(Vec3::Y).normalize();
        let offset = rng.range_f32(-0.009, 0.009);
        let centre = Vec3::new(0.0, rng.range_f32(-0.4, 0.4), 0.0) + side * offset;
        let step = dir * (10.0 / 60.0);
        let (prev, p) = (centre - step * 0.5, centre + step * 0.5);
        assert!(
            axis_dist(prev, p) < limit,
            "the test's path must cross the rod"
        );
        assert!(axis_dist(prev, prev) > limit && axis_dist(p, p) > limit);
        let q = push_out_of_capsule(p, prev, a, b, limit);
        let clear = axis_dist(prev, q);
        assert!(
            clear >= limit * (1.0 - 1e-3),
            "through the rod: from {prev} to {p}, resolved {q} ({clear} from the axis)"
        );
        if offset.abs() < 0.001 && dir.y.abs() < 0.05 {
            head_on += 1;
            let horizontal = |v: Vec3| Vec3::new(v.x, 0.0, v.z);
            assert!(
                horizontal(q).dot(dir) < 0.0,
                "head on, yet past the rod: from {prev} to {p}, resolved {q}"
            );
        }
    }
    assert!(head_on > 50, "{head_on} head-on cases");
}

/// A long step that grazes the shape: its path's closest approach swept across the depth
/// at which it counts as entering (1e-4 of the contact distance) in steps of `delta`. The
/// entry point is taken on the same surface as the test, so the redirection fades to
/// nothing at the threshold: it is the rest of the step (0.15 m) times the sine of the
/// angle at which the path meets that surface, ≈ sqrt(2·depth / limit), so between two
/// samples `delta` apart the result may change by about 0.15·sqrt(2·delta / limit) and
/// not more (asserted with a factor of 2), whatever `delta`. Before, the slide started
/// from the real surface and the result jumped by 2.1 mm at the threshold (a 0.3 m step
/// past a 0.08 m sphere), however fine the sampling: found by the KawaiiPhysics
/// reference test with contacts.
fn continuous_across_threshold(name: &str, resolve: impl Fn(Vec3, Vec3) -> Vec3, limit: f32) {
    let tol = 1e-4 * limit;
    for delta in [1e-7f32, 1e-8] {
        // The path runs along +Y at closest approach `limit − tol + e` from the centre or
        // axis (along +Z), from 0.15 m before the closest point to 0.15 m after it.
        let mut last: Option<Vec3> = None;
        let mut worst = 0.0f32;
        for k in -20..=20 {
            let z = limit - tol + k as f32 * delta;
            let out = resolve(Vec3::new(0.0, 0.15, z), Vec3::new(0.0, -0.15, z));
            if let Some(l) = last {
                worst = worst.max((out - l).length());
            }
            last = Some(out);
        }
        let bound = 2.0 * 0.15 * (2.0 * delta / limit).sqrt();
        println!("{name}: largest change between dips {delta:e} m apart: {worst:.2e} m (bound {bound:.1e})");
        assert!(
            worst <= bound,
            "{name}: the result jumps by {worst} m at the entry threshold"
        );
    }
}

#[test]
fn grazing_contacts_are_continuous() {
    let limit = 0.08;
    continuous_across_threshold(
        "sphere",
        |p, prev| push_out_of_sphere(p, prev, Vec3::ZERO, limit),
        limit,
    );
    // A capsule along X: the path along Y grazes its side.
    let (a, b) = (Vec3::new(-0.2, 0.0, 0.0), Vec3::new(0.2, 0.0, 0.0));
    continuous_across_threshold(
        "capsule",
        |p, prev| push_out_of_capsule(p, prev, a, b, limit),
        limit,
    );
}
