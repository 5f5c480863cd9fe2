//! One `move_shape` call of Tassel's controller and of rapier3d 0.36.1's
//! `KinematicCharacterController`, side by side in one run, on the same level
//! (`builtin::level::bench_level(1000, 7)`: the demo level and seeded boxes, spheres and
//! capsules), the same capsule (1.7 m, radius 0.28), the same settings (skin/offset 1 cm,
//! step 0.3 m with 0.1 m of room, 45° slopes, snap 0.3 m) and the same three poses as the
//! criterion bench `crates/tassel/benches/controller.rs`: a flat walk, a diagonal walk into
//! a wall, and the move that climbs the first stair riser.
//!
//! Run: `cargo run --release --manifest-path bench/controller_vs_rapier/Cargo.toml`
//! (from the repository root). Prints the median of 41 rounds of 2 000 calls per case and
//! engine, rounds interleaved so that both see the same machine load, and the ratio.

use rapier3d::control::{CharacterAutostep, CharacterLength, KinematicCharacterController};
use rapier3d::prelude::*;
use std::hint::black_box;
use std::time::Instant;
use tassel::builtin::level::{bench_level, STAIRS};
use tassel::controller::{CharacterCapsule, ControllerSettings, Level, LevelShape};
use tassel::glam::{Quat as TQuat, Vec3 as TVec3};
use tassel::Transform;

fn v(p: TVec3) -> Vector {
    Vector::new(p.x, p.y, p.z)
}

fn rapier_level(colliders: &[tassel::controller::LevelCollider]) -> ColliderSet {
    let mut set = ColliderSet::new();
    for c in colliders {
        let b = match &c.shape {
            LevelShape::Box { half_extents: h } => ColliderBuilder::cuboid(h.x, h.y, h.z),
            LevelShape::Sphere { radius } => ColliderBuilder::ball(*radius),
            LevelShape::Capsule {
                half_height,
                radius,
            } => ColliderBuilder::capsule_y(*half_height, *radius),
            LevelShape::Ramp {
                width,
                length,
                height,
            } => {
                let (w, l, h) = (0.5 * width, *length, *height);
                let pts = [
                    TVec3::new(-w, 0.0, 0.0),
                    TVec3::new(w, 0.0, 0.0),
                    TVec3::new(-w, 0.0, l),
                    TVec3::new(w, 0.0, l),
                    TVec3::new(-w, h, l),
                    TVec3::new(w, h, l),
                ]
                .map(v);
                ColliderBuilder::convex_hull(&pts).expect("ramp hull")
            }
            LevelShape::TriMesh { vertices, indices } => {
                ColliderBuilder::trimesh(vertices.iter().map(|&p| v(p)).collect(), indices.clone())
                    .expect("trimesh")
            }
        };
        let axis = c.rotation.to_scaled_axis();
        set.insert(b.translation(v(c.position)).rotation(v(axis)).build());
    }
    set
}

fn median(mut xs: Vec<f64>) -> f64 {
    xs.sort_by(f64::total_cmp);
    xs[xs.len() / 2]
}

