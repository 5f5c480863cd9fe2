//! The embedded default character: a small humanoid with a ponytail, two side locks, a
//! tail, a skirt ring, two chest bones and body colliders, procedural clips (idle, walk,
//! run, jump start / loop / end), and the scripted run of `tassel demo`. Built in code; no file needed.

use crate::anim::{Channel, Clip, Interpolation, JointTrack};
use crate::collide::Shape;
use crate::dynamics::chain::ChainSettings;
use crate::dynamics::cloth::ClothSettings;
use crate::dynamics::particles::ParticleSettings;
use crate::dynamics::rope::RopeSettings;
use crate::dynamics::spring::SpringSettings;
use crate::dynamics::{ColliderSettings, Curve, RigSettings};
use crate::math::Transform;
use crate::skeleton::{Skeleton, SkeletonBuilder};
use glam::{EulerRot, Quat, Vec3};
use std::f32::consts::{PI, TAU};

/// The embedded character.
#[derive(Debug, Clone)]
pub struct Character {
    /// Skeleton (metres, Y up, facing +Z).
    pub skeleton: Skeleton,
    /// Chains and colliders.
    pub rig: RigSettings,
    /// Clips, in order: idle, walk, run, jump_start, jump_loop, jump_end.
    pub clips: Vec<Clip>,
}

#[path = "builtin_level.rs"]
pub mod level;

#[path = "builtin_avatar.rs"]
pub mod avatar;

/// Index of each clip in [`Character::clips`].
pub mod clip {
    /// Breathing in place, 2 s loop.
    pub const IDLE: usize = 0;
    /// Walk cycle, 1 s loop.
    pub const WALK: usize = 1;
    /// Run cycle, 0.7 s loop.
    pub const RUN: usize = 2;
    /// Crouch and take-off, 0.45 s.
    pub const JUMP_START: usize = 3;
    /// Tucked in the air, 0.45 s loop.
    pub const JUMP_LOOP: usize = 4;
    /// Landing, 0.3 s.
    pub const JUMP_END: usize = 5;
}

fn skeleton() -> Skeleton {
    let mut b = SkeletonBuilder::new();
    let t = |x: f32, y: f32, z: f32| Transform::from_translation(Vec3::new(x, y, z));
    let root = b.add("root", None, Transform::IDENTITY);
    let hips = b.add("hips", Some(root), t(0.0, 0.95, 0.0));
    let spine = b.add("spine", Some(hips), t(0.0, 0.1, 0.0));
    let chest = b.add("chest", Some(spine), t(0.0, 0.15, 0.0));
    let neck = b.add("neck", Some(chest), t(0.0, 0.17, 0.0));
    let head = b.add("head", Some(neck), t(0.0, 0.08, 0.0));
    b.add("head_end", Some(head), t(0.0, 0.2, 0.0));
    let mut p = b.add("ponytail_0", Some(head), t(0.0, 0.15, -0.11));
    for i in 1..6 {
        p = b.add(format!("ponytail_{i}"), Some(p), t(0.0, -0.065, -0.02));
    }
    let mut hand_l = 0;
    for (side, x) in [("l", 1.0f32), ("r", -1.0)] {
        let mut p = b.add(
            format!("lock_{side}_0"),
            Some(head),
            t(0.085 * x, 0.06, 0.05),
        );
        for i in 1..3 {
            p = b.add(
                format!("lock_{side}_{i}"),
                Some(p),
                t(0.005 * x, -0.06, 0.0),
            );
        }
        b.add(
            format!("chest_{side}"),
            Some(chest),
            t(0.07 * x, 0.03, 0.07),
        );
        let sh = b.add(
            format!("shoulder_{side}"),
            Some(chest),
            t(0.08 * x, 0.13, 0.0),
        );
        let ua = b.add(format!("upper_arm_{side}"), Some(sh), t(0.1 * x, 0.0, 0.0));
        let la = b.add(format!("lower_arm_{side}"), Some(ua), t(0.0, -0.28, 0.0));
        let hand = b.add(format!("hand_{side}"), Some(la), t(0.0, -0.25, 0.0));
        if side == "l" {
            hand_l = hand;
        }
        let th = b.add(format!("thigh_{side}"), Some(hips), t(0.09 * x, -0.05, 0.0));
        let sh = b.add(format!("shin_{side}"), Some(th), t(0.0, -0.42, 0.0));
        let ft = b.add(format!("foot_{side}"), Some(sh), t(0.0, -0.42, 0.0));
        b.add(format!("toe_{side}"), Some(ft), t(0.0, -0.05, 0.12));
    }
    // A tassel on a cord held in the left hand: a rope of particles on five bones.
    let mut p = b.add("charm_0", Some(hand_l), t(0.0, -0.06, 0.0));
    for i in 1..5 {
        p = b.add(format!("charm_{i}"), Some(p), t(0.0, -0.05, 0.0));
    }
    let mut p = b.add("tail_0", Some(hips), t(0.0, 0.0, -0.12));
    for i in 1..8 {
        p = b.add(format!("tail_{i}"), Some(p), t(0.0, -0.012, -0.075));
    }
    for k in 0..8 {
        let a = k as f32 * TAU / 8.0;
        let (s, c) = a.sin_cos();
        let mut p = b.add(
            format!("skirt_{k}_0"),
            Some(hips),
            t(0.17 * s, -0.02, 0.17 * c),
        );
        for i in 1..4 {
            p = b.add(
                format!("skirt_{k}_{i}"),
                Some(p),
                t(0.035 * s, -0.1, 0.035 * c),
            );
        }
    }
    b.build().expect("the built-in skeleton is valid").0
}

