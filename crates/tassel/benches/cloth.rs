//! Criterion bench: one 60 Hz frame of the built-in character's skirt alone (one bone
//! cloth of 40 points, 4 leg capsules, 120 Hz steps), single thread, with the same
//! motion as `tassel bench --cloth` (a 0.5 m sideways sway at 3 rad/s while walking
//! forward at 1 m/s). Issue 16's target for it is 25 µs per frame.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use tassel::crowd::SimdUse;
use tassel::dynamics::RigSettings;
use tassel::{builtin, CharacterSim, Transform};

fn skirt_frame(c: &mut Criterion) {
    let ch = builtin::character();
    let rig = RigSettings {
        cloths: ch.rig.cloths.clone(),
        colliders: ch.rig.colliders.clone(),
        ..Default::default()
    };
    let rest = ch.skeleton.rest().to_vec();
    // The lanes (the default) and the scalar reference, which give the same bits.
    for (name, simd) in [
        ("cloth/builtin_skirt_frame", SimdUse::Auto),
        ("cloth/builtin_skirt_frame_scalar", SimdUse::Scalar),
    ] {
        let mut sim = CharacterSim::new(ch.skeleton.clone(), &rig).unwrap();
        assert_eq!(sim.cloths().point_count(), 40);
        sim.set_simd(simd);
        let mut f = 0u32;
        c.bench_function(name, |b| {
            b.iter(|| {
                f += 1;
                let t = f as f32 / 60.0;
                let comp =
                    Transform::from_translation(glam::Vec3::new((3.0 * t).sin() * 0.5, 0.0, t));
                black_box(sim.frame(black_box(&rest), comp, 1.0 / 60.0).unwrap());
            })
        });
    }
}

criterion_group!(benches, skirt_frame);
criterion_main!(benches);
