//! The particle-constraint world (seed 001) against closed forms and invariants.

use glam::{Quat, Vec3};
use tassel::dynamics::particles::{ParticleSettings, ParticleWorld};
use tassel::Transform;

/// Solves `length = 2a·sinh(span / 2a)` for the catenary parameter `a` by bisection
/// (the left side falls monotonically in `a` towards `span`).
fn catenary_a(span: f32, length: f32) -> f64 {
    let (span, length) = (span as f64, length as f64);
    let f = |a: f64| 2.0 * a * (span / (2.0 * a)).sinh() - length;
    let (mut lo, mut hi) = (1e-3, 1e3);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn rope_pinned_at_both_ends_hangs_as_a_catenary() {
    let (span, length, n) = (1.6_f32, 2.0_f32, 20);
    let mut w = ParticleWorld::new(ParticleSettings {
        iterations: 120,
        damping: 0.03,
        ..Default::default()
    });
    // Built straight at its full length, then the far end is pinned closer in.
    let rope = w.add_rope(Vec3::ZERO, Vec3::new(length, 0.0, 0.0), n, 1.0);
    w.pin(rope[0], Vec3::ZERO).unwrap();
    w.pin(rope[n - 1], Vec3::new(span, 0.0, 0.0)).unwrap();
    for _ in 0..20 * 60 {
        w.step(1.0 / 60.0).unwrap();
    }
    // Settled: nothing moves any more and the sticks are at their length.
    let before: Vec<Vec3> = w.positions().to_vec();
    w.step(1.0 / 60.0).unwrap();
    let drift = before
        .iter()
        .zip(w.positions())
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f32::max);
    assert!(drift < 1e-5, "still moving by {drift} m per frame");
    let segment = length / (n - 1) as f32;
    for s in w.sticks() {
        let l = (w.position(s.a) - w.position(s.b)).length();
        assert!(
            (l - segment).abs() < 0.002 * segment,
            "stick stretched to {l}"
        );
    }
    // Mid-span: the middle of the central (horizontal) segment between particles 9, 10.
    let mid = 0.5 * (w.position(rope[n / 2 - 1]) + w.position(rope[n / 2]));
    let sag = -mid.y as f64;
    let a = catenary_a(span, length);
    let expected = a * ((span as f64 / (2.0 * a)).cosh() - 1.0);
    let err = (sag - expected).abs() / expected;
    println!(
        "catenary: a = {a:.4} m, sag {sag:.4} m, closed form {expected:.4} m, error {:.2} %",
        100.0 * err
    );
    assert!(
        err < 0.02,
        "sag {sag} vs catenary {expected}: {:.2} %",
        100.0 * err
    );
    assert!((mid.x - 0.5 * span).abs() < 1e-3, "the rope is symmetric");
}

#[test]
fn tetrahedron_keeps_its_edges_when_it_hits_the_ground() {
    let mut w = ParticleWorld::new(ParticleSettings::default());
    let edge = 0.5;
    let tilt = Quat::from_rotation_z(0.4) * Quat::from_rotation_x(0.3);
    let ids = w.add_tetrahedron(Vec3::new(0.0, 1.0, 0.0), edge, tilt, 1.0);
    for i in 0..4 {
        for j in i + 1..4 {
            let l = (w.position(ids[i]) - w.position(ids[j])).length();
            assert!((l - edge).abs() < 1e-5, "built edge {l}");
        }
    }
    w.add_ground(0.0);
    let mut worst = 0.0_f32;
    let mut lowest = f32::MAX;
    for _ in 0..180 {
        w.step(1.0 / 60.0).unwrap();
        for i in 0..4 {
            lowest = lowest.min(w.position(ids[i]).y);
            for j in i + 1..4 {
                let l = (w.position(ids[i]) - w.position(ids[j])).length();
                worst = worst.max((l - edge).abs() / edge);
            }
        }
    }
    println!(
        "tetrahedron: worst edge error {:.3} %, lowest point {lowest:.5} m",
        100.0 * worst
    );
    assert!(worst < 0.01, "edges changed by {:.2} %", 100.0 * worst);
    assert!(lowest > -1e-4, "a corner went {lowest} m under the ground");
    // It landed: its lowest corner rests on the ground.
    let min_y = ids
        .iter()
        .map(|&i| w.position(i).y)
        .fold(f32::MAX, f32::min);
    assert!(min_y.abs() < 1e-3, "resting at {min_y}");
}