fn rig() -> RigSettings {
    let col = |name: &str, bone: &str, offset: Vec3, shape: Shape| ColliderSettings {
        mirror: None,
        mirror_bone: String::new(),
        name: name.into(),
        bone: bone.into(),
        offset,
        rotation: Quat::IDENTITY,
        shape,
    };
    let mut colliders = vec![
        col(
            "head",
            "head",
            Vec3::new(0.0, 0.09, 0.0),
            Shape::Sphere {
                radius: 0.11,
                inside: false,
            },
        ),
        col(
            "torso",
            "spine",
            Vec3::new(0.0, 0.12, 0.0),
            Shape::Capsule {
                radius: 0.12,
                length: 0.22,
            },
        ),
    ];
    for side in ["l", "r"] {
        colliders.push(col(
            &format!("thigh_{side}"),
            &format!("thigh_{side}"),
            Vec3::new(0.0, -0.21, 0.0),
            Shape::Capsule {
                radius: 0.075,
                length: 0.3,
            },
        ));
        colliders.push(col(
            &format!("shin_{side}"),
            &format!("shin_{side}"),
            Vec3::new(0.0, -0.21, 0.0),
            Shape::Capsule {
                radius: 0.055,
                length: 0.32,
            },
        ));
    }
    let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let base = ChainSettings::default();
    let mut chains = vec![
        ChainSettings {
            name: "ponytail".into(),
            root: "ponytail_0".into(),
            damping: 0.08,
            stiffness: 0.04,
            radius: 0.025,
            colliders: names(&["head", "torso"]),
            curves: crate::dynamics::chain::ChainCurves {
                stiffness: Curve::new(vec![[0.0, 1.5], [1.0, 0.5]]),
                ..Default::default()
            },
            ..base.clone()
        },
        ChainSettings {
            name: "tail".into(),
            root: "tail_0".into(),
            damping: 0.12,
            stiffness: 0.08,
            radius: 0.03,
            limit_angle: 70.0,
            colliders: names(&["thigh_l", "thigh_r", "shin_l", "shin_r"]),
            ..base.clone()
        },
    ];
    for side in ["l", "r"] {
        chains.push(ChainSettings {
            name: format!("lock_{side}"),
            root: format!("lock_{side}_0"),
            damping: 0.15,
            stiffness: 0.1,
            radius: 0.015,
            colliders: names(&["head"]),
            ..base.clone()
        });
    }
    let mut springs = Vec::new();
    for side in ["l", "r"] {
        springs.push(SpringSettings {
            name: format!("chest_{side}"),
            bone: format!("chest_{side}"),
            stiffness: 120.0,
            damping: 6.0,
            limit_displacement: 0.03,
            ..Default::default()
        });
    }
    // The skirt is one bone cloth over its eight chains, closed into a ring.
    let cloths = vec![ClothSettings {
        name: "skirt".into(),
        chains: (0..8)
            .map(|k| [format!("skirt_{k}_0"), format!("skirt_{k}_3")])
            .collect(),
        loop_chains: true,
        virtual_bone_length: 0.08,
        resistance: 0.08,
        hardness: 0.01,
        radius: 0.015,
        friction: 0.3,
        limit_angle: 60.0,
        colliders: names(&["thigh_l", "thigh_r", "shin_l", "shin_r"]),
        // The skirt brushes the wall the demo slides along.
        world_collision: true,
        ..Default::default()
    }];
    // The tassel in the left hand: a particle rope, kept out of the left thigh, above
    // the ground and out of the world (it swings into the demo's wall without it).
    let ropes = vec![RopeSettings {
        name: "charm".into(),
        root: "charm_0".into(),
        end: "charm_4".into(),
        mass: 0.05,
        colliders: names(&["thigh_l"]),
        ground: Some(0.0),
        world_collision: true,
        world: ParticleSettings {
            damping: 0.03,
            iterations: 8,
            radius: 0.01,
            friction: 0.5,
            ..Default::default()
        },
        ..Default::default()
    }];
    RigSettings {
        chains,
        colliders,
        springs,
        cloths,
        ropes,
        ..Default::default()
    }
}

