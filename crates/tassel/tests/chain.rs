//! Bone-chain scenarios checked against closed forms and invariants.

use glam::{Quat, Vec3};
use tassel::collide::Shape;
use tassel::dynamics::chain::{
    ChainJob, ChainRig, ChainSettings, ChainState, PlanarAxis, TimeMode,
};
use tassel::dynamics::{ColliderSettings, RigSettings};
use tassel::{Pose, Skeleton, Transform};

/// A straight chain: an anchor, then `n` bones of `len` along `dir`.
fn line_skeleton(n: usize, len: f32, dir: Vec3) -> Skeleton {
    let mut names = vec!["anchor".to_string()];
    let mut parents = vec![None];
    let mut rest = vec![Transform::IDENTITY];
    for i in 0..n {
        names.push(format!("b{i}"));
        parents.push(Some(i));
        rest.push(Transform::from_translation(dir * len));
    }
    Skeleton::new(names, parents, rest).unwrap()
}

fn chain(settings: ChainSettings) -> ChainSettings {
    ChainSettings {
        name: "c".into(),
        root: "anchor".into(),
        ..settings
    }
}

struct Sim {
    sk: Skeleton,
    rig: ChainRig,
    state: ChainState,
    pose: Pose,
}

impl Sim {
    fn new(sk: Skeleton, rig: RigSettings) -> Self {
        let rig_c = ChainRig::new(&sk, &rig).unwrap();
        let state = ChainState::new(&rig_c);
        let pose = Pose::rest(&sk);
        Self {
            sk,
            rig: rig_c,
            state,
            pose,
        }
    }

    /// One frame with the animated pose = rest pose; returns world positions of points.
    fn frame(&mut self, component: Transform, dt: f32) -> Vec<Vec3> {
        let mut locals = self.sk.rest().to_vec();
        let mut models = Pose::rest(&self.sk).models;
        ChainJob {
            skeleton: &self.sk,
            rig: &self.rig,
            state: &mut self.state,
            component,
            dt,
            locals: &mut locals,
            models: &mut models,
            level: None,
        }
        .run()
        .unwrap();
        self.pose = Pose { locals, models };
        self.state
            .output_positions()
            .iter()
            .map(|&p| component.transform_point(p))
            .collect()
    }
}

fn free(mode: TimeMode, fps: f32) -> ChainSettings {
    chain(ChainSettings {
        damping: 0.0,
        stiffness: 0.0,
        world_damping_location: 0.0,
        world_damping_rotation: 0.0,
        mode,
        target_framerate: fps,
        ..Default::default()
    })
}

#[test]
fn pendulum_period_matches_small_angle_formula() {
    let l = 1.0f32;
    let theta0 = 0.1f32;
    let dir = Quat::from_rotation_z(theta0) * -Vec3::Y;
    let sk = line_skeleton(1, l, dir);
    let rig = RigSettings {
        chains: vec![free(TimeMode::Fixed, 600.0)],
        ..Default::default()
    };
    let mut sim = Sim::new(sk, rig);
    // Stiffness 0: the animated pose only sets the start. Record x(t) and find the times
    // x crosses zero going the same way.
    let dt = 1.0 / 600.0;
    let mut crossings = Vec::new();
    let mut last_x = sim.frame(Transform::IDENTITY, 0.0)[1].x;
    for f in 1..6000 {
        let x = sim.frame(Transform::IDENTITY, dt)[1].x;
        if last_x > 0.0 && x <= 0.0 {
            let t = (f as f32 - 1.0 + last_x / (last_x - x)) * dt;
            crossings.push(t);
        }
        last_x = x;
    }
    assert!(
        crossings.len() >= 3,
        "pendulum did not swing: {crossings:?}"
    );
    let periods: Vec<f32> = crossings.windows(2).map(|w| w[1] - w[0]).collect();
    let mean = periods.iter().sum::<f32>() / periods.len() as f32;
    let expected = 2.0 * std::f32::consts::PI * (l / 9.81).sqrt();
    assert!(
        ((mean - expected) / expected).abs() < 0.02,
        "period {mean} vs {expected}"
    );
}