#[test]
fn free_fall_matches_the_closed_form() {
    let mut w = ParticleWorld::new(ParticleSettings {
        damping: 0.0,
        ..Default::default()
    });
    let p = w.add_particle(Vec3::ZERO, 1.0);
    // 1 s in 120 steps. Verlet from rest (prev = pos) gives y_n = −g·h²·n(n+1)/2.
    for _ in 0..60 {
        w.step(1.0 / 60.0).unwrap();
    }
    let (g, h, n) = (9.81_f64, 1.0_f64 / 120.0, 120.0_f64);
    let expected = -g * h * h * n * (n + 1.0) / 2.0;
    let y = w.position(p).y as f64;
    assert!((y - expected).abs() < 1e-4, "{y} vs {expected}");
    // And within one step's drift of ½·g·t².
    assert!((y + 0.5 * g).abs() < g * h, "{y}");
}

#[test]
fn angle_constraint_keeps_a_folded_joint_open() {
    let mut w = ParticleWorld::new(ParticleSettings {
        gravity: Vec3::ZERO,
        damping: 0.1,
        ..Default::default()
    });
    let c = w.add_particle(Vec3::ZERO, 1.0);
    let a = w.add_particle(Vec3::X, 1.0);
    let b = w.add_particle(Vec3::new(0.3_f32.cos(), 0.3_f32.sin(), 0.0), 1.0);
    w.add_stick(c, a).unwrap();
    w.add_stick(c, b).unwrap();
    w.pin(c, Vec3::ZERO).unwrap();
    // 1 and 2 radians, given in degrees.
    w.add_angle_constraint(a, c, b, 1f32.to_degrees(), 2f32.to_degrees())
        .unwrap();
    for _ in 0..120 {
        w.step(1.0 / 60.0).unwrap();
        let (da, db) = (w.position(a) - w.position(c), w.position(b) - w.position(c));
        let angle = da.angle_between(db);
        assert!((1.0 - 1e-3..=2.0 + 1e-3).contains(&angle), "angle {angle}");
        assert!((da.length() - 1.0).abs() < 1e-3 && (db.length() - 1.0).abs() < 1e-3);
    }
}

#[test]
fn friction_stops_a_sliding_particle() {
    let run = |friction: f32| {
        let mut w = ParticleWorld::new(ParticleSettings {
            damping: 0.0,
            friction,
            ..Default::default()
        });
        w.add_ground(0.0);
        let p = w.add_particle(Vec3::ZERO, 1.0);
        w.set_velocity(p, Vec3::new(1.0, 0.0, 0.0));
        for _ in 0..60 {
            w.step(1.0 / 60.0).unwrap();
        }
        w.position(p)
    };
    let slick = run(0.0);
    let rough = run(1.0);
    assert!(
        slick.y.abs() < 1e-3 && rough.y.abs() < 1e-3,
        "{slick} {rough}"
    );
    assert!(rough.x < 0.02, "friction 1 keeps sliding: {rough}");
    assert!(
        slick.x > 0.5 * rough.x + 0.5,
        "no friction should slide on: {slick}"
    );
}

#[test]
fn attached_particle_follows_its_bone() {
    let mut w = ParticleWorld::new(ParticleSettings::default());
    let rope = w.add_rope(Vec3::ZERO, Vec3::new(0.0, -1.0, 0.0), 5, 1.0);
    w.attach(rope[0], 1, Vec3::new(0.0, 0.1, 0.0)).unwrap();
    let models = [
        Transform::IDENTITY,
        Transform::from_translation_rotation(
            Vec3::new(1.0, 2.0, 0.0),
            Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
        ),
    ];
    let component = Transform::from_translation(Vec3::new(0.0, 0.0, 3.0));
    w.follow_bones(&models, &component).unwrap();
    w.step(1.0 / 60.0).unwrap();
    // By hand: the offset (0, 0.1, 0) turned 90° about Z is (−0.1, 0, 0).
    let expected = Vec3::new(0.9, 2.0, 3.0);
    assert!(
        (w.position(rope[0]) - expected).length() < 1e-5,
        "{}",
        w.position(rope[0])
    );
    // A pose without that bone is an error, not a panic.
    let e = w
        .follow_bones(&models[..1], &component)
        .unwrap_err()
        .to_string();
    assert!(e.contains("joint 1"), "{e}");
}

#[test]
fn rope_in_wind_lies_along_wind_plus_gravity() {
    // A uniform body force on a hanging chain: at rest it is straight, along the sum of
    // wind and gravity, at atan(wind / g) from the vertical.
    let wind = 6.0_f32;
    let mut w = ParticleWorld::new(ParticleSettings {
        wind: Vec3::new(wind, 0.0, 0.0),
        damping: 0.05,
        iterations: 30,
        ..Default::default()
    });
    let rope = w.add_rope(Vec3::ZERO, Vec3::new(0.0, -1.0, 0.0), 10, 0.2);
    w.pin(rope[0], Vec3::ZERO).unwrap();
    for _ in 0..900 {
        w.step(1.0 / 60.0).unwrap();
    }
    let expected = wind.atan2(9.81);
    for &i in &rope[1..] {
        let d = w.position(i);
        let angle = d.x.atan2(-d.y);
        assert!(
            (angle - expected).abs() < 0.01,
            "particle {i} at {angle} rad, expected {expected}"
        );
    }
}

