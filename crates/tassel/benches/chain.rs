//! Criterion bench: one frame of 16 chains × 8 joints with 8 colliders (fixed mode, one
//! 60 Hz step per frame), single thread. Throughput is reported per simulated joint.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;
use tassel::{builtin, CharacterSim, Transform};

fn chain_frame(c: &mut Criterion) {
    let (sk, rig) = builtin::bench_character(16, 8, 8);
    let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
    let rest = sk.rest().to_vec();
    let simulated = (sim.chains().point_count() - sim.chains().chain_count()) as u64;
    let mut g = c.benchmark_group("chain");
    g.throughput(Throughput::Elements(simulated));
    let mut f = 0u32;
    g.bench_function("16x8_joints_8_colliders_frame", |b| {
        b.iter(|| {
            f += 1;
            let t = f as f32 / 60.0;
            let comp = Transform::from_translation(glam::Vec3::new((3.0 * t).sin() * 0.5, 0.0, t));
            black_box(sim.frame(black_box(&rest), comp, 1.0 / 60.0).unwrap());
        })
    });
    g.finish();
}

/// World collision on a chain away from all geometry (500 m above a 1 000-collider level)
/// against the same frame without the option: one BVH query per character and frame.
fn world_far(c: &mut Criterion) {
    let (sk, mut rig) = builtin::bench_character(16, 8, 8);
    let level = std::sync::Arc::new(
        tassel::controller::Level::new(builtin::level::bench_level(1000, 7)).unwrap(),
    );
    let rest = sk.rest().to_vec();
    let mut g = c.benchmark_group("chain_world_far");
    for on in [false, true] {
        for ch in &mut rig.chains {
            ch.world_collision = on;
        }
        let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
        sim.set_level(Some(level.clone()));
        let mut f = 0u32;
        g.bench_function(if on { "world_collision" } else { "off" }, |b| {
            b.iter(|| {
                f += 1;
                let t = f as f32 / 60.0;
                let comp =
                    Transform::from_translation(glam::Vec3::new((3.0 * t).sin() * 0.5, 500.0, t));
                black_box(sim.frame(black_box(&rest), comp, 1.0 / 60.0).unwrap());
            })
        });
    }
    g.finish();
}

criterion_group!(benches, chain_frame, world_far);
criterion_main!(benches);