fn main() {
    let colliders = bench_level(1000, 7);
    let level = Level::new(colliders.clone()).unwrap();

    // rapier: fixed colliders, one step to fill the broad phase.
    let mut bodies = RigidBodySet::new();
    let mut set = rapier_level(&colliders);
    let mut islands = IslandManager::new();
    let mut broad_phase = DefaultBroadPhase::new();
    let mut narrow_phase = NarrowPhase::new();
    PhysicsPipeline::new().step(
        Vector::ZERO,
        &IntegrationParameters::default(),
        &mut islands,
        &mut broad_phase,
        &mut narrow_phase,
        &mut bodies,
        &mut set,
        &mut ImpulseJointSet::new(),
        &mut MultibodyJointSet::new(),
        &mut SoftBodySet::new(),
        &mut CCDSolver::new(),
        &(),
        &(),
    );
    let queries = broad_phase.as_query_pipeline(
        narrow_phase.query_dispatcher(),
        &bodies,
        &set,
        QueryFilter::default(),
    );

    let capsule = CharacterCapsule::with_height(1.7, 0.28);
    let s = ControllerSettings::default();
    let kcc = KinematicCharacterController {
        up: Vector::Y,
        offset: CharacterLength::Absolute(s.skin),
        slide: true,
        autostep: Some(CharacterAutostep {
            max_height: CharacterLength::Absolute(s.max_step_height),
            min_width: CharacterLength::Absolute(s.min_step_width),
            include_dynamic_bodies: false,
        }),
        max_slope_climb_angle: s.max_climb_angle.to_radians(),
        min_slope_slide_angle: s.min_slide_angle.to_radians(),
        snap_to_ground: Some(CharacterLength::Absolute(s.snap_to_ground)),
        normal_nudge_factor: 1.0e-4,
    };
    let shape = SharedShape::capsule_y(capsule.half_height, capsule.radius);
    let dt = 1.0f32 / 60.0;
    let centre_y = capsule.half_total_height() + s.skin;
    let walk = TVec3::new(0.0, -9.81 * dt * dt, 1.4 * dt);

    // The three poses of the criterion bench.
    let flat = TVec3::new(0.0, centre_y, 1.0);
    let at_wall = TVec3::new(1.2 - 0.28 - s.skin, centre_y, 25.0);
    let diagonal = TVec3::new(1.0, 0.0, 1.0).normalize() * 1.4 * dt + TVec3::new(0.0, walk.y, 0.0);
    let mut pose = Transform::from_translation(TVec3::new(0.0, centre_y, STAIRS.3 - 0.6));
    let before_step = loop {
        let m = s.move_shape(&level, &capsule, &pose, walk, dt).unwrap();
        if m.stepped {
            break pose.translation;
        }
        pose.translation += m.translation;
        assert!(
            pose.translation.z < STAIRS.3 + 0.5,
            "never climbed the riser"
        );
    };
    let cases = [
        ("walk_flat", flat, walk),
        ("walk_into_wall", at_wall, diagonal),
        ("walk_up_stairs", before_step, walk),
    ];

    const CALLS: usize = 2000;
    const ROUNDS: usize = 41;
    println!("one move_shape call, 1 000 colliders, median of {ROUNDS} rounds of {CALLS} calls");
    println!(
        "| case | tassel µs | rapier 0.36.1 µs | rapier / tassel | rapier moved | tassel moved |"
    );
    println!("|---|---|---|---|---|---|");
    for (name, at, desired) in cases {
        let tpose = Transform::from_translation(at);
        let rpose = Pose::from_translation(v(at));
        let (mut tt, mut rt) = (Vec::new(), Vec::new());
        for _ in 0..ROUNDS {
            let t0 = Instant::now();
            for _ in 0..CALLS {
                black_box(
                    s.move_shape(&level, &capsule, black_box(&tpose), desired, dt)
                        .unwrap(),
                );
            }
            tt.push(t0.elapsed().as_secs_f64() / CALLS as f64 * 1e6);
            let t0 = Instant::now();
            for _ in 0..CALLS {
                black_box(kcc.move_shape(
                    dt,
                    &queries,
                    &*shape,
                    black_box(&rpose),
                    v(desired),
                    |_| {},
                ));
            }
            rt.push(t0.elapsed().as_secs_f64() / CALLS as f64 * 1e6);
        }
        let tm = s.move_shape(&level, &capsule, &tpose, desired, dt).unwrap();
        let rm = kcc.move_shape(dt, &queries, &*shape, &rpose, v(desired), |_| {});
        let (t, r) = (median(tt), median(rt));
        println!(
            "| {name} | {t:.2} | {r:.2} | {:.2}× | [{:.4}, {:.4}, {:.4}] | [{:.4}, {:.4}, {:.4}] |",
            r / t,
            rm.translation.x,
            rm.translation.y,
            rm.translation.z,
            tm.translation.x,
            tm.translation.y,
            tm.translation.z
        );
    }
    let _ = TQuat::IDENTITY;
}
