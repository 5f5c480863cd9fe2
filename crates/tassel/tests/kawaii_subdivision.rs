//! Bone subdivision (issue 62 item 1, KawaiiPhysics 1.21's `BoneSubdivisionCount`,
//! `bBoneSubdivisionCollisionOnly`, `bBoneSubdivisionDensifyByRadius`).
//!
//! - `kawaii` mode against an independent f64 port of 1.21's substepped update with the
//!   points between bones, written from the plugin's `20260624-v1.21.0` source
//!   (`AnimNode_KawaiiPhysicsModifyBones.cpp`: `InsertInterBoneDummyBonesCore`,
//!   `CalcBoneLength`, `UpdateInterBoneDummyPose`; `AnimNode_KawaiiPhysicsSimulation.cpp`:
//!   `SimulateOnce`). What the port keeps from 1.21, as `kawaii` does: the bones' array
//!   order (a bone's points, then the bone); their poses lerped between the bone and its
//!   child each frame; under collision-only the points skip `Simulate` and are put on the
//!   segment after every bone has, so a bone after points pulls toward the last point's
//!   place *before* this step; a bone's whole length counted again after its points in
//!   its length from the root (the parameter curves' x); every point's length restored
//!   in array order.
//! - `fixed` and `classic` do what 1.21 means: points that only collide do not change a
//!   chain that touches nothing.
//! - Colliders meet the bone between its ends: a sphere swung through a chain of long
//!   bones passes between the bone ends without subdivision, and never does with the
//!   points spaced by the radius (`bone_subdivision_densify_by_radius`).

use glam::{DQuat, DVec3, Quat, Vec3};
use tassel::collide::Shape;
use tassel::dynamics::chain::{ChainSettings, ClassicGravity, TimeMode};
use tassel::dynamics::Curve;
use tassel::dynamics::{ColliderSettings, RigSettings};
use tassel::{CharacterSim, Transform};

mod common;
use common::hair::{component, pose, skeleton, BONES};
use common::kawaii::{
    DAMPING, GRAVITY, STIFFNESS, TARGET_FPS, WORLD_DAMPING_LOCATION, WORLD_DAMPING_ROTATION,
};

const MAX_SUBSTEPS: u32 = 4;

/// The curves of the subdivided hair: stiffness falling and damping rising along it (so
/// each point's length from the root matters).
const STIFFNESS_KEYS: [[f64; 2]; 2] = [[0.0, 1.0], [1.0, 0.3]];
const DAMPING_KEYS: [[f64; 2]; 2] = [[0.0, 0.5], [1.0, 1.5]];

fn curve_at(keys: &[[f64; 2]; 2], x: f64) -> f64 {
    let w = ((x - keys[0][0]) / (keys[1][0] - keys[0][0])).clamp(0.0, 1.0);
    keys[0][1] + (keys[1][1] - keys[0][1]) * w
}

/// The head's nod (the pose itself moving): the root turned about +X.
fn nod(motion: &str, t: f64) -> f64 {
    if motion == "nod" {
        0.5 * (std::f64::consts::TAU * 0.8 * t).sin()
    } else {
        0.0
    }
}

fn pose_at(angle: f64) -> Vec<DVec3> {
    let p = pose();
    let turn = DQuat::from_rotation_x(angle);
    p.iter().map(|&x| p[0] + turn * (x - p[0])).collect()
}

/// One of 1.21's `ModifyBones`: a real bone (`joint`) or a point between bones on the
/// segment from real bone `a` to real bone `b` at `alpha`.
#[derive(Clone, Copy)]
struct Layout {
    parent: Option<usize>,
    joint: Option<usize>,
    between: Option<(usize, usize, f64)>,
}