#[test]
fn chain_released_horizontally_hangs_straight_down() {
    for mode in [TimeMode::Fixed, TimeMode::Classic] {
        let sk = line_skeleton(4, 0.1, Vec3::X);
        let mut s = free(mode, 60.0);
        s.damping = 0.1;
        if mode == TimeMode::Classic {
            // Classic mode applies gravity as seed 000 writes it: location += g·dt.
            s.gravity = Vec3::new(0.0, -0.5, 0.0);
        }
        let mut sim = Sim::new(
            sk,
            RigSettings {
                chains: vec![s],
                ..Default::default()
            },
        );
        let mut pts = Vec::new();
        for _ in 0..600 {
            pts = sim.frame(Transform::IDENTITY, 1.0 / 60.0);
        }
        for w in pts.windows(2) {
            let d = (w[1] - w[0]).normalize();
            assert!(d.dot(-Vec3::Y) > 0.999, "{mode:?}: bone direction {d}");
            assert!(((w[1] - w[0]).length() - 0.1).abs() < 1e-5);
        }
        // The written-back pose agrees with the points.
        let tip = sim.pose.models[4].translation;
        assert!(tip.abs_diff_eq(pts[4], 1e-4), "{tip} vs {}", pts[4]);
    }
}

#[test]
fn stiffness_one_gives_the_animated_pose() {
    for mode in [TimeMode::Fixed, TimeMode::Classic] {
        let sk = line_skeleton(5, 0.1, Vec3::new(0.3, -1.0, 0.2).normalize());
        let mut s = free(mode, 60.0);
        s.stiffness = 1.0;
        let mut sim = Sim::new(
            sk.clone(),
            RigSettings {
                chains: vec![s],
                ..Default::default()
            },
        );
        let rest = Pose::rest(&sk);
        for f in 0..200 {
            let t = f as f32 / 60.0;
            let comp = Transform::from_translation_rotation(
                Vec3::new((3.0 * t).sin(), 0.0, t),
                Quat::from_rotation_y(2.0 * t),
            );
            let pts = sim.frame(comp, 1.0 / 60.0);
            for (i, p) in pts.iter().enumerate() {
                let want = comp.transform_point(rest.models[i].translation);
                assert!(
                    p.abs_diff_eq(want, 1e-5),
                    "{mode:?} frame {f} point {i}: {p} vs {want}"
                );
            }
        }
    }
}

fn collider(name: &str, offset: Vec3, shape: Shape) -> ColliderSettings {
    ColliderSettings {
        mirror: None,
        mirror_bone: String::new(),
        name: name.into(),
        bone: "anchor".into(),
        offset,
        rotation: Quat::from_rotation_x(0.4),
        shape,
    }
}

#[test]
fn points_never_end_a_frame_inside_colliders() {
    let shapes = [
        collider(
            "sphere",
            Vec3::new(0.15, -0.35, 0.0),
            Shape::Sphere {
                radius: 0.12,
                inside: false,
            },
        ),
        collider(
            "capsule",
            Vec3::new(-0.2, -0.3, 0.05),
            Shape::Capsule {
                radius: 0.06,
                length: 0.3,
            },
        ),
        collider(
            "box",
            Vec3::new(0.0, -0.6, 0.0),
            Shape::Box {
                half_extents: Vec3::new(0.4, 0.05, 0.4),
            },
        ),
        collider(
            "inside",
            Vec3::ZERO,
            Shape::Sphere {
                radius: 0.55,
                inside: true,
            },
        ),
    ];
    for mode in [TimeMode::Fixed, TimeMode::Classic] {
        let sk = line_skeleton(6, 0.08, Vec3::new(1.0, 0.2, 0.1).normalize());
        let mut s = free(mode, 60.0);
        s.damping = 0.05;
        s.radius = 0.02;
        if mode == TimeMode::Classic {
            s.gravity = Vec3::new(0.0, -0.3, 0.0);
        }
        let rig = RigSettings {
            chains: vec![s],
            colliders: shapes.to_vec(),
            ..Default::default()
        };
        let mut sim = Sim::new(sk, rig);
        let mut worst = f32::MIN;
        for f in 0..400 {
            // Shake the character hard so points hit the shapes at speed.
            let t = f as f32 / 60.0;
            let comp = Transform::from_translation_rotation(
                Vec3::new(0.3 * (9.0 * t).sin(), 0.2 * (7.0 * t).cos(), 0.0),
                Quat::from_rotation_z(0.3 * (5.0 * t).sin()),
            );
            sim.frame(comp, 1.0 / 60.0);
            let out = sim.state.output_positions();
            for (p, &x) in out.iter().enumerate().skip(1) {
                for c in sim.state.placed_colliders() {
                    worst = worst.max(c.penetration(x, sim.rig.point_radius(p)));
                }
            }
        }
        assert!(
            worst <= 1e-4,
            "{mode:?}: a point ended a frame {worst} m inside a collider"
        );
    }
}