/// Samples a procedural clip at 30 keys per second into LINEAR channels.
fn bake(
    sk: &Skeleton,
    name: &str,
    duration: f32,
    pose_at: impl Fn(f32, &mut [Transform], &dyn Fn(&str) -> usize),
) -> Clip {
    let find = |n: &str| sk.find(n).expect("built-in bone");
    let keys = (duration * 30.0).round() as usize;
    let times: Vec<f32> = (0..=keys)
        .map(|k| k as f32 * duration / keys as f32)
        .collect();
    let mut frames = Vec::new();
    for &t in &times {
        let mut locals = sk.rest().to_vec();
        pose_at(t, &mut locals, &find);
        frames.push(locals);
    }
    let mut tracks = Vec::new();
    for j in 0..sk.len() {
        let rot: Vec<Quat> = frames.iter().map(|f| f[j].rotation).collect();
        let tr: Vec<Vec3> = frames.iter().map(|f| f[j].translation).collect();
        let moves_r = rot
            .iter()
            .any(|q| q.dot(sk.rest()[j].rotation).abs() < 1.0 - 1e-7);
        let moves_t = tr
            .iter()
            .any(|v| !v.abs_diff_eq(sk.rest()[j].translation, 1e-7));
        if !moves_r && !moves_t {
            continue;
        }
        let ch = |values| Channel {
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values,
        };
        tracks.push(JointTrack {
            joint: j,
            translation: moves_t.then(|| ch(tr)),
            rotation: moves_r.then(|| Channel {
                interpolation: Interpolation::Linear,
                times: times.clone(),
                values: rot,
            }),
            scale: None,
        });
    }
    Clip {
        name: name.into(),
        duration,
        tracks,
    }
}

fn rot(l: &mut [Transform], j: usize, x: f32, y: f32, z: f32) {
    l[j].rotation = (l[j].rotation * Quat::from_euler(EulerRot::XYZ, x, y, z)).normalize();
}