/// 1.21's array for the hair with `n` points between each bone and its child, and each
/// entry's length rate from the root (`CalcBoneLength`, its over-count included).
fn layout(n: usize) -> (Vec<Layout>, Vec<f64>) {
    let p = pose();
    let mut bones = vec![Layout {
        parent: None,
        joint: Some(0),
        between: None,
    }];
    let mut from_root = vec![0.0f64];
    let mut real = 0; // the array index of the last real bone
    for j in 1..=BONES {
        let length = (p[j] - p[j - 1]).length();
        let mut parent = real;
        let first = bones.len();
        for k in 0..n {
            let alpha = (k + 1) as f32 / (n + 1) as f32;
            bones.push(Layout {
                parent: Some(parent),
                joint: None,
                between: Some((real, first + n, alpha as f64)),
            });
            // A point's own segment.
            from_root.push(from_root[parent] + length / (n + 1) as f64);
            parent = bones.len() - 1;
        }
        bones.push(Layout {
            parent: Some(parent),
            joint: Some(j),
            between: None,
        });
        // The bone's whole length, after its points' (1.21's over-count).
        from_root.push(from_root[parent] + length);
        real = bones.len() - 1;
    }
    let total = from_root.iter().cloned().fold(0.0, f64::max);
    (bones, from_root.iter().map(|d| d / total).collect())
}