/// Tip world position per frame for a swaying character at render rate `hz`.
fn sway(mode: TimeMode, hz: f32, seconds: f32) -> (Vec<f32>, Vec<Vec3>, Vec<Vec3>) {
    let sk = line_skeleton(5, 0.1, -Vec3::Y);
    let mut s = chain(ChainSettings {
        mode,
        damping: 0.05,
        stiffness: 0.02,
        ..Default::default()
    });
    s.world_damping_location = 0.0;
    s.world_damping_rotation = 0.0;
    if mode == TimeMode::Classic {
        s.gravity = Vec3::new(0.0, -9.81 / 60.0, 0.0);
    }
    let mut sim = Sim::new(
        sk.clone(),
        RigSettings {
            chains: vec![s],
            ..Default::default()
        },
    );
    let rest = Pose::rest(&sk);
    let frames = (seconds * hz).round() as usize;
    let (mut times, mut tips, mut rigid) = (vec![], vec![], vec![]);
    for f in 0..=frames {
        let t = f as f32 / hz;
        let comp = Transform::from_translation_rotation(
            Vec3::new(0.3 * (std::f32::consts::TAU * t).sin(), 0.0, 0.0),
            Quat::from_rotation_y(0.5 * (std::f32::consts::TAU * 0.7 * t).sin()),
        );
        let pts = sim.frame(comp, if f == 0 { 0.0 } else { 1.0 / hz });
        times.push(t);
        tips.push(pts[5]);
        rigid.push(comp.transform_point(rest.models[5].translation));
    }
    (times, tips, rigid)
}

/// RMS difference of runs at 30 and 144 Hz against 60 Hz at shared times, and the RMS
/// dynamic deviation of the 60 Hz tip.
fn frame_rate_spread(mode: TimeMode) -> (f32, f32) {
    let (t60, tip60, rigid60) = sway(mode, 60.0, 4.0);
    let mut diff2 = 0.0;
    let mut n = 0;
    for hz in [30.0, 144.0] {
        let (t, tip, _) = sway(mode, hz, 4.0);
        for (i, &ti) in t.iter().enumerate() {
            // Shared instants: multiples of 1/6 s after the first second.
            let k = (ti * 6.0).round();
            if (ti * 6.0 - k).abs() > 1e-3 || ti < 1.0 {
                continue;
            }
            let j = t60.iter().position(|&u| (u - ti).abs() < 1e-4).unwrap();
            diff2 += (tip[i] - tip60[j]).length_squared();
            n += 1;
        }
    }
    let dev2: f32 = tip60
        .iter()
        .zip(&rigid60)
        .skip(60)
        .map(|(a, b)| (*a - *b).length_squared())
        .sum::<f32>()
        / (tip60.len() - 60) as f32;
    ((diff2 / n as f32).sqrt(), dev2.sqrt())
}

#[test]
fn fixed_mode_agrees_across_frame_rates() {
    let (spread, deviation) = frame_rate_spread(TimeMode::Fixed);
    let (classic_spread, classic_dev) = frame_rate_spread(TimeMode::Classic);
    println!(
        "fixed: rms spread {spread:.5} m = {:.2} % of dynamic deviation {deviation:.4} m; classic: {classic_spread:.5} m = {:.1} % of {classic_dev:.4} m",
        100.0 * spread / deviation,
        100.0 * classic_spread / classic_dev
    );
    assert!(
        deviation > 0.01,
        "the sway barely moves the chain: {deviation}"
    );
    assert!(
        spread < 0.01 * deviation,
        "fixed mode spread {spread} vs deviation {deviation}"
    );
}

