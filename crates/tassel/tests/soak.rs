//! Soak: every solver for many frames under hostile conditions — hitches (dt from 0 to
//! 1 s), 1 km teleports, NaN and infinite inputs, zero-length bones and colliders on top of
//! bones. Checked on every frame: no panic; a frame with a bad input is refused (an error)
//! and one with good input is accepted; the output is finite; bones keep their lengths
//! (write-back turns bones, it never stretches them; a spring controller's bone, which
//! moves, excepted); and one second of simulated time
//! after the last disturbance the simulated joints move no faster, relative to the
//! animated pose, than `MAX_SPEED` (energy bounded, recovery within a second).
//!
//! `cargo test --release -p tassel --test soak -- --nocapture` runs 20 000 frames per
//! solver (CI); `TASSEL_SOAK_FRAMES=1000000` runs the full soak of 10⁶ frames each.

use glam::{Quat, Vec3};
use tassel::anim::{Playback, SamplingCursor, SamplingJob};
use tassel::dynamics::chain::TimeMode;
use tassel::dynamics::vrm::{
    VrmCollider, VrmColliderGroup, VrmJoint, VrmMode, VrmOptions, VrmShape, VrmSpring,
    VrmSpringBones, VrmTail,
};
use tassel::dynamics::RigSettings;
use tassel::rng::SplitMix64;
use tassel::{builtin, CharacterSim, Skeleton, SkeletonBuilder, Transform};

/// Relative to the animated pose, m/s: hair and cloth flung by the walk and sway move
/// well under this; a solver gaining energy passes it.
const MAX_SPEED: f32 = 25.0;