macro_rules! port {
    ($name:ident, $f:ty, $v:ty, $q:ty, $to_v:expr, $to_q:expr) => {
        struct $name {
            bones: Vec<Layout>,
            damping: Vec<$f>,
            stiffness: Vec<$f>,
            collision_only: bool,
            location: Vec<$v>,
            prev_location: Vec<$v>,
            prev_pose: Vec<$v>,
            dt_old: $f,
            pre_comp: ($v, $q),
            accumulator: f32,
        }

        impl $name {
            fn new(n: usize, collision_only: bool) -> Self {
                let (bones, rate) = layout(n);
                let damping = rate
                    .iter()
                    .map(|&x| (DAMPING * curve_at(&DAMPING_KEYS, x)).clamp(0.0, 1.0) as $f)
                    .collect();
                let stiffness = rate
                    .iter()
                    .map(|&x| (STIFFNESS * curve_at(&STIFFNESS_KEYS, x)).clamp(0.0, 1.0) as $f)
                    .collect();
                let mut s = Self {
                    bones,
                    damping,
                    stiffness,
                    collision_only,
                    location: Vec::new(),
                    prev_location: Vec::new(),
                    prev_pose: Vec::new(),
                    dt_old: 1.0 / TARGET_FPS as $f,
                    pre_comp: (<$v>::ZERO, <$q>::IDENTITY),
                    accumulator: 0.0,
                };
                let p = s.poses(&pose());
                s.location = p.clone();
                s.prev_location = p.clone();
                s.prev_pose = p;
                s
            }

            /// Every entry's pose: the real bones' animated places, the points lerped
            /// between their segment's ends (`UpdateInterBoneDummyPose`).
            fn poses(&self, animated: &[DVec3]) -> Vec<$v> {
                let mut out: Vec<$v> = self
                    .bones
                    .iter()
                    .map(|b| b.joint.map_or(<$v>::ZERO, |j| ($to_v)(animated[j])))
                    .collect();
                for (i, b) in self.bones.iter().enumerate() {
                    if let Some((a, e, alpha)) = b.between {
                        out[i] = out[a] + (out[e] - out[a]) * alpha as $f;
                    }
                }
                out
            }

            fn frame(&mut self, comp: (DVec3, DQuat), animated: Vec<DVec3>, frame_dt: f32) {
                let comp: ($v, $q) = (($to_v)(comp.0), ($to_q)(comp.1));
                let pose_now = self.poses(&animated);
                let fixed_dt: f32 = 1.0f32 / TARGET_FPS as f32;
                let raw = (self.accumulator + frame_dt).max(1.0e-4);
                let mut acc = raw.min(MAX_SUBSTEPS as f32 * fixed_dt);
                let dropped = raw - acc;
                let steps = (acc / fixed_dt).floor() as i32;
                acc -= steps as f32 * fixed_dt;
                self.accumulator = acc;
                let move_frac = (fixed_dt / raw) as $f;
                let consume = ((steps as f32 * fixed_dt + dropped) / raw).clamp(0.0, 1.0);
                let inv = comp.1.inverse();
                let move_vector = inv * (self.pre_comp.0 - comp.0);
                let move_rotation = inv * self.pre_comp.1;
                let h = fixed_dt as $f;
                let exponent = (TARGET_FPS as f32 * fixed_dt) as $f;
                let gravity_cs = inv * ($to_v)(DVec3::from(GRAVITY));
                for k in 0..steps {
                    let alpha = ((k + 1) as f32 / steps as f32) as $f;
                    let target: Vec<$v> = self
                        .prev_pose
                        .iter()
                        .zip(&pose_now)
                        .map(|(a, b)| *a + (*b - *a) * alpha)
                        .collect();
                    let sub_move = move_vector * move_frac;
                    let sub_rotation = <$q>::IDENTITY.slerp(move_rotation, move_frac).normalize();
                    self.prev_location[0] = self.location[0];
                    self.location[0] = target[0];
                    // Simulate, in array order (the points skip it when they only collide).
                    for i in 1..self.bones.len() {
                        if self.collision_only && self.bones[i].between.is_some() {
                            continue;
                        }
                        let parent = self.bones[i].parent.unwrap();
                        let mut velocity =
                            (self.location[i] - self.prev_location[i]) / self.dt_old.max(1.0e-4);
                        self.prev_location[i] = self.location[i];
                        velocity *= 1.0 - self.damping[i];
                        velocity += gravity_cs * h;
                        self.location[i] += velocity * h;
                        self.location[i] += sub_move * (1.0 - WORLD_DAMPING_LOCATION as $f);
                        self.location[i] += (sub_rotation * self.prev_location[i]
                            - self.prev_location[i])
                            * (1.0 - WORLD_DAMPING_ROTATION as $f);
                        let base = self.location[parent] + (target[i] - target[parent]);
                        let pull = (base - self.location[i])
                            * (1.0 - (1.0 - self.stiffness[i]).powf(exponent));
                        self.location[i] += pull;
                    }
                    // The points that only collide: on their segment.
                    if self.collision_only {
                        for i in 1..self.bones.len() {
                            if let Some((a, e, alpha)) = self.bones[i].between {
                                self.prev_location[i] = self.location[i];
                                self.location[i] = self.location[a]
                                    + (self.location[e] - self.location[a]) * alpha as $f;
                            }
                        }
                    }
                    // Lengths, in array order.
                    for i in 1..self.bones.len() {
                        let parent = self.bones[i].parent.unwrap();
                        let length = (target[i] - target[parent]).length();
                        let dir = (self.location[i] - self.location[parent]).normalize_or_zero();
                        self.location[i] = dir * length + self.location[parent];
                    }
                    self.dt_old = h;
                }
                self.dt_old = h;
                self.pre_comp = if consume >= 1.0 - 1.0e-4 {
                    comp
                } else {
                    let c = consume as $f;
                    (
                        self.pre_comp.0 + (comp.0 - self.pre_comp.0) * c,
                        self.pre_comp.1.slerp(comp.1, c).normalize(),
                    )
                };
                self.prev_pose = pose_now;
            }

            fn point(&self, i: usize) -> DVec3 {
                let v = self.location[i];
                DVec3::new(v.x as f64, v.y as f64, v.z as f64)
            }
        }
    };
}

port!(Port, f64, DVec3, DQuat, |v: DVec3| v, |q: DQuat| q);
port!(
    Port32,
    f32,
    Vec3,
    Quat,
    |v: DVec3| v.as_vec3(),
    |q: DQuat| q.as_quat()
);

fn locals(rest: &[Transform], angle: f64) -> Vec<Transform> {
    let mut l = rest.to_vec();
    l[0].rotation = DQuat::from_rotation_x(angle).as_quat();
    l
}

