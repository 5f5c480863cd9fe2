//! Scaffolding shared by the core's scenario tests (each test file uses part of it).
#![allow(dead_code)]

use glam::{DQuat, DVec3, Quat, Vec3};
use std::sync::Arc;
use tassel::controller::{Level, LevelCollider, LevelShape};
use tassel::{Skeleton, Transform};

/// An anchor joint at `anchor` and `n` bones `b0..` of `len` along `dir`.
pub fn line(n: usize, len: f32, dir: Vec3, anchor: Vec3) -> Skeleton {
    let mut names = vec!["anchor".to_string()];
    let mut parents = vec![None];
    let mut rest = vec![Transform::from_translation(anchor)];
    for i in 0..n {
        names.push(format!("b{i}"));
        parents.push(Some(i));
        rest.push(Transform::from_translation(dir * len));
    }
    Skeleton::new(names, parents, rest).unwrap()
}

/// A level box centred at `centre`.
pub fn boxed(name: &str, centre: Vec3, half: Vec3) -> LevelCollider {
    LevelCollider::new(name, LevelShape::Box { half_extents: half }, centre)
}

/// A floor: the top of a 100 m box at y = 0.
pub fn floor() -> Arc<Level> {
    let floor = boxed(
        "floor",
        Vec3::new(0.0, -0.5, 0.0),
        Vec3::new(50.0, 0.5, 50.0),
    );
    Arc::new(Level::new(vec![floor]).unwrap())
}

/// A 5 cm wall across +Z whose near face is at z = `near`.
pub fn thin_wall(near: f32) -> Arc<Level> {
    let wall = boxed(
        "wall",
        Vec3::new(0.0, 0.0, near + 0.025),
        Vec3::new(2.0, 2.0, 0.025),
    );
    Arc::new(Level::new(vec![wall]).unwrap())
}

/// A character walking along +Z at 2 m/s, turning 0.8 rad from 1.5 s to 2.5 s and
/// stopping at 3 s.
pub fn drag_walk(t: f32) -> Transform {
    let yaw = if t > 1.5 {
        0.8 * (t - 1.5).min(1.0)
    } else {
        0.0
    };
    Transform::from_translation_rotation(
        Vec3::new(0.0, 0.0, 2.0 * t.min(3.0)),
        Quat::from_rotation_y(yaw),
    )
}

/// A character running along +Z at 10 m/s for 0.1 s, then standing.
pub fn flung(t: f32) -> Transform {
    Transform::from_translation(Vec3::new(0.0, 0.0, 10.0 * t.min(0.1)))
}

/// The 6-bone hair chain of the KawaiiPhysics reference tests.
pub mod hair {
    use super::*;

    /// Simulated bones below the root.
    pub const BONES: usize = 6;

    /// Head at 1.6 m; hair from the back of the head, down and back (component space).
    pub fn pose() -> Vec<DVec3> {
        let mut p = vec![DVec3::new(0.0, 1.62, -0.1)];
        for i in 0..BONES {
            let last = p[i];
            p.push(last + DVec3::new(0.004 * i as f64, -0.06, -0.015));
        }
        p
    }

    /// `hair_0..=hair_6` on that pose.
    pub fn skeleton() -> Skeleton {
        let p = pose();
        let mut names = vec!["hair_0".to_string()];
        let mut parents = vec![None];
        let mut rest = vec![Transform::from_translation(p[0].as_vec3())];
        for i in 1..=BONES {
            names.push(format!("hair_{i}"));
            parents.push(Some(i - 1));
            rest.push(Transform::from_translation((p[i] - p[i - 1]).as_vec3()));
        }
        Skeleton::new(names, parents, rest).unwrap()
    }

    /// The component (character) transform at `t`, f64: still, swaying ±0.3 m at 1 Hz,
    /// stepped 0.2 m at 0.5 s, or turning ±0.5 rad at 0.7 Hz.
    pub fn component(motion: &str, t: f64) -> (DVec3, DQuat) {
        match motion {
            "still" => (DVec3::ZERO, DQuat::IDENTITY),
            "sway" => (
                DVec3::new(0.3 * (std::f64::consts::TAU * t).sin(), 0.0, 0.0),
                DQuat::IDENTITY,
            ),
            "step" => (
                DVec3::new(if t >= 0.5 { 0.2 } else { 0.0 }, 0.0, 0.0),
                DQuat::IDENTITY,
            ),
            "turn" => (
                DVec3::ZERO,
                DQuat::from_rotation_y(0.5 * (std::f64::consts::TAU * 0.7 * t).sin()),
            ),
            _ => unreachable!(),
        }
    }
}

/// A transform's bits: translation, rotation, scale.
pub fn transform_bits(t: &Transform) -> [u32; 10] {
    let mut b = [0u32; 10];
    let all = t.translation.to_array().into_iter();
    let all = all.chain(t.rotation.to_array()).chain(t.scale.to_array());
    for (k, v) in all.enumerate() {
        b[k] = v.to_bits();
    }
    b
}