#[test]
fn bad_time_steps_and_hitches() {
    let sk = line_skeleton(3, 0.1, Vec3::X);
    let mut sim = Sim::new(
        sk.clone(),
        RigSettings {
            chains: vec![free(TimeMode::Fixed, 60.0)],
            ..Default::default()
        },
    );
    let mut locals = sk.rest().to_vec();
    let mut models = Pose::rest(&sk).models;
    for dt in [f32::NAN, -1.0, f32::INFINITY] {
        let e = ChainJob {
            skeleton: &sk,
            rig: &sim.rig,
            state: &mut sim.state,
            component: Transform::IDENTITY,
            dt,
            locals: &mut locals,
            models: &mut models,
            level: None,
        }
        .run();
        assert!(e.is_err(), "dt {dt} accepted");
    }
    // A 5 s hitch and a 100 m teleport: finite, lengths kept, back near the pose.
    sim.frame(Transform::IDENTITY, 1.0 / 60.0);
    let pts = sim.frame(Transform::IDENTITY, 5.0);
    assert!(pts.iter().all(|p| p.is_finite()));
    let far = Transform::from_translation(Vec3::new(100.0, 0.0, 0.0));
    let pts = sim.frame(far, 1.0 / 60.0);
    assert_eq!(sim.state.teleport_count(), 1);
    for (i, w) in pts.windows(2).enumerate() {
        assert!(((w[1] - w[0]).length() - 0.1).abs() < 1e-4, "bone {i}");
    }
    assert!(pts[0].abs_diff_eq(Vec3::new(100.0, 0.0, 0.0), 1e-4));
}

#[test]
fn same_inputs_same_bits() {
    let run = || {
        let sk = line_skeleton(6, 0.1, Vec3::X);
        let mut s = free(TimeMode::Fixed, 60.0);
        s.wind.speed = 0.01;
        s.wind.direction = Vec3::Z;
        let mut sim = Sim::new(
            sk,
            RigSettings {
                chains: vec![s],
                ..Default::default()
            },
        );
        let mut bits = Vec::new();
        for f in 0..300 {
            let comp = Transform::from_translation(Vec3::new((f as f32 * 0.1).sin(), 0.0, 0.0));
            for p in sim.frame(comp, 1.0 / 75.0) {
                bits.extend([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]);
            }
        }
        bits
    };
    assert_eq!(run(), run());
}

#[test]
fn wind_pushes_the_chain_downwind() {
    let sk = line_skeleton(4, 0.1, -Vec3::Y);
    let mut s = free(TimeMode::Fixed, 60.0);
    s.damping = 0.2;
    s.gravity = Vec3::ZERO;
    s.wind.direction = Vec3::Z;
    s.wind.speed = 0.002;
    let mut sim = Sim::new(
        sk,
        RigSettings {
            chains: vec![s],
            ..Default::default()
        },
    );
    let mut pts = Vec::new();
    for _ in 0..300 {
        pts = sim.frame(Transform::IDENTITY, 1.0 / 60.0);
    }
    // Without gravity or stiffness the steady wind lays the chain along +Z.
    let dir = (pts[4] - pts[0]).normalize();
    assert!(dir.z > 0.9, "chain direction {dir}");
}

/// The planar constraint keeps every bone perpendicular to its parent joint's axis: a
/// chain released along X under gravity and a wind along Z (which lays an unconstrained
/// chain along Z, as above) with its bones kept perpendicular to the parents' Z axis
/// (world Z: the pose is the rest pose, every rotation the identity) swings in the XY
/// plane, every bone's Z within rounding of zero at every frame; the same chain without
/// the constraint leaves the plane.
#[test]
fn planar_constraint_keeps_every_bone_in_its_plane() {
    let largest_z = |planar: PlanarAxis| {
        let mut s = free(TimeMode::Fixed, 60.0);
        s.damping = 0.1;
        s.wind.direction = Vec3::Z;
        s.wind.speed = 0.004;
        s.planar_constraint = planar;
        let rig = RigSettings {
            chains: vec![s],
            ..Default::default()
        };
        let mut sim = Sim::new(line_skeleton(4, 0.1, Vec3::X), rig);
        let mut largest = 0.0f32;
        for _ in 0..240 {
            let pts = sim.frame(Transform::IDENTITY, 1.0 / 60.0);
            for p in 1..pts.len() {
                let bone = pts[p] - pts[p - 1];
                largest = largest.max(bone.z.abs() / bone.length());
            }
        }
        largest
    };
    let kept = largest_z(PlanarAxis::Z);
    assert!(kept < 1e-5, "a bone left the plane by {kept} of its length");
    let free_z = largest_z(PlanarAxis::None);
    assert!(
        free_z > 0.1,
        "the wind barely pushed the free chain ({free_z})"
    );
}