/// The hair with the port's curves, `n` points a segment.
fn subdivided(mode: TimeMode, n: u32, collision_only: bool) -> ChainSettings {
    let mut chain = common::kawaii::hair_chain(mode, ClassicGravity::PerFrame);
    chain.max_substeps = MAX_SUBSTEPS;
    chain.curves.stiffness = Curve::new(STIFFNESS_KEYS.map(|k| k.map(|v| v as f32)).to_vec());
    chain.curves.damping = Curve::new(DAMPING_KEYS.map(|k| k.map(|v| v as f32)).to_vec());
    chain.bone_subdivision_count = n;
    chain.bone_subdivision_collision_only = collision_only;
    chain
}

#[test]
fn kawaii_subdivision_matches_kawaiiphysics_1_21() {
    let sk = skeleton();
    let mut worst_all = 0.0f64;
    for (n, collision_only) in [(2usize, true), (2, false), (1, true)] {
        let rig = RigSettings {
            chains: vec![subdivided(TimeMode::Kawaii, n as u32, collision_only)],
            ..Default::default()
        };
        for motion in ["still", "sway", "step", "turn", "nod"] {
            for (label, hz) in [("30", 30.0f64), ("60", 60.0), ("144", 144.0)] {
                let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
                assert_eq!(
                    sim.chain_state().output_positions().len(),
                    1 + BONES * (n + 1),
                    "points: the bones and {n} between each"
                );
                let mut kp = Port::new(n, collision_only);
                let mut kp32 = Port32::new(n, collision_only);
                let rest = sk.rest().to_vec();
                sim.frame(&rest, Transform::IDENTITY, 0.0).unwrap();
                let (mut worst, mut rounding, mut swing) = (0.0f64, 0.0f64, 0.0f64);
                let mut t = 0.0f64;
                for _ in 1..=120 {
                    let dt = 1.0 / hz;
                    t += dt;
                    let (pos, rot) = component(if motion == "nod" { "still" } else { motion }, t);
                    let angle = nod(motion, t);
                    kp.frame((pos, rot), pose_at(angle), dt as f32);
                    kp32.frame((pos, rot), pose_at(angle), dt as f32);
                    let comp = Transform::from_translation_rotation(pos.as_vec3(), rot.as_quat());
                    sim.frame(&locals(&rest, angle), comp, dt as f32).unwrap();
                    let out = sim.chain_state().output_positions();
                    let animated = kp.poses(&pose_at(angle));
                    for (i, &got) in out.iter().enumerate().skip(1) {
                        worst = worst.max((got.as_dvec3() - kp.point(i)).length());
                        rounding = rounding.max((kp32.point(i) - kp.point(i)).length());
                        swing = swing.max((kp.point(i) - animated[i]).length());
                    }
                }
                println!(
                    "{n} a segment{}, {motion} {label} Hz: Tassel vs the 1.21 port (f64) \
                     {worst:.2e} m; its f32 vs f64 {rounding:.2e} m; swing {swing:.3} m",
                    if collision_only {
                        ", collision only"
                    } else {
                        ""
                    }
                );
                assert!(swing > 1e-3, "{motion} {label}: nothing moved");
                assert!(
                    worst <= 2e-5_f64.max(3.0 * rounding),
                    "{n} {collision_only} {motion} {label} Hz: {worst} m (f32 rounding: {rounding} m)"
                );
                worst_all = worst_all.max(worst);
            }
        }
    }
    println!("worst over every case: {worst_all:.2e} m");
}