#[test]
fn gusts_are_seeded_and_deterministic() {
    let run = |seed: u64| {
        let mut w = ParticleWorld::new(ParticleSettings {
            wind: Vec3::new(3.0, 0.0, 1.0),
            gust: 0.8,
            seed,
            ..Default::default()
        });
        let ids = w.add_cloth(Vec3::ZERO, Vec3::X, Vec3::NEG_Y, [4, 4], true, 1.0);
        w.pin(ids[0], Vec3::ZERO).unwrap();
        for _ in 0..120 {
            w.step(1.0 / 60.0).unwrap();
        }
        w.positions()
            .iter()
            .flat_map(|p| p.to_array())
            .map(f32::to_bits)
            .collect::<Vec<_>>()
    };
    assert_eq!(run(7), run(7));
    assert_ne!(run(7), run(8));
}

#[test]
fn cloth_builder_counts_by_hand() {
    let mut w = ParticleWorld::new(ParticleSettings::default());
    let ids = w.add_cloth(Vec3::ZERO, Vec3::X, Vec3::Y, [4, 3], true, 1.0);
    assert_eq!(ids.len(), 12);
    // Horizontal 3·3, vertical 4·2, two diagonals in each of 3·2 cells.
    assert_eq!(w.sticks().len(), 9 + 8 + 12);
    let mut plain = ParticleWorld::new(ParticleSettings::default());
    plain.add_cloth(Vec3::ZERO, Vec3::X, Vec3::Y, [4, 3], false, 1.0);
    assert_eq!(plain.sticks().len(), 17);
}

#[test]
fn bad_input_is_an_error_naming_the_problem() {
    let mut w = ParticleWorld::new(ParticleSettings::default());
    let a = w.add_particle(Vec3::ZERO, 1.0);
    assert!(w.step(f32::NAN).is_err());
    assert!(w.step(-1.0).is_err());
    let e = w.add_stick(a, 5).unwrap_err().to_string();
    assert!(e.contains("particle 5"), "{e}");
    assert!(w.add_soft_stick(a, a, 2.0).is_err());
    assert!(w.pin(a, Vec3::NAN).is_err());
    w.settings.iterations = 0;
    let e = w.step(0.1).unwrap_err().to_string();
    assert!(e.contains("iterations"), "{e}");
    w.settings.iterations = 4;
    w.settings.radius = -0.1;
    let e = w.step(0.1).unwrap_err().to_string();
    assert!(e.contains("radius"), "{e}");
}

#[test]
fn a_huge_time_step_is_capped_and_stays_finite() {
    let mut w = ParticleWorld::new(ParticleSettings::default());
    let ids = w.add_cloth(Vec3::ZERO, Vec3::X, Vec3::NEG_Z, [5, 5], true, 1.0);
    w.pin(ids[0], Vec3::ZERO).unwrap();
    w.add_ground(-3.0);
    w.step(1.0e6).unwrap();
    assert!(w.positions().iter().all(|p| p.is_finite()));
    // At most max_steps_per_frame steps of free fall: y ≥ −g·(24h)²·(1 + 1/24)/2.
    let h = 1.0 / 120.0_f32;
    let bound = 9.81 * (24.0 * h) * (24.0 * h) * (25.0 / 24.0) / 2.0 + 1.5;
    assert!(
        w.positions().iter().all(|p| p.y > -bound),
        "fell too far in one capped call"
    );
}