/// Asserts that `pose` is `reference` bit for bit, joint by joint (local and model
/// transforms); `what` says which frame and way in the message.
pub fn assert_pose_bits(sk: &Skeleton, what: &str, pose: &tassel::Pose, reference: &tassel::Pose) {
    for j in 0..sk.len() {
        assert_eq!(
            transform_bits(&pose.locals[j]),
            transform_bits(&reference.locals[j]),
            "{what}, joint '{}': {:?} vs the reference {:?}",
            sk.name(j),
            pose.locals[j],
            reference.locals[j]
        );
        assert_eq!(
            transform_bits(&pose.models[j]),
            transform_bits(&reference.models[j]),
            "{what}, joint '{}' (model)",
            sk.name(j)
        );
    }
}

/// How many chain features [`chain_feature`] knows.
pub const CHAIN_FEATURES: usize = 9;

/// Gives `ch` chain feature `feature` (0..[`CHAIN_FEATURES`]): wind with gusts, a cone
/// limit, the planar constraints, classic mode with each gravity rule, fixed steps at
/// 90 Hz (steps between frames, a powf pull) with a step cap, warm-up steps with alpha
/// and gravity in the character's space, 30 Hz with wind, and a dummy tip on a chain
/// that never resets on a jump (90 Hz: steps between frames). `seed` seeds the wind.
pub fn chain_feature(ch: &mut tassel::dynamics::chain::ChainSettings, feature: usize, seed: u64) {
    use tassel::dynamics::chain::{ClassicGravity, PlanarAxis, TimeMode, Wind};
    match feature {
        0 => {
            ch.wind = Wind {
                direction: Vec3::new(1.0, 0.0, 0.5),
                speed: 0.01,
                gust: 0.5,
                seed,
                ..Default::default()
            }
        }
        1 => ch.limit_angle = 0.2,
        2 => ch.planar_constraint = PlanarAxis::X,
        3 => {
            ch.mode = TimeMode::Classic;
            ch.classic_gravity = ClassicGravity::DtSquared;
        }
        4 => {
            ch.mode = TimeMode::Classic;
            ch.classic_gravity = ClassicGravity::HalfDtSquared;
            ch.planar_constraint = PlanarAxis::Z;
        }
        5 => {
            ch.target_framerate = 90.0;
            ch.max_steps_per_frame = 3;
        }
        6 => {
            ch.warmup_steps = 5;
            ch.alpha = 0.7;
            ch.gravity_in_world = false;
        }
        7 => {
            ch.target_framerate = 30.0;
            ch.wind = Wind {
                direction: Vec3::Z,
                speed: 0.02,
                gust: 1.0,
                seed: seed + 3,
                ..Default::default()
            };
        }
        _ => {
            // Never resets on a jump, beside chains that do.
            ch.dummy_bone_length = 0.04;
            ch.target_framerate = 90.0;
            ch.teleport_distance = 0.0;
            ch.teleport_rotation = 0.0;
        }
    }
}

/// Every collider shape in a bench rig (`builtin::bench_character` with at least four
/// colliders: spheres and capsules): collider 1 becomes a box, collider 2 a tilted tapered
/// capsule, collider 3 a turned capsule, and a tilted floor plane and a keep-inside sphere
/// join them.
pub fn every_collider_shape(rig: &mut tassel::dynamics::RigSettings) {
    use tassel::collide::Shape;
    use tassel::dynamics::ColliderSettings;
    rig.colliders[1].shape = Shape::Box {
        half_extents: Vec3::new(0.05, 0.08, 0.03),
    };
    rig.colliders[2].shape = Shape::TaperedCapsule {
        radius0: 0.08,
        radius1: 0.02,
        length: 0.2,
    };
    rig.colliders[2].rotation = Quat::from_rotation_x(0.5);
    rig.colliders[3].rotation = Quat::from_rotation_z(0.6);
    rig.colliders.push(ColliderSettings {
        mirror: None,
        mirror_bone: String::new(),
        name: "floor".into(),
        bone: "root".into(),
        offset: Vec3::new(0.0, -0.32, 0.0),
        rotation: Quat::from_rotation_x(0.1),
        shape: Shape::Plane,
    });
    rig.colliders.push(ColliderSettings {
        mirror: None,
        mirror_bone: String::new(),
        name: "limit".into(),
        bone: "root".into(),
        offset: Vec3::ZERO,
        rotation: Quat::IDENTITY,
        shape: Shape::Sphere {
            radius: 0.38,
            inside: true,
        },
    });
}