/// The same hair run with and without points between its bones: its real points' and
/// its joints' places, every frame (model space), through the five motions at 60 and
/// 144 Hz.
fn run_hair(chain: ChainSettings) -> Vec<Vec3> {
    let sk = skeleton();
    let rig = RigSettings {
        chains: vec![chain],
        ..Default::default()
    };
    let mut out = Vec::new();
    for motion in ["still", "sway", "step", "turn", "nod"] {
        for hz in [60.0f64, 144.0] {
            let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
            let rest = sk.rest().to_vec();
            sim.frame(&rest, Transform::IDENTITY, 0.0).unwrap();
            let mut t = 0.0;
            for _ in 0..(2.0 * hz) as usize {
                t += 1.0 / hz;
                let (pos, rot) = component(if motion == "nod" { "still" } else { motion }, t);
                let comp = Transform::from_translation_rotation(pos.as_vec3(), rot.as_quat());
                sim.frame(&locals(&rest, nod(motion, t)), comp, (1.0 / hz) as f32)
                    .unwrap();
                out.extend(sim.pose().models.iter().map(|m| m.translation));
            }
        }
    }
    out
}

/// `fixed` and `classic` do what 1.21 means: points that only collide leave a chain that
/// touches nothing as it was (every joint every frame within 2e-5 m, f32 rounding of
/// the lengths restored through the points); `kawaii` keeps 1.21's stale pull, which
/// moves the same chain by centimetres (measured and printed, asserted > 1 mm).
#[test]
fn collision_only_points_leave_a_free_chain_as_it_was() {
    for mode in [TimeMode::Fixed, TimeMode::Classic, TimeMode::Kawaii] {
        let plain = run_hair(subdivided(mode, 0, true));
        let mut apart = 0.0f32;
        for n in [1, 3, 10] {
            let points = run_hair(subdivided(mode, n, true));
            let d = plain
                .iter()
                .zip(&points)
                .map(|(a, b)| a.distance(*b))
                .fold(0.0f32, f32::max);
            println!("{mode:?}, {n} points a segment, collision only: {d:.2e} m from none");
            apart = apart.max(d);
        }
        if mode == TimeMode::Kawaii {
            assert!(apart > 1e-3, "kawaii: 1.21's stale pull shows ({apart} m)");
        } else {
            assert!(
                apart < 2e-5,
                "{mode:?}: the points moved a free chain {apart} m"
            );
        }
        // Simulated points (not collision only) are bones of their own: a different chain.
        let simulated = run_hair(subdivided(mode, 2, false));
        let d = plain
            .iter()
            .zip(&simulated)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0f32, f32::max);
        println!("{mode:?}, 2 simulated points a segment: {d:.2e} m from none");
        assert!(
            d > 1e-3,
            "{mode:?}: simulated points changed nothing ({d} m)"
        );
    }
}

/// Three bones of 30 cm hanging from `anchor`, and a `bat` beside the middle one whose
/// animation swings a 4 cm sphere along X through the chain's line (±0.3 m at 1 Hz).
fn long_bones() -> (tassel::Skeleton, Vec<Transform>) {
    let names = ["anchor", "b0", "b1", "b2", "bat"]
        .map(String::from)
        .to_vec();
    let parents = vec![None, Some(0), Some(1), Some(2), Some(0)];
    let down = Transform::from_translation(Vec3::new(0.0, -0.3, 0.0));
    let rest = vec![
        Transform::IDENTITY,
        down,
        down,
        down,
        Transform::from_translation(Vec3::new(0.0, -0.45, 0.0)),
    ];
    let sk = tassel::Skeleton::new(names, parents, rest.clone()).unwrap();
    (sk, rest)
}

fn long_rig(mode: TimeMode, densify: bool) -> RigSettings {
    RigSettings {
        chains: vec![ChainSettings {
            name: "rope".into(),
            root: "anchor".into(),
            exclude: vec!["bat".into()],
            mode,
            stiffness: 0.02,
            damping: 0.1,
            radius: 0.02,
            bone_subdivision_densify_by_radius: densify,
            ..Default::default()
        }],
        colliders: vec![ColliderSettings {
            mirror: None,
            mirror_bone: String::new(),
            name: "ball".into(),
            bone: "bat".into(),
            offset: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            shape: Shape::Sphere {
                radius: 0.04,
                inside: false,
            },
        }],
        ..Default::default()
    }
}