fn frames() -> u64 {
    std::env::var("TASSEL_SOAK_FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20_000)
}

struct Report {
    accepted: u64,
    refused: u64,
    events: u64,
    worst_calm_speed: f32,
    worst_length_error: f32,
}

/// Drives `sim` with the walk clip (when the skeleton is the built-in one) plus a sway,
/// and the disturbances, for `n` frames; asserts the invariants on every frame.
fn soak(name: &str, mut sim: CharacterSim, simulated: &[usize], seed: u64, n: u64) -> Report {
    let skeleton = sim.skeleton().clone();
    let c = builtin::character();
    let clip = (skeleton.len() == c.skeleton.len()).then(|| &c.clips[1]);
    let mut cursor = clip.map(SamplingCursor::new);
    let mut rng = SplitMix64::new(seed);
    let mut locals = skeleton.rest().to_vec();
    let mut base = Vec3::ZERO;
    let mut t = 0.0f32;
    let mut since_event = 0.0f32;
    let mut last_dev: Option<Vec<Vec3>> = None;
    let mut r = Report {
        accepted: 0,
        refused: 0,
        events: 0,
        worst_calm_speed: 0.0,
        worst_length_error: 0.0,
    };
    for f in 0..n {
        let roll = rng.range_f32(0.0, 1.0);
        let mut dt = 1.0 / 60.0;
        let mut bad = false;
        let mut event = true;
        if roll < 0.01 {
            dt = rng.range_f32(0.0, 1.0); // a hitch
        } else if roll < 0.015 {
            dt = 0.0;
        } else if roll < 0.017 {
            // A 1 km teleport in a random horizontal direction.
            let a = rng.range_f32(0.0, std::f32::consts::TAU);
            base += Vec3::new(a.cos(), 0.0, a.sin()) * 1000.0;
            if base.length() > 1.0e5 {
                base = Vec3::ZERO;
            }
        } else if roll < 0.022 {
            bad = true; // NaN or infinity somewhere in the input
        } else {
            event = false;
        }
        t += dt;
        if let (Some(clip), Some(cursor)) = (clip, cursor.as_mut()) {
            SamplingJob {
                clip,
                cursor,
                time: t,
                playback: Playback::Loop,
                locals: &mut locals,
            }
            .run()
            .unwrap();
        }
        let sway = Vec3::new(0.3 * (t * 6.0).sin(), 0.05 * (t * 11.0).sin(), 0.0);
        let mut component = Transform::from_translation_rotation(
            base + sway,
            Quat::from_rotation_y(0.6 * (t * 2.5).sin()),
        );
        let mut frame_dt = dt;
        if bad {
            let k = (rng.next_u64() % locals.len() as u64) as usize;
            match rng.next_u64() % 4 {
                0 => frame_dt = f32::NAN,
                1 => component.translation.x = f32::INFINITY,
                2 => locals[k].rotation.y = f32::NAN,
                _ => locals[k].translation.z = f32::NAN,
            }
        }
        let result = sim.frame(&locals, component, frame_dt);
        assert_eq!(
            result.is_err(),
            bad,
            "{name} frame {f}: bad input {bad}, result {:?}",
            result.as_ref().err()
        );
        if bad {
            r.refused += 1;
            locals.copy_from_slice(skeleton.rest());
            r.events += 1;
            since_event = 0.0;
            continue;
        }
        r.accepted += 1;
        let pose = sim.pose();
        let animated = sim.animated_models();
        for j in 0..skeleton.len() {
            assert!(
                pose.models[j].is_finite() && pose.locals[j].is_finite(),
                "{name} frame {f}: joint '{}' is not finite",
                skeleton.name(j)
            );
            // A spring controller moves its bone (translation channel): not a rotation.
            let moved = name == "springs" && simulated.contains(&j);
            if let (Some(p), false) = (skeleton.parent(j), moved) {
                let out = (pose.models[j].translation - pose.models[p].translation).length();
                let want = (animated[j].translation - animated[p].translation).length();
                let err = (out - want).abs();
                r.worst_length_error = r.worst_length_error.max(err);
                assert!(
                    err <= 1e-3 * want.max(1.0),
                    "{name} frame {f}: bone to '{}' is {out} m, animated {want} m",
                    skeleton.name(j)
                );
            }
        }
        let dev: Vec<Vec3> = simulated
            .iter()
            .map(|&j| pose.models[j].translation - animated[j].translation)
            .collect();
        if event {
            r.events += 1;
            since_event = 0.0;
        } else {
            since_event += dt;
            if since_event >= 1.0 {
                if let Some(prev) = &last_dev {
                    let speed = dev
                        .iter()
                        .zip(prev)
                        .map(|(a, b)| (*a - *b).length() / dt)
                        .fold(0.0f32, f32::max);
                    r.worst_calm_speed = r.worst_calm_speed.max(speed);
                    assert!(
                        speed <= MAX_SPEED,
                        "{name} frame {f}: a simulated joint moves {speed} m/s relative to \
                         the animation, {since_event} s after the last disturbance"
                    );
                }
            }
        }
        last_dev = Some(dev);
        locals.copy_from_slice(skeleton.rest());
    }
    println!(
        "{name}: {} frames accepted, {} refused, {} disturbances; worst speed 1 s after a \
         disturbance {:.2} m/s; worst bone length error {:.2e} m",
        r.accepted, r.refused, r.events, r.worst_calm_speed, r.worst_length_error
    );
    r
}

/// The built-in character with only one kind of solver of its rig.
fn builtin_with(keep: &str, mode: TimeMode) -> (CharacterSim, Vec<usize>) {
    let c = builtin::character();
    let mut rig = RigSettings {
        colliders: c.rig.colliders.clone(),
        ..RigSettings::default()
    };
    match keep {
        "chains" => {
            rig.chains = c.rig.chains.clone();
            for ch in &mut rig.chains {
                ch.mode = mode;
            }
        }
        "springs" => rig.springs = c.rig.springs.clone(),
        "cloth" => rig.cloths = c.rig.cloths.clone(),
        "ropes" => rig.ropes = c.rig.ropes.clone(),
        _ => unreachable!(),
    }
    let sim = CharacterSim::new(c.skeleton.clone(), &rig).unwrap();
    let simulated = sim.simulated_joints().to_vec();
    assert!(!simulated.is_empty(), "{keep}: nothing simulated");
    (sim, simulated)
}

/// A 7-bone hanging chain with a zero-length bone in the middle, a sphere centred exactly
/// on one joint, a capsule along two bones, a plane through the root.
fn degenerate_skeleton() -> Skeleton {
    let mut b = SkeletonBuilder::new();
    let mut p = b.add(
        "root",
        None,
        Transform::from_translation(Vec3::new(0.0, 1.5, 0.0)),
    );
    for (i, y) in [-0.1, -0.1, 0.0, -0.1, -0.1, -0.1, -0.1]
        .into_iter()
        .enumerate()
    {
        p = b.add(
            format!("j{i}"),
            Some(p),
            Transform::from_translation(Vec3::new(0.0, y, 0.02)),
        );
    }
    b.build().unwrap().0
}

fn degenerate_vrm(mode: VrmMode) -> (CharacterSim, Vec<usize>) {
    let sk = degenerate_skeleton();
    let j = |name: &str| sk.find(name).unwrap();
    let colliders = vec![
        VrmCollider {
            joint: j("j3"),
            shape: VrmShape::Sphere {
                offset: Vec3::ZERO,
                radius: 0.05,
                inside: false,
            },
        },
        VrmCollider {
            joint: j("j1"),
            shape: VrmShape::Capsule {
                offset: Vec3::ZERO,
                tail: Vec3::new(0.0, -0.2, 0.0),
                radius: 0.03,
                inside: false,
            },
        },
        VrmCollider {
            joint: j("root"),
            shape: VrmShape::Plane {
                offset: Vec3::ZERO,
                normal: Vec3::NEG_Y,
            },
        },
    ];
    let joints: Vec<VrmJoint> = (0..6)
        .map(|i| VrmJoint {
            joint: j(&format!("j{i}")),
            tail: VrmTail::Joint(j(&format!("j{}", i + 1))),
            hit_radius: 0.02,
            stiffness: 0.5,
            gravity_power: 0.3,
            gravity_dir: Vec3::NEG_Y,
            drag_force: 0.4,
            limit: None,
        })
        .collect();
    let bones = VrmSpringBones {
        colliders,
        collider_groups: vec![VrmColliderGroup {
            name: "all".into(),
            colliders: vec![0, 1, 2],
        }],
        springs: vec![VrmSpring {
            name: "hair".into(),
            joints,
            collider_groups: vec![0],
            center: None,
        }],
        ..Default::default()
    };
    let options = VrmOptions {
        mode,
        ..VrmOptions::default()
    };
    let sim = CharacterSim::with_vrm(sk, &RigSettings::default(), &bones, options).unwrap();
    let simulated = sim.simulated_joints().to_vec();
    (sim, simulated)
}

fn degenerate_chain(mode: TimeMode) -> (CharacterSim, Vec<usize>) {
    let sk = degenerate_skeleton();
    let text = r#"
[[collider]]
name = "on_joint"
bone = "j3"
shape = "sphere"
radius = 0.05

[[collider]]
name = "along"
bone = "j1"
shape = "capsule"
radius = 0.03
length = 0.2

[[chain]]
name = "c"
root = "j0"
radius = 0.02
dummy_bone_length = 0.05
limit_angle = 60.0
"#;
    let mut rig = RigSettings::from_toml_str(text).unwrap();
    rig.chains[0].mode = mode;
    let sim = CharacterSim::new(sk, &rig).unwrap();
    let simulated = sim.simulated_joints().to_vec();
    (sim, simulated)
}

#[test]
fn every_solver_survives_hostile_frames() {
    let n = frames();
    let cases: Vec<(&str, (CharacterSim, Vec<usize>))> = vec![
        ("chains classic", builtin_with("chains", TimeMode::Classic)),
        ("chains fixed", builtin_with("chains", TimeMode::Fixed)),
        ("springs", builtin_with("springs", TimeMode::Fixed)),
        ("cloth", builtin_with("cloth", TimeMode::Fixed)),
        ("ropes", builtin_with("ropes", TimeMode::Fixed)),
        (
            "VRM spec (zero-length bone, colliders on bones)",
            degenerate_vrm(VrmMode::Spec),
        ),
        (
            "VRM fixed (zero-length bone, colliders on bones)",
            degenerate_vrm(VrmMode::Fixed),
        ),
        (
            "chain classic (zero-length bone, colliders on bones)",
            degenerate_chain(TimeMode::Classic),
        ),
        (
            "chain fixed (zero-length bone, colliders on bones)",
            degenerate_chain(TimeMode::Fixed),
        ),
    ];
    for (i, (name, (sim, simulated))) in cases.into_iter().enumerate() {
        let r = soak(name, sim, &simulated, 0x5eed + i as u64, n);
        assert_eq!(r.accepted + r.refused, n);
        assert!(
            r.refused > 0 && r.events > n / 100,
            "{name}: too few disturbances"
        );
    }
}

#[test]
fn same_disturbances_same_bits() {
    let run = || {
        let (mut sim, _) = builtin_with("chains", TimeMode::Fixed);
        let c = builtin::character();
        let mut rng = SplitMix64::new(9);
        let mut locals = c.skeleton.rest().to_vec();
        let mut hash = 0u64;
        for f in 0..600 {
            let dt = if f % 50 == 7 {
                rng.range_f32(0.0, 1.0)
            } else {
                1.0 / 60.0
            };
            let comp = Transform::from_translation(Vec3::new((f as f32 * 0.1).sin(), 0.0, 0.0));
            locals.copy_from_slice(c.skeleton.rest());
            sim.frame(&locals, comp, dt).unwrap();
            for m in &sim.pose().models {
                for v in m
                    .translation
                    .to_array()
                    .into_iter()
                    .chain(m.rotation.to_array())
                {
                    hash = hash.rotate_left(5) ^ v.to_bits() as u64;
                }
            }
        }
        hash
    };
    assert_eq!(run(), run());
}

/// A refused frame changes nothing: after it, the next good frame gives the same bits as
/// on a copy that never saw the bad one.
#[test]
fn a_refused_frame_leaves_the_state_untouched() {
    let c = builtin::character();
    let mut sim = CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap();
    let rest = c.skeleton.rest().to_vec();
    let at = |f: usize| Transform::from_translation(Vec3::new((f as f32 * 0.1).sin(), 0.0, 0.0));
    for f in 0..60 {
        sim.frame(&rest, at(f), 1.0 / 60.0).unwrap();
    }
    let mut twin = sim.clone();
    let mut bad = rest.clone();
    bad[5].rotation = Quat::from_xyzw(0.0, 0.0, 0.0, 3.0); // not a rotation
    let mut far = rest.clone();
    far[0].translation.x = 2.0e6; // beyond the coordinate limit
    for (locals, comp, dt) in [
        (&bad, at(60), 1.0 / 60.0),
        (&far, at(60), 1.0 / 60.0),
        (&rest, at(60), -1.0),
        (&rest, at(60), f32::NAN),
        (
            &rest,
            Transform::from_translation(Vec3::splat(f32::INFINITY)),
            1.0 / 60.0,
        ),
    ] {
        let e = sim.frame(locals, comp, dt).unwrap_err().to_string();
        assert!(
            e.contains("joint") || e.contains("character transform") || e.contains("time step"),
            "{e}"
        );
    }
    let a = sim.frame(&rest, at(60), 1.0 / 60.0).unwrap().models.clone();
    let b = twin
        .frame(&rest, at(60), 1.0 / 60.0)
        .unwrap()
        .models
        .clone();
    assert_eq!(a, b);
}