/// A gait's shape: leg swing (rad), knee bend (rad), forward lean (rad), vertical bob
/// (m) and arm swing (rad) over one cycle of `period` seconds.
struct Gait {
    period: f32,
    stride: f32,
    knee: f32,
    lean: f32,
    bob: f32,
    arm: f32,
}

impl Gait {
    fn apply(&self, t: f32, l: &mut [Transform], f: &dyn Fn(&str) -> usize) {
        let Gait {
            period,
            stride,
            knee,
            lean,
            bob,
            arm,
        } = *self;
        let ph = TAU * t / period;
        let s = ph.sin();
        rot(l, f("thigh_l"), -stride * s, 0.0, 0.0);
        rot(l, f("thigh_r"), stride * s, 0.0, 0.0);
        rot(
            l,
            f("shin_l"),
            knee * (0.5 + 0.5 * (ph + 0.6).cos()).powi(2),
            0.0,
            0.0,
        );
        rot(
            l,
            f("shin_r"),
            knee * (0.5 - 0.5 * (ph + 0.6).cos()).powi(2),
            0.0,
            0.0,
        );
        rot(l, f("upper_arm_l"), arm * s, 0.0, 0.0);
        rot(l, f("upper_arm_r"), -arm * s, 0.0, 0.0);
        rot(l, f("lower_arm_l"), -arm * 0.8, 0.0, 0.0);
        rot(l, f("lower_arm_r"), -arm * 0.8, 0.0, 0.0);
        rot(l, f("spine"), lean, 0.12 * stride * s, 0.0);
        rot(l, f("hips"), 0.0, -0.15 * stride * s, 0.0);
        l[f("hips")].translation.y += bob * (2.0 * ph).cos() - bob;
    }
}

fn clips(sk: &Skeleton) -> Vec<Clip> {
    let idle = bake(sk, "idle", 2.0, |t, l, f| {
        let b = (TAU * t / 2.0).sin();
        rot(l, f("spine"), 0.02 * b, 0.0, 0.0);
        rot(l, f("chest"), 0.015 * b, 0.0, 0.0);
        rot(l, f("head"), -0.03 * b, 0.05 * (TAU * t / 2.0).cos(), 0.0);
        rot(l, f("upper_arm_l"), 0.0, 0.0, 0.08 + 0.01 * b);
        rot(l, f("upper_arm_r"), 0.0, 0.0, -0.08 - 0.01 * b);
    });
    let walk = bake(sk, "walk", 1.0, |t, l, f| {
        Gait {
            period: 1.0,
            stride: 0.45,
            knee: 0.7,
            lean: 0.05,
            bob: 0.02,
            arm: 0.35,
        }
        .apply(t, l, f)
    });
    let run = bake(sk, "run", 0.7, |t, l, f| {
        Gait {
            period: 0.7,
            stride: 0.8,
            knee: 1.4,
            lean: 0.25,
            bob: 0.05,
            arm: 0.7,
        }
        .apply(t, l, f)
    });
    // One jump, cut in three for the state machine: crouch and take-off (0.45 s), tuck in
    // the air (a 0.45 s loop), landing (0.3 s).
    let jump_pose = |t: f32, l: &mut [Transform], f: &dyn Fn(&str) -> usize| {
        let crouch = if t < 0.3 {
            (t / 0.3 * PI / 2.0).sin()
        } else if t < 0.45 {
            1.0 - (t - 0.3) / 0.15
        } else if t < 0.9 {
            0.0
        } else {
            ((t - 0.9) / 0.3 * PI).sin()
        };
        let tuck = if (0.45..0.9).contains(&t) {
            ((t - 0.45) / 0.45 * PI).sin()
        } else {
            0.0
        };
        let bend = crouch + 0.8 * tuck;
        for side in ["l", "r"] {
            rot(l, f(&format!("thigh_{side}")), -0.9 * bend, 0.0, 0.0);
            rot(l, f(&format!("shin_{side}")), 1.6 * bend, 0.0, 0.0);
            rot(l, f(&format!("foot_{side}")), -0.7 * crouch, 0.0, 0.0);
            let up = if side == "l" { 1.0 } else { -1.0 };
            rot(
                l,
                f(&format!("upper_arm_{side}")),
                -1.2 * tuck,
                0.0,
                up * 0.3 * (1.0 - crouch),
            );
        }
        rot(l, f("spine"), 0.4 * crouch, 0.0, 0.0);
        l[f("hips")].translation.y -= 0.25 * crouch;
    };
    let jump_start = bake(sk, "jump_start", 0.45, |t, l, f| jump_pose(t, l, f));
    let jump_loop = bake(sk, "jump_loop", 0.45, |t, l, f| jump_pose(0.45 + t, l, f));
    let jump_end = bake(sk, "jump_end", 0.3, |t, l, f| jump_pose(0.9 + t, l, f));
    vec![idle, walk, run, jump_start, jump_loop, jump_end]
}