#[test]
fn charm_rope_follows_the_hand_keeps_its_bones_on_the_particles_and_stays_out_of_the_thigh() {
    use tassel::builtin::{self, DemoScript};
    use tassel::CharacterSim;
    let c = builtin::character();
    let sk = &c.skeleton;
    let mut sim = CharacterSim::new(sk.clone(), &c.rig).unwrap();
    let script = DemoScript;
    let mut animator = script.animator(&c);
    let mut locals = sk.rest().to_vec();
    let bones: Vec<usize> = (0..5)
        .map(|i| sk.find(&format!("charm_{i}")).unwrap())
        .collect();
    let thigh = c
        .rig
        .colliders
        .iter()
        .position(|col| col.name == "thigh_l")
        .unwrap();
    let dt = 1.0 / 60.0;
    let (mut worst_bone, mut worst_inside, mut swing) = (0.0_f32, 0.0_f32, 0.0_f32);
    for f in 0..=600 {
        let m = script.at(f as f32 * dt);
        let step = if f == 0 { 0.0 } else { dt };
        script
            .pose(&c, &mut animator, &m, step, &mut locals)
            .unwrap();
        let animated_tip = {
            let mut pose = tassel::Pose::rest(sk);
            pose.locals.copy_from_slice(&locals);
            tassel::LocalToModelJob {
                skeleton: sk,
                root: Transform::IDENTITY,
                locals: &pose.locals,
                models: &mut pose.models,
            }
            .run()
            .unwrap();
            m.component
                .transform_point(pose.models[bones[4]].translation)
        };
        sim.frame(&locals, m.component, step).unwrap();
        let pose = sim.pose();
        let world = sim.ropes().world(0);
        let out = sim.ropes().output_positions(0);
        // The written-back bones lie along the output's directions (the pose plus the
        // particles' interpolated deviation) with their rest lengths, so bone k is off
        // output point k by at most the sum of the length errors before it (collisions
        // and the interpolation can stretch a stick a little).
        let mut allowed = 1e-4;
        for (k, &b) in bones.iter().enumerate() {
            if k > 0 {
                let s = world.sticks()[k - 1];
                allowed += ((out[k] - out[k - 1]).length() - s.length).abs();
            }
            let bone = m.component.transform_point(pose.models[b].translation);
            let e = (bone - out[k]).length();
            assert!(
                e <= allowed,
                "frame {f}: charm_{k} is {e} m off its output point (allowed {allowed})"
            );
            worst_bone = worst_bone.max(e);
        }
        // The colliders the last step used (none before the first step).
        let Some(placed) = world.colliders.first() else {
            continue;
        };
        assert_eq!(placed.shape, c.rig.colliders[thigh].shape);
        for p in world.positions() {
            worst_inside = worst_inside.max(placed.penetration(*p, 0.0));
            assert!(p.y > -1e-4, "below the ground: {p}");
        }
        swing = swing.max((world.position(4) - animated_tip).length());
    }
    println!("charm: bones at most {worst_bone:.5} m off the output, worst thigh penetration {worst_inside:.5} m, largest swing {swing:.3} m");
    assert!(worst_inside <= 1e-3, "{worst_inside} m inside the thigh");
    assert!(swing > 0.02, "the rope never swung: {swing} m");
}

#[test]
fn rope_on_a_tilted_bone_settles_hanging_straight_down() {
    use tassel::dynamics::rope::RopeSettings;
    use tassel::dynamics::RigSettings;
    use tassel::{CharacterSim, SkeletonBuilder};
    let mut b = SkeletonBuilder::new();
    let root = b.add(
        "root",
        None,
        Transform::from_translation(Vec3::new(0.0, 2.0, 0.0)),
    );
    // The rope starts sideways along +X.
    let mut p = b.add("r0", Some(root), Transform::IDENTITY);
    for i in 1..5 {
        p = b.add(
            format!("r{i}"),
            Some(p),
            Transform::from_translation(Vec3::new(0.1, 0.0, 0.0)),
        );
    }
    let sk = b.build().unwrap().0;
    let rig = RigSettings {
        ropes: vec![RopeSettings {
            name: "r".into(),
            root: "r0".into(),
            end: "r4".into(),
            ..Default::default()
        }],
        ..Default::default()
    };
    let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
    let rest = sk.rest().to_vec();
    for _ in 0..1200 {
        sim.frame(&rest, Transform::IDENTITY, 1.0 / 60.0).unwrap();
    }
    let pose = sim.pose();
    for i in 1..5 {
        let j = sk.find(&format!("r{i}")).unwrap();
        let expected = Vec3::new(0.0, 2.0 - 0.1 * i as f32, 0.0);
        let got = pose.models[j].translation;
        assert!(
            (got - expected).length() < 2e-3,
            "r{i} at {got}, expected {expected}"
        );
    }
    // A bone on a rope and a chain at once is refused.
    let mut both = rig.clone();
    both.chains.push(tassel::dynamics::chain::ChainSettings {
        name: "c".into(),
        root: "r2".into(),
        ..Default::default()
    });
    let e = CharacterSim::new(sk.clone(), &both)
        .unwrap_err()
        .to_string();
    // r2 is the chain's root (the chain turns it) and a rope bone; r3 is moved by both.
    assert!(
        (e.contains("'r2'") || e.contains("'r3'")) && e.contains("chain") && e.contains("rope"),
        "{e}"
    );
}