#[test]
fn alpha_warmup_and_turn_teleport() {
    // alpha 0: the animated pose, whatever the dynamics.
    let sk = line_skeleton(4, 0.1, Vec3::X);
    let mut s = free(TimeMode::Fixed, 60.0);
    s.alpha = 0.0;
    let mut sim = Sim::new(
        sk.clone(),
        RigSettings {
            chains: vec![s],
            ..Default::default()
        },
    );
    let rest = Pose::rest(&sk);
    for _ in 0..30 {
        let pts = sim.frame(Transform::IDENTITY, 1.0 / 60.0);
        for (i, p) in pts.iter().enumerate() {
            assert!(p.abs_diff_eq(rest.models[i].translation, 1e-5));
        }
    }
    // Warm-up: 600 steps on the first frame let a horizontal chain fall to hang already.
    let mut s = free(TimeMode::Fixed, 60.0);
    s.damping = 0.1;
    s.warmup_steps = 600;
    let mut sim = Sim::new(
        sk.clone(),
        RigSettings {
            chains: vec![s],
            ..Default::default()
        },
    );
    let pts = sim.frame(Transform::IDENTITY, 0.0);
    assert!(
        (pts[4] - pts[0]).normalize().dot(-Vec3::Y) > 0.99,
        "{}",
        pts[4]
    );
    // Turning 90° in one frame (threshold 60°) resets to the animated pose.
    let mut sim = Sim::new(
        sk.clone(),
        RigSettings {
            chains: vec![free(TimeMode::Fixed, 60.0)],
            ..Default::default()
        },
    );
    for _ in 0..20 {
        sim.frame(Transform::IDENTITY, 1.0 / 60.0);
    }
    let turned = Transform::from_translation_rotation(
        Vec3::ZERO,
        Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
    );
    let pts = sim.frame(turned, 1.0 / 60.0);
    assert_eq!(sim.state.teleport_count(), 1);
    for (i, p) in pts.iter().enumerate() {
        assert!(p.abs_diff_eq(turned.transform_point(rest.models[i].translation), 1e-5));
    }
}

/// `classic_gravity`: one classic frame from rest drops a horizontal 1 m bone's tip by
/// the chosen KawaiiPhysics gravity step δ (g·dt, ½·g·dt² or g·dt²), then the bone length
/// puts it back on the unit circle: y = −δ / √(1 + δ²), by hand.
#[test]
fn classic_gravity_steps_are_kawaiiphysics_three_versions() {
    use tassel::dynamics::chain::ClassicGravity;
    let dt = 1.0f32 / 60.0;
    let g = 9.81f32;
    for (mode, delta) in [
        (ClassicGravity::PerFrame, g * dt),
        (ClassicGravity::HalfDtSquared, 0.5 * g * dt * dt),
        (ClassicGravity::DtSquared, g * dt * dt),
    ] {
        let rig = RigSettings {
            chains: vec![ChainSettings {
                classic_gravity: mode,
                ..free(TimeMode::Classic, 60.0)
            }],
            ..Default::default()
        };
        let mut sim = Sim::new(line_skeleton(1, 1.0, Vec3::X), rig);
        sim.frame(Transform::IDENTITY, 0.0);
        let tip = sim.frame(Transform::IDENTITY, dt)[1];
        let want = -delta / (1.0 + delta * delta).sqrt();
        assert!(
            (tip.y - want).abs() < 1e-6 && ((tip.length() - 1.0).abs() < 1e-6),
            "{mode:?}: tip {tip}, want y = {want}"
        );
    }
    // Read from a rig file by name.
    let rig = RigSettings::from_toml_str(
        "[[chain]]\nname = \"c\"\nroot = \"anchor\"\nmode = \"classic\"\nclassic_gravity = \"half_dt_squared\"\n",
    )
    .unwrap();
    assert_eq!(rig.chains[0].classic_gravity, ClassicGravity::HalfDtSquared);
}