/// A synthetic benchmark character: a root with `chains` chains of `joints` joints each
/// (0.05 m bones fanning out and down) and `colliders` alternating spheres and capsules
/// among them.
pub fn bench_character(chains: usize, joints: usize, colliders: usize) -> (Skeleton, RigSettings) {
    let mut b = SkeletonBuilder::new();
    let root = b.add("root", None, Transform::IDENTITY);
    let mut rig = RigSettings::default();
    for c in 0..chains {
        let a = c as f32 * TAU / chains as f32;
        let dir = Vec3::new(0.3 * a.sin(), -1.0, 0.3 * a.cos()).normalize();
        let mut p = b.add(
            format!("c{c}_0"),
            Some(root),
            Transform::from_translation(Vec3::new(0.2 * a.sin(), 0.0, 0.2 * a.cos())),
        );
        for j in 1..joints {
            p = b.add(
                format!("c{c}_{j}"),
                Some(p),
                Transform::from_translation(dir * 0.05),
            );
        }
        rig.chains.push(ChainSettings {
            name: format!("c{c}"),
            root: format!("c{c}_0"),
            ..Default::default()
        });
    }
    for k in 0..colliders {
        let a = (k as f32 + 0.5) * TAU / colliders.max(1) as f32;
        let offset = Vec3::new(0.3 * a.sin(), -0.2, 0.3 * a.cos());
        let shape = if k % 2 == 0 {
            Shape::Sphere {
                radius: 0.06,
                inside: false,
            }
        } else {
            Shape::Capsule {
                radius: 0.04,
                length: 0.2,
            }
        };
        rig.colliders.push(ColliderSettings {
            mirror: None,
            mirror_bone: String::new(),
            name: format!("k{k}"),
            bone: "root".into(),
            offset,
            rotation: Quat::IDENTITY,
            shape,
        });
    }
    (b.build().expect("valid bench skeleton").0, rig)
}

/// The bench character of [`bench_character`] as VRM spring bones: every chain bone below
/// the chain's first swings toward its child (the last toward a virtual tail 7 cm down),
/// tail radius 2 cm, stiffness 1, gravity 1, colliding with every collider (one group).
pub fn bench_vrm(
    chains: usize,
    joints: usize,
    colliders: usize,
) -> (Skeleton, crate::dynamics::vrm::VrmSpringBones) {
    use crate::dynamics::vrm::{VrmColliderGroup, VrmJoint, VrmSpring, VrmSpringBones, VrmTail};
    let (sk, rig) = bench_character(chains, joints, colliders);
    let mut b = VrmSpringBones {
        colliders: avatar::vrm_colliders(&sk, &rig.colliders)
            .into_iter()
            .map(|(_, c)| c)
            .collect(),
        ..Default::default()
    };
    b.collider_groups.push(VrmColliderGroup {
        name: "all".into(),
        colliders: (0..b.colliders.len()).collect(),
    });
    for ch in &rig.chains {
        let root = sk.find(&ch.root).expect("bench chain root");
        let mut joints = Vec::new();
        let mut j = sk.children(root).next();
        while let Some(k) = j {
            let child = sk.children(k).next();
            joints.push(VrmJoint {
                joint: k,
                tail: match child {
                    Some(c) => VrmTail::Joint(c),
                    None => VrmTail::Local(Vec3::new(0.0, -0.07, 0.0)),
                },
                hit_radius: 0.02,
                stiffness: 1.0,
                gravity_power: 1.0,
                ..Default::default()
            });
            j = child;
        }
        b.springs.push(VrmSpring {
            name: ch.name.clone(),
            joints,
            collider_groups: vec![0],
            center: None,
        });
    }
    (sk, b)
}