/// Frames in which the chain's line (through every output point, in order) passes
/// inside the sphere by more than 1 mm; and the largest angle between a real bone as
/// written and the direction to its first point.
fn sweep(mode: TimeMode, densify: bool, hz: f32) -> (usize, usize, f32) {
    let (sk, rest) = long_bones();
    let rig = long_rig(mode, densify);
    let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
    let chains = sim.rig().chains().clone();
    let (mut through, mut frames, mut turn) = (0, 0, 0.0f32);
    for f in 0..=(4.0 * hz) as usize {
        let t = f as f32 / hz;
        let mut locals = rest.clone();
        locals[4].translation.x = 0.3 * (std::f32::consts::TAU * t).sin();
        sim.frame(
            &locals,
            Transform::IDENTITY,
            if f == 0 { 0.0 } else { 1.0 / hz },
        )
        .unwrap();
        let state = sim.chain_state();
        let (out, ball) = (state.output_positions(), state.placed_colliders()[0]);
        let centre = ball.transform.translation;
        let inside = out.windows(2).any(|w| {
            let (a, b) = (w[0], w[1]);
            let s = ((centre - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
            centre.distance(a + (b - a) * s) < 0.04 - 1e-3
        });
        through += usize::from(inside);
        frames += 1;
        // Each real bone as written points at the first point after it.
        let models = &sim.pose().models;
        for j in 1..3 {
            let p = (0..out.len())
                .find(|&p| chains.point(p).joint == Some(j))
                .unwrap();
            let first = (0..out.len())
                .find(|&c| chains.point(c).parent == Some(p))
                .unwrap();
            let written = models[j + 1].translation - models[j].translation;
            let aim = out[first] - out[p];
            turn = turn.max(written.angle_between(aim));
        }
    }
    (through, frames, turn)
}

#[test]
fn colliders_meet_the_bone_between_its_ends() {
    for mode in [TimeMode::Fixed, TimeMode::Classic, TimeMode::Kawaii] {
        for hz in [60.0, 144.0] {
            let (without, frames, _) = sweep(mode, false, hz);
            let (with, _, turn) = sweep(mode, true, hz);
            println!(
                "{mode:?} {hz} Hz: the sphere inside a bone in {without} of {frames} frames \
                 without subdivision, {with} with the points spaced by the radius; bones \
                 aimed at their first point within {turn:.1e} rad"
            );
            assert!(
                without > 10,
                "{mode:?} {hz}: the sphere never crossed a bone"
            );
            assert_eq!(with, 0, "{mode:?} {hz} Hz: the sphere went through a bone");
            assert!(
                turn < 1e-3,
                "{mode:?} {hz} Hz: a bone {turn} rad off its first point"
            );
        }
    }
}

/// The keys: read, written back only when set, refused out of range with the chain and
/// the key named; the number of points a segment gets, against the rule computed here
/// from the pose: the count, or with densify `ceil(length / (2 · r)) − 1` where `r` is the
/// radius times the radius curve's smallest value over [0, 1] (its ends and its keys),
/// at most 50; none on a radius of 0.
#[test]
fn subdivision_keys_and_point_counts() {
    let text = "[[chain]]\nname = \"hair\"\nroot = \"hair_0\"\nbone_subdivision_count = 3\n\
                bone_subdivision_collision_only = false\nbone_subdivision_densify_by_radius = true\n";
    let rig = RigSettings::from_toml_str(text).unwrap();
    let c = &rig.chains[0];
    assert_eq!(c.bone_subdivision_count, 3);
    assert!(!c.bone_subdivision_collision_only);
    assert!(c.bone_subdivision_densify_by_radius);
    let back = rig.to_toml_string().unwrap();
    assert_eq!(RigSettings::from_toml_str(&back).unwrap(), rig);
    let plain = RigSettings::from_toml_str("[[chain]]\nroot = \"hair_0\"\n").unwrap();
    assert_eq!(plain.chains[0].bone_subdivision_count, 0);
    assert!(plain.chains[0].bone_subdivision_collision_only);
    assert!(!plain.to_toml_string().unwrap().contains("subdivision"));
    for bad in ["11", "4294967295", "-1", "2.5"] {
        let t = text.replace(
            "bone_subdivision_count = 3",
            &format!("bone_subdivision_count = {bad}"),
        );
        let e = RigSettings::from_toml_str(&t).unwrap_err().to_string();
        assert!(e.contains("bone_subdivision_count"), "{bad}: {e}");
        if bad == "11" {
            assert!(e.contains("'hair'"), "{e}");
        }
    }
    // Points per segment.
    let sk = skeleton();
    let p = pose();
    let count = |radius: f32, keys: Vec<[f32; 2]>, n: u32| {
        let mut chain = subdivided(TimeMode::Fixed, n, true);
        chain.radius = radius;
        chain.curves.radius = Curve::new(keys);
        chain.bone_subdivision_densify_by_radius = true;
        let rig = RigSettings {
            chains: vec![chain],
            ..Default::default()
        };
        let sim = CharacterSim::new(sk.clone(), &rig).unwrap();
        sim.chain_state().output_positions().len()
    };
    let expected = |r_min: f64, n: usize| -> usize {
        1 + (1..=BONES)
            .map(|j| {
                let d = (p[j] - p[j - 1]).length();
                let cover = if r_min > 1e-6 {
                    ((d / (2.0 * r_min)).ceil() as usize).saturating_sub(1)
                } else {
                    0
                };
                cover.max(n).min(50) + 1
            })
            .sum::<usize>()
    };
    // A dip to 0.3 in the middle of the radius curve (no segment on a whole number).
    let dip = vec![[0.0, 1.0], [0.5, 0.3], [1.0, 2.0]];
    assert_eq!(count(0.01, dip.clone(), 0), expected(0.003, 0));
    assert_eq!(count(0.1, dip, 10), expected(0.03, 10));
    assert_eq!(count(0.02, Vec::new(), 0), expected(0.02, 0));
    assert_eq!(
        count(1e-5, Vec::new(), 0),
        1 + BONES * 51,
        "50 a segment at most"
    );
    assert_eq!(
        count(0.0, Vec::new(), 2),
        1 + BONES * 3,
        "no radius: the count"
    );
}

/// `fixed` with points between bones keeps its look across frame rates: the hair swayed
/// and turned (`common::kawaii::fixed_run`) at 30 and 60 Hz against 144 Hz, within 1 %
/// of the RMS dynamic deviation, with collision-only and with simulated points.
#[test]
fn fixed_with_subdivision_agrees_across_frame_rates() {
    let sk = skeleton();
    for collision_only in [true, false] {
        let rig = RigSettings {
            chains: vec![subdivided(TimeMode::Fixed, 2, collision_only)],
            ..Default::default()
        };
        let locals = |sk: &tassel::Skeleton, _t: f64| sk.rest().to_vec();
        let reference = common::kawaii::fixed_run(&sk, &rig, 144, locals);
        let rest: Vec<Vec<Vec3>> = reference
            .iter()
            .map(|_| pose().iter().map(|v| v.as_vec3()).collect())
            .collect();
        let deviation = common::kawaii::rms(&reference, &rest).max(1e-9);
        for hz in [30, 60] {
            let other = common::kawaii::fixed_run(&sk, &rig, hz, locals);
            let rel = common::kawaii::rms(&other, &reference) / deviation;
            println!(
                "collision only {collision_only}: {hz} Hz vs 144 Hz {:.3} % of the motion",
                100.0 * rel
            );
            assert!(rel < 0.01, "{collision_only} {hz} Hz: {:.3} %", 100.0 * rel);
        }
    }
}
