//! Criterion bench: one `move_shape` call in a level of 1 000 colliders (the demo level and
//! seeded boxes, spheres and capsules), single thread: walking on flat ground, walking
//! diagonally into a wall, and a walking move that climbs a 0.18 m stair step (checked in
//! the set-up).

use criterion::{criterion_group, criterion_main, Criterion};
use glam::{Quat, Vec3};
use std::hint::black_box;
use tassel::builtin::level::{bench_level, bench_moves};
use tassel::controller::{CharacterCapsule, ControllerSettings, Level};

fn controller(c: &mut Criterion) {
    let level = Level::new(bench_level(1000, 7)).unwrap();
    assert_eq!(level.len(), 1000);
    let capsule = CharacterCapsule::with_height(1.7, 0.28);
    let s = ControllerSettings::default();
    let dt = 1.0 / 60.0;
    let mut g = c.benchmark_group("move_shape_1000_colliders");
    // The pose of the stair case is found by walking up to the riser (a fixed guess
    // missed the edge and timed a plain walk); asserted here, in the set-up, so that
    // release builds check it too.
    for (name, pose, desired) in bench_moves(&level).unwrap() {
        let m = s.move_shape(&level, &capsule, &pose, desired, dt).unwrap();
        if name == "walk_up_stairs" {
            assert!(
                m.stepped && m.translation.y > 0.0,
                "the stair case must climb the step: {m:?}"
            );
        }
        g.bench_function(name, |b| {
            b.iter(|| {
                black_box(
                    s.move_shape(&level, &capsule, black_box(&pose), desired, dt)
                        .unwrap(),
                )
            })
        });
    }
    g.finish();
}

/// Moving 10 colliders of the 1 000-collider level by one frame's motion: `set_pose`
/// (each leaf updated in place in the BVH) against building the level again.
fn level_edit(c: &mut Criterion) {
    let colliders = bench_level(1000, 7);
    let mut level = Level::new(colliders.clone()).unwrap();
    let movers: Vec<usize> = (0..10).map(|i| 100 + 90 * i).collect();
    let mut g = c.benchmark_group("level_edit_10_of_1000");
    let mut t = 0.0f32;
    g.bench_function("set_pose", |b| {
        b.iter(|| {
            t += 1.0 / 60.0;
            level.start_frame();
            for &id in &movers {
                let p = colliders[id].position + Vec3::new(t.sin(), 0.0, t.cos());
                level.set_pose(id, p, Quat::IDENTITY).unwrap();
            }
        })
    });
    g.bench_function("rebuild", |b| {
        b.iter(|| {
            t += 1.0 / 60.0;
            let mut moved = colliders.clone();
            for &id in &movers {
                moved[id].position += Vec3::new(t.sin(), 0.0, t.cos());
            }
            black_box(Level::new(moved).unwrap())
        })
    });
    g.finish();
}

criterion_group!(benches, controller, level_edit);
criterion_main!(benches);