/// Builds the embedded character.
pub fn character() -> Character {
    let skeleton = skeleton();
    let clips = clips(&skeleton);
    Character {
        rig: rig(),
        clips,
        skeleton,
    }
}

/// One moment of the demo script: where the character is and the signals it gives the
/// state machine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DemoMoment {
    /// The character's world transform.
    pub component: Transform,
    /// Ground speed, m/s (the `speed` parameter).
    pub speed: f32,
    /// The jump button is held (the `jumping` parameter).
    pub jumping: bool,
    /// A label for the phase: idle, walk, run, stop, turn, jump.
    pub phase: &'static str,
}

/// The scripted run of `tassel demo`: idle, walk, run, sudden stop, turn in place, jump.
/// The script moves the character and sets the locomotion state machine's parameters;
/// the state machine chooses and blends the clips.
#[derive(Debug, Clone, Copy, Default)]
pub struct DemoScript;

const SEGMENTS: [(f32, f32, f32, &str); 7] = [
    // start, forward speed m/s, yaw rate rad/s, label
    (0.0, 0.0, 0.0, "idle"),
    (1.5, 1.4, 0.0, "walk"),
    (3.5, 4.0, 0.0, "run"),
    (6.0, 0.0, 0.0, "stop"),
    (7.0, 0.0, PI, "turn"),
    (8.0, 0.0, 0.0, "jump"),
    (9.2, 0.0, 0.0, "idle"),
];
/// The jump: button held from 8.0 s; take-off when the 0.45 s jump_start clip ends; 0.45 s
/// of flight, 0.4 m high; the button is released on landing.
const JUMP_AT: f32 = 8.0;
const TAKE_OFF: f32 = 0.45 + 1.0 / 60.0;
const FLIGHT: f32 = 0.45;

impl DemoScript {
    /// Length of the script, seconds.
    pub const DURATION: f32 = 10.0;

    /// The state of the script at `t` seconds. Motion is integrated in closed form, so
    /// any frame rate sees the same path.
    pub fn at(&self, t: f32) -> DemoMoment {
        let t = t.clamp(0.0, Self::DURATION);
        let (mut pos, mut yaw) = (Vec3::ZERO, 0.0f32);
        let mut seg = 0;
        for (i, s) in SEGMENTS.iter().enumerate() {
            let end = SEGMENTS.get(i + 1).map(|n| n.0).unwrap_or(Self::DURATION);
            if t < s.0 {
                break;
            }
            seg = i;
            let span = t.min(end) - s.0;
            // Constant yaw rate and speed within a segment: integrate the heading exactly.
            if s.2 != 0.0 {
                let y1 = yaw + s.2 * span;
                pos += Vec3::new(y1.cos() - yaw.cos(), 0.0, yaw.sin() - y1.sin()) * (-s.1 / s.2);
                yaw = y1;
            } else {
                pos += Quat::from_rotation_y(yaw) * Vec3::Z * (s.1 * span);
            }
        }
        let s = SEGMENTS[seg];
        let since_jump = t - JUMP_AT;
        let air = ((since_jump - TAKE_OFF) / FLIGHT).clamp(0.0, 1.0);
        pos.y = 4.0 * 0.4 * air * (1.0 - air);
        DemoMoment {
            component: Transform::from_translation_rotation(pos, Quat::from_rotation_y(yaw)),
            speed: s.1,
            jumping: (0.0..TAKE_OFF + FLIGHT).contains(&since_jump),
            phase: s.3,
        }
    }