/// A character's world transform and animated pose at time `t`: a sway, a bob and a
/// turn, the root and joint `swing` swinging, moved `jump` metres along x.
pub fn sway(sk: &Skeleton, swing: usize, t: f32, jump: f32, locals: &mut [Transform]) -> Transform {
    locals.copy_from_slice(sk.rest());
    locals[0].rotation = sk.rest()[0].rotation * Quat::from_rotation_z(0.3 * (2.0 * t).sin());
    locals[swing].rotation =
        sk.rest()[swing].rotation * Quat::from_rotation_x(0.5 * (3.0 * t + 1.0).sin());
    Transform::from_translation_rotation(
        Vec3::new((3.0 * t).sin() * 0.5 + jump, 0.1 * (5.0 * t).sin(), t),
        Quat::from_rotation_y(0.4 * (2.0 * t).sin()),
    )
}

/// Frame `f`'s time step: 60 Hz with a paused frame (200), a hitch (300) and a slow
/// stretch (320..=340: steps between frames).
pub fn dt_with_hitches(f: usize) -> f32 {
    match f {
        200 => 0.0,
        300 => 0.25,
        320..=340 => 1.0 / 45.0,
        _ => 1.0 / 60.0,
    }
}

/// What the KawaiiPhysics reference tests share: the chain parameters of their ports, the
/// hair chain with them, and the fixed-mode frame-rate run.
pub mod kawaii {
    use super::*;
    use tassel::dynamics::chain::{ChainSettings, ClassicGravity, TimeMode};
    use tassel::dynamics::RigSettings;
    use tassel::CharacterSim;

    pub const TARGET_FPS: f64 = 60.0;
    pub const DAMPING: f64 = 0.1;
    pub const STIFFNESS: f64 = 0.05;
    pub const WORLD_DAMPING_LOCATION: f64 = 0.8;
    pub const WORLD_DAMPING_ROTATION: f64 = 0.7;
    pub const GRAVITY: [f64; 3] = [0.0, -9.81, 0.0];

    /// The hair chain (`hair_0` down) with the ports' parameters, no teleport reset, no
    /// frame clamp.
    pub fn hair_chain(mode: TimeMode, classic_gravity: ClassicGravity) -> ChainSettings {
        ChainSettings {
            name: "hair".into(),
            root: "hair_0".into(),
            mode,
            classic_gravity,
            damping: DAMPING as f32,
            stiffness: STIFFNESS as f32,
            world_damping_location: WORLD_DAMPING_LOCATION as f32,
            world_damping_rotation: WORLD_DAMPING_ROTATION as f32,
            gravity: Vec3::from(GRAVITY.map(|g| g as f32)),
            target_framerate: TARGET_FPS as f32,
            max_delta_time: 1.0,
            teleport_distance: 0.0,
            teleport_rotation: 0.0,
            ..Default::default()
        }
    }

    /// World positions of every joint every 1/6 s over 6 s at `hz`, the character swaying
    /// ±0.3 m at 1 Hz and turning ±0.5 rad at 0.7 Hz, the pose from `locals_at(sk, t)`.
    pub fn fixed_run(
        sk: &Skeleton,
        rig: &RigSettings,
        hz: u32,
        locals_at: impl Fn(&Skeleton, f64) -> Vec<Transform>,
    ) -> Vec<Vec<Vec3>> {
        let mut sim = CharacterSim::new(sk.clone(), rig).unwrap();
        let mut out = Vec::new();
        for f in 0..=6 * hz {
            let t = f as f64 / hz as f64;
            let comp = Transform::from_translation_rotation(
                Vec3::new((0.3 * (std::f64::consts::TAU * t).sin()) as f32, 0.0, 0.0),
                Quat::from_rotation_y((0.5 * (std::f64::consts::TAU * 0.7 * t).sin()) as f32),
            );
            let dt = if f == 0 { 0.0 } else { 1.0 / hz as f32 };
            sim.frame(&locals_at(sk, t), comp, dt).unwrap();
            if (f * 6) % hz == 0 {
                out.push(
                    sim.pose()
                        .models
                        .iter()
                        .map(|m| comp.transform_point(m.translation))
                        .collect(),
                );
            }
        }
        out
    }

    /// The RMS distance between two runs' positions.
    pub fn rms(a: &[Vec<Vec3>], b: &[Vec<Vec3>]) -> f64 {
        let (mut d2, mut n) = (0.0f64, 0usize);
        for (x, y) in a.iter().zip(b) {
            for (p, q) in x.iter().zip(y) {
                d2 += (*p - *q).length_squared() as f64;
                n += 1;
            }
        }
        (d2 / n as f64).sqrt()
    }
}

/// Runs a crowd frame's parts (`frame_parts`) as a game engine's task pool might: each on
/// a scoped thread of its own (`threads`), or all on this thread, the last first.
pub fn run_parts<J: Send>(
    jobs: &mut dyn Iterator<Item = J>,
    threads: bool,
    run: impl Fn(J) + Sync,
) {
    if threads {
        let run = &run;
        std::thread::scope(|s| {
            for job in jobs {
                s.spawn(move || run(job));
            }
        });
    } else {
        let mut all: Vec<J> = jobs.collect();
        while let Some(job) = all.pop() {
            run(job);
        }
    }
}