/// A chain that starts again (a teleport past its threshold) leaves the other chains of
/// the character alone: a chain that does not reset gives the same bits with a resetting
/// chain before it in the rig as on its own, through a jump in the middle of a motion
/// whose colliders move (the steps of the jump frame interpolate the colliders between
/// last frame's placement and this one's, whatever another chain does).
#[test]
fn a_chain_reset_does_not_change_the_other_chains() {
    let (sk, mut rig) = tassel::builtin::bench_character(2, 6, 4);
    for ch in &mut rig.chains {
        ch.stiffness = 0.1;
        ch.target_framerate = 90.0; // steps between frames: colliders interpolated
    }
    rig.chains[0].teleport_distance = 0.5;
    rig.chains[1].teleport_distance = 0.0;
    rig.chains[1].teleport_rotation = 0.0;
    let alone = RigSettings {
        chains: vec![rig.chains[1].clone()],
        ..rig.clone()
    };
    let run = |rig: &RigSettings| -> Vec<[u32; 3]> {
        let chains = ChainRig::new(&sk, rig).unwrap();
        let mut state = ChainState::new(&chains);
        let last = chains.chain_points(chains.chain_count() - 1);
        let mut out = Vec::new();
        let mut resets = 0;
        for f in 0..120 {
            let t = f as f32 / 60.0;
            let mut locals = sk.rest().to_vec();
            // The root swings: the colliders (on the root) move in model space.
            locals[0].rotation = Quat::from_rotation_z(0.6 * (4.0 * t).sin());
            let mut models = locals.clone();
            tassel::LocalToModelJob {
                skeleton: &sk,
                root: Transform::IDENTITY,
                locals: &locals,
                models: &mut models,
            }
            .run()
            .unwrap();
            let jump = if f >= 60 { 3.0 } else { 0.0 };
            let before = state.teleport_count();
            ChainJob {
                skeleton: &sk,
                rig: &chains,
                state: &mut state,
                component: Transform::from_translation(Vec3::new(jump, 0.0, 0.1 * t)),
                dt: 1.0 / 60.0,
                locals: &mut locals,
                models: &mut models,
                level: None,
            }
            .run()
            .unwrap();
            resets += state.teleport_count() - before;
            for p in last.clone() {
                out.push(state.output_positions()[p].to_array().map(f32::to_bits));
            }
        }
        if rig.chains.len() == 2 {
            assert_eq!(resets, 1, "the first chain resets once, on the jump");
        }
        out
    };
    let (with, without) = (run(&rig), run(&alone));
    assert_eq!(with.len(), without.len());
    let first = with.iter().zip(&without).position(|(a, b)| a != b);
    assert_eq!(first, None, "first differing point (frame × 6 + point)");
}

/// A chain state made for another rig (other chains, other twins) is refused by name,
/// not read out of its bounds.
#[test]
fn a_state_of_another_rig_is_refused() {
    let (sk, rig) = tassel::builtin::bench_character(4, 5, 2);
    let (_, other) = tassel::builtin::bench_character(4, 5, 2);
    let chains = ChainRig::new(&sk, &rig).unwrap();
    let fewer = RigSettings {
        chains: other.chains[..3].to_vec(),
        ..other
    };
    let mut wrong = ChainState::new(&ChainRig::new(&sk, &fewer).unwrap());
    let mut locals = sk.rest().to_vec();
    let mut models = locals.clone();
    let err = ChainJob {
        skeleton: &sk,
        rig: &chains,
        state: &mut wrong,
        component: Transform::IDENTITY,
        dt: 1.0 / 60.0,
        locals: &mut locals,
        models: &mut models,
        level: None,
    }
    .run()
    .unwrap_err();
    assert!(err.to_string().contains("another chain rig"), "{err}");
}