    /// The locomotion state machine for the built-in character's clips.
    pub fn animator(&self, c: &Character) -> crate::anim::Animator {
        let names: Vec<&str> = c.clips.iter().map(|c| c.name.as_str()).collect();
        let durations: Vec<f32> = c.clips.iter().map(|c| c.duration).collect();
        let machine = crate::anim::StateMachine::from_toml_str(
            crate::anim::StateMachine::LOCOMOTION,
            &names,
            &durations,
        )
        .expect("the locomotion graph fits the built-in clips");
        crate::anim::Animator::new(machine, &c.clips)
    }

    /// Sets `animator`'s parameters from moment `m`, advances it by `dt` and writes the
    /// blended local pose into `locals`. Returns the plan (state, layers, events).
    pub fn pose<'a>(
        &self,
        c: &Character,
        animator: &'a mut crate::anim::Animator,
        m: &DemoMoment,
        dt: f32,
        locals: &mut [Transform],
    ) -> crate::Result<&'a crate::anim::BlendPlan> {
        let (speed, jumping) = (
            animator.machine().param("speed"),
            animator.machine().param("jumping"),
        );
        if let (Some(s), Some(j)) = (speed, jumping) {
            animator.state.set(s, m.speed);
            animator.state.set(j, if m.jumping { 1.0 } else { 0.0 });
        }
        animator.update(&c.clips, c.skeleton.rest(), dt, locals)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::chain::ChainRig;

    #[test]
    fn has_the_promised_parts() {
        let c = character();
        let rig = ChainRig::new(&c.skeleton, &c.rig).unwrap();
        let count = |prefix: &str| {
            c.skeleton
                .names()
                .iter()
                .filter(|n| n.starts_with(prefix))
                .count()
        };
        assert_eq!(count("ponytail_"), 6);
        assert_eq!(count("tail_"), 8);
        assert_eq!(count("skirt_"), 32);
        assert_eq!(count("lock_"), 6);
        assert_eq!(count("chest_"), 2);
        assert_eq!(c.clips.len(), 6);
        assert_eq!(rig.chain_count(), 4);
        assert_eq!(c.rig.springs.len(), 2);
        // The skirt cloth: 8 chains of 4 bones and a virtual tip, closed into a ring.
        let cloth = crate::dynamics::cloth::ClothRig::new(&c.skeleton, &c.rig).unwrap();
        assert_eq!(cloth.point_count(), 40);
        assert_eq!(cloth.simulated_joints().count(), 24);
        assert_eq!(cloth.quads(0).len(), 32);
        // By hand: vertical 8·4, bending 8·3, horizontal 8·5 minus the 8 between fixed
        // roots, shear 8·4·2.
        assert_eq!(cloth.constraints(0).len(), 32 + 24 + 32 + 64);
        for clip in &c.clips {
            clip.validate(c.skeleton.len()).unwrap();
        }
    }

    #[test]
    fn script_turns_half_a_circle_and_stops() {
        let s = DemoScript;
        let before = s.at(6.5).component;
        let after = s.at(8.0).component;
        // The turn is in place: no translation, 180° of yaw.
        assert!(before.translation.abs_diff_eq(after.translation, 1e-4));
        let fwd = after.rotation * Vec3::Z;
        assert!(fwd.abs_diff_eq(-Vec3::Z, 1e-4), "{fwd}");
        // Walked 2 s at 1.4 m/s then ran 2.5 s at 4 m/s.
        assert!((before.translation.z - (2.8 + 10.0)).abs() < 1e-3);
    }
}
