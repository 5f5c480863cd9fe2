//! Bone constraints and sync bones (issue 49, parts 1 and 4) against KawaiiPhysics 1.20
//! itself: an independent
//! port, in f64 and in this file, of `FAnimNode_KawaiiPhysics::SimulateModifyBones` as the
//! plugin's `20260106-v1.20.0` tag ships it, for what a skirt of chains uses: every bone
//! integrated first (Verlet velocity over the previous frame's dt, damping, gravity into the
//! velocity — 1.20's default —, the component's move and turn as inertia, the pull toward
//! the pose relative to the *integrated* parent), then `AdjustByBoneConstraints` (XPBD,
//! unit masses, compliance over dt², multipliers reset before each batch) for
//! `BoneConstraintIterationCountAfterCollision` passes, then every bone put back at its
//! length from the root down. `InitBoneConstraints`' rest lengths and its dummy-tip
//! constraints (`bAutoAddChildDummyBoneConstraint`) are ported too; 1.21's passes before
//! collision are run where a case asks for them (1.21 runs them before the collision pass,
//! which has nothing to do here). No colliders, wind or limits here: their differences are
//! the chains' own (docs/chains.md).
//!
//! `ApplySyncBones` (before the simulation: the source's component-space movement from its
//! reference place, scaled by its distance curve and per-axis global scale, filtered by
//! sign per axis, attenuated by distance to each target's simulated point, scaled by each
//! target's length-rate curve, and put on the targets' pose keeping their bone lengths) is
//! ported the same way, with the curves evaluated piecewise-linearly as Tassel's are
//! (Unreal's default keys are cubic: a documented difference).
//!
//! An 8-column skirt ring (each column a chain of 3 bones and a dummy tip), neighbouring
//! columns joined at every level, a left thigh swinging under it, 120 frames at 30, 60 and
//! 144 Hz, the character still, swaying, stepped and turning: every simulated point of
//! Tassel's `classic` output agrees with the port to 2e-5 m.

use glam::{DQuat, DVec3, Quat, Vec3};
use std::sync::Arc;
use tassel::crowd::{ChainCrowd, CrowdKind};
use tassel::dynamics::chain::{
    BoneConstraintSettings, ChainRig, ChainSettings, ClassicGravity, Compliance, CompliancePreset,
    SyncBoneSettings, SyncDirection, SyncTargetSettings, TimeMode,
};
use tassel::dynamics::Curve;
use tassel::dynamics::RigSettings;
use tassel::{CharacterRig, CharacterSim, Skeleton, Transform};

mod common;
use common::hair::component;

const COLUMNS: usize = 8;
const LEVELS: usize = 3;
const DUMMY: f64 = 0.05;
use common::kawaii::{
    DAMPING, GRAVITY, STIFFNESS, TARGET_FPS, WORLD_DAMPING_LOCATION, WORLD_DAMPING_ROTATION,
};

/// Component-space pose of joint `skirt_k_i` (i = 0 is the column's animated root under
/// the hips at 1 m).
fn joint_pose(k: usize, i: usize) -> DVec3 {
    let a = k as f64 * std::f64::consts::TAU / COLUMNS as f64;
    let (s, c) = a.sin_cos();
    DVec3::new(0.17 * s, 0.98, 0.17 * c) + i as f64 * DVec3::new(0.035 * s, -0.1, 0.035 * c)
}

/// The left thigh's place (model space) and the knee below it, 0.4 m down the thigh.
const THIGH: [f64; 3] = [0.09, 0.97, 0.0];
const KNEE: f64 = 0.4;

/// The thigh's swing about X at `t` seconds (radians; negative swings the knee forward).
fn thigh_angle(t: f64) -> f64 {
    -0.7 * (std::f64::consts::TAU * 0.8 * t).sin()
}

/// The knee's component-space place at `t`.
fn knee_at(t: f64) -> DVec3 {
    DVec3::from(THIGH) + DQuat::from_rotation_x(thigh_angle(t)) * DVec3::new(0.0, -KNEE, 0.0)
}

/// The animated locals at `t`: the rest pose with the thigh swung.
fn locals_at(sk: &Skeleton, t: f64) -> Vec<Transform> {
    let mut locals = sk.rest().to_vec();
    let thigh = sk.find("thigh_l").unwrap();
    locals[thigh].rotation = Quat::from_rotation_x(thigh_angle(t) as f32);
    locals
}

fn skeleton() -> Skeleton {
    let mut names = vec!["hips".to_string()];
    let mut parents = vec![None];
    let mut rest = vec![Transform::from_translation(Vec3::new(0.0, 1.0, 0.0))];
    for k in 0..COLUMNS {
        for i in 0..=LEVELS {
            names.push(format!("skirt_{k}_{i}"));
            let (parent, from) = if i == 0 {
                (0, DVec3::new(0.0, 1.0, 0.0))
            } else {
                (names.len() - 2, joint_pose(k, i - 1))
            };
            parents.push(Some(parent));
            rest.push(Transform::from_translation(
                (joint_pose(k, i) - from).as_vec3(),
            ));
        }
    }
    names.push("thigh_l".into());
    parents.push(Some(0));
    rest.push(Transform::from_translation(
        (DVec3::from(THIGH) - DVec3::new(0.0, 1.0, 0.0)).as_vec3(),
    ));
    names.push("knee_l".into());
    parents.push(Some(names.len() - 2));
    rest.push(Transform::from_translation(Vec3::new(
        0.0,
        -KNEE as f32,
        0.0,
    )));
    Skeleton::new(names, parents, rest).unwrap()
}

/// The neighbouring-column pairs at every level, ring closed, in the order the rig lists
/// them: column by column, level by level.
fn pairs() -> Vec<(String, String)> {
    let mut out = Vec::new();
    for k in 0..COLUMNS {
        for i in 1..=LEVELS {
            out.push((
                format!("skirt_{k}_{i}"),
                format!("skirt_{}_{i}", (k + 1) % COLUMNS),
            ));
        }
    }
    out
}

/// A skirt rig: one chain per column, `mode`, neighbouring columns constrained with
/// `compliance` (no constraints when `None`), `before` / `after` passes.
fn rig(mode: TimeMode, compliance: Option<Compliance>, before: u32, after: u32) -> RigSettings {
    let chains = (0..COLUMNS)
        .map(|k| ChainSettings {
            name: format!("skirt_{k}"),
            root: format!("skirt_{k}_0"),
            mode,
            classic_gravity: ClassicGravity::DtSquared,
            damping: DAMPING as f32,
            stiffness: STIFFNESS as f32,
            world_damping_location: WORLD_DAMPING_LOCATION as f32,
            world_damping_rotation: WORLD_DAMPING_ROTATION as f32,
            gravity: Vec3::from(GRAVITY.map(|g| g as f32)),
            target_framerate: TARGET_FPS as f32,
            dummy_bone_length: DUMMY as f32,
            max_delta_time: 1.0,
            teleport_distance: 0.0,
            teleport_rotation: 0.0,
            ..Default::default()
        })
        .collect();
    RigSettings {
        chains,
        bone_constraints: match compliance {
            Some(_) => pairs()
                .iter()
                .map(|(a, b)| BoneConstraintSettings::between(a, b))
                .collect(),
            None => Vec::new(),
        },
        bone_constraint_global_compliance_type: compliance.unwrap_or_default(),
        bone_constraint_iteration_count_before_collision: before,
        bone_constraint_iteration_count_after_collision: after,
        ..Default::default()
    }
}

const GLOBAL_SCALE: [f64; 3] = [1.0, 0.5, 1.0];
const DELTA_CURVE: [[f64; 2]; 2] = [[0.0, 1.0], [0.4, 0.5]];
const RATE_CURVE: [[f64; 2]; 2] = [[0.0, 0.4], [1.0, 1.0]];
const ATTENUATION: [f64; 3] = [0.25, 0.6, 0.7];

/// The knee pushes the front of the skirt: `skirt_0_1` and the bones below it (a share
/// growing along them), `skirt_1_1` alone and `skirt_7_1` with the bones below it; only
/// its forward (+Z) movement, half of its vertical one, attenuated with distance.
fn sync_bone() -> SyncBoneSettings {
    let curve =
        |k: [[f64; 2]; 2]| Curve::new(k.iter().map(|k| [k[0] as f32, k[1] as f32]).collect());
    SyncBoneSettings {
        bone: "knee_l".into(),
        target_roots: vec![
            SyncTargetSettings {
                bone: "skirt_0_1".into(),
                scale_curve_by_bone_length_rate: curve(RATE_CURVE),
                ..Default::default()
            },
            SyncTargetSettings {
                bone: "skirt_1_1".into(),
                include_child_bones: false,
                ..Default::default()
            },
            SyncTargetSettings {
                bone: "skirt_7_1".into(),
                ..Default::default()
            },
        ],
        global_scale: Vec3::from(GLOBAL_SCALE.map(|g| g as f32)),
        scale_curve_by_delta_distance: curve(DELTA_CURVE),
        apply_direction_z: SyncDirection::Positive,
        enable_distance_attenuation: true,
        attenuation_inner_radius: ATTENUATION[0] as f32,
        attenuation_outer_radius: ATTENUATION[1] as f32,
        max_attenuation_rate: ATTENUATION[2] as f32,
        ..Default::default()
    }
}

/// A piecewise-linear curve through two keys, clamped (Tassel's rule).
fn linear(k: [[f64; 2]; 2], x: f64) -> f64 {
    let w = ((x - k[0][0]) / (k[1][0] - k[0][0])).clamp(0.0, 1.0);
    k[0][1] + (k[1][1] - k[0][1]) * w
}

/// KawaiiPhysics 1.20's update of the skirt, in a float type of choice (f64: the
/// reference; f32: how far rounding alone moves the same update).
macro_rules! kawaii {
    ($name:ident, $f:ty, $v:ty, $q:ty, $to_v:expr, $to_q:expr) => {
        struct $name {
            /// Points column by column: root, 3 bones, the dummy tip.
            location: Vec<$v>,
            prev_location: Vec<$v>,
            pose: Vec<$v>,
            parent: Vec<Option<usize>>,
            /// (bone1, bone2, length, lambda).
            constraints: Vec<(usize, usize, $f, $f)>,
            compliance: $f,
            before: u32,
            after: u32,
            dt_old: $f,
            prev_comp: ($v, $q),
            /// The pose before sync bones move it, each bone's reference length, and
            /// the sync targets (point, scale by length rate) when the knee syncs.
            rest_pose: Vec<$v>,
            bone_length: Vec<$f>,
            sync: Vec<(usize, $f)>,
        }

        impl $name {
            /// `open`: the ring not closed (no pairs from the last column to the first).
            fn new(
                compliance: Option<f64>,
                before: u32,
                after: u32,
                sync: bool,
                open: bool,
            ) -> Self {
                let (mut pose, mut parent) = (Vec::new(), Vec::new());
                let point = |k: usize, i: usize| k * (LEVELS + 2) + i;
                for k in 0..COLUMNS {
                    for i in 0..=LEVELS {
                        pose.push(($to_v)(joint_pose(k, i)));
                        parent.push((i > 0).then(|| point(k, i - 1)));
                    }
                    // The dummy tip: the last bone's direction, `DUMMY` on.
                    let (a, b) = (joint_pose(k, LEVELS - 1), joint_pose(k, LEVELS));
                    pose.push(($to_v)(b + (b - a).normalize() * DUMMY));
                    parent.push(Some(point(k, LEVELS)));
                }
                // InitBoneConstraints: the listed pairs, then each pair's dummy children.
                let mut constraints = Vec::new();
                let mut dummies = Vec::new();
                if compliance.is_some() {
                    let last = if open { COLUMNS - 1 } else { COLUMNS };
                    for k in 0..last {
                        for i in 1..=LEVELS {
                            let (a, b) = (point(k, i), point((k + 1) % COLUMNS, i));
                            constraints.push((a, b, (pose[a] - pose[b]).length(), 0.0));
                            if i == LEVELS {
                                let (da, db) = (a + 1, b + 1);
                                dummies.push((da, db, (pose[da] - pose[db]).length(), 0.0));
                            }
                        }
                    }
                }
                constraints.extend(dummies);
                let bone_length: Vec<$f> = (0..pose.len())
                    .map(|i| parent[i].map_or(0.0, |p: usize| (pose[i] - pose[p]).length()))
                    .collect();
                // InitSyncBone: each target root and (with its children) the bones below
                // it, each with its length rate from the root through the curve.
                let mut targets = Vec::new();
                if sync {
                    let from_root = |i: usize| {
                        let mut l = 0.0 as $f;
                        let mut j = i;
                        while let Some(p) = parent[j] {
                            l += bone_length[j];
                            j = p;
                        }
                        l
                    };
                    for (k, children, curve) in
                        [(0usize, true, true), (1, false, false), (7, true, false)]
                    {
                        let root = point(k, 1);
                        let members: Vec<usize> = if children {
                            (root..point(k, LEVELS + 1) + 1).collect()
                        } else {
                            vec![root]
                        };
                        let start = from_root(root);
                        let max = members.iter().map(|&i| from_root(i)).fold(start, <$f>::max);
                        for i in members {
                            let rate = if max - start > 1e-6 {
                                (from_root(i) - start) / (max - start)
                            } else {
                                0.0
                            };
                            let scale = if curve {
                                linear(RATE_CURVE, rate as f64) as $f
                            } else {
                                1.0
                            };
                            targets.push((i, scale));
                        }
                    }
                }
                Self {
                    rest_pose: pose.clone(),
                    bone_length,
                    sync: targets,
                    location: pose.clone(),
                    prev_location: pose.clone(),
                    pose,
                    parent,
                    constraints,
                    compliance: compliance.unwrap_or(0.0) as $f,
                    before,
                    after,
                    dt_old: 1.0 / TARGET_FPS as $f,
                    prev_comp: (<$v>::ZERO, <$q>::IDENTITY),
                }
            }

            /// `AdjustByBoneConstraints`, `n` passes after resetting the multipliers.
            fn constrain(&mut self, n: u32, dt: $f) {
                if n == 0 {
                    return;
                }
                for c in &mut self.constraints {
                    c.3 = 0.0;
                }
                for _ in 0..n {
                    for c in &mut self.constraints {
                        let mut delta = self.location[c.1] - self.location[c.0];
                        let len = delta.length();
                        if len <= 0.0 {
                            continue;
                        }
                        let constraint = len - c.2;
                        let compliance = self.compliance / (dt * dt);
                        let dl = (constraint - compliance * c.3) / (2.0 + compliance);
                        delta = (delta / len) * dl;
                        self.location[c.0] += delta;
                        self.location[c.1] -= delta;
                        c.3 += dl;
                    }
                }
            }

            /// `ApplySyncBones` with the knee at `knee` (component space).
            fn apply_sync(&mut self, knee: DVec3) {
                self.pose.copy_from_slice(&self.rest_pose);
                if self.sync.is_empty() {
                    return;
                }
                let knee = ($to_v)(knee);
                let rest_knee = ($to_v)(knee_at(0.0));
                let mut delta = knee - rest_knee;
                delta *= linear(DELTA_CURVE, delta.length() as f64) as $f;
                delta *= ($to_v)(DVec3::from(GLOBAL_SCALE));
                // Z: the positive direction only.
                if delta.z <= 0.0 {
                    delta.z = 0.0;
                }
                // FVector::IsNearlyZero (1e-4 cm = 1e-6 m per component).
                if delta.abs().max_element() <= 1e-6 {
                    return;
                }
                let [inner, outer, max] = ATTENUATION.map(|a| a as $f);
                for &(i, scale) in &self.sync {
                    let distance = (knee - self.location[i]).length();
                    let amount = if distance <= inner {
                        0.0
                    } else if distance >= outer {
                        max
                    } else {
                        (distance - inner) / (outer - inner) * max
                    };
                    let alpha = (1.0 - amount).max(0.0);
                    let moved = self.pose[i] + delta * alpha * scale;
                    let p = self.parent[i].unwrap();
                    self.pose[i] = (moved - self.pose[p]).normalize_or_zero() * self.bone_length[i]
                        + self.pose[p];
                }
            }

            fn frame(&mut self, comp: (DVec3, DQuat), dt: f64, knee: DVec3) {
                self.apply_sync(knee);
                let comp: ($v, $q) = (($to_v)(comp.0), ($to_q)(comp.1));
                let dt = dt as $f;
                let inv = comp.1.inverse();
                let move_vector = inv * (self.prev_comp.0 - comp.0);
                let move_rotation = inv * self.prev_comp.1;
                self.prev_comp = comp;
                let exponent = TARGET_FPS as $f * dt;
                let gravity = inv * ($to_v)(DVec3::from(GRAVITY));
                let n = self.location.len();
                // Save Prev/Pose info: the roots take the pose.
                for i in 0..n {
                    if self.parent[i].is_none() {
                        self.prev_location[i] = self.location[i];
                        self.location[i] = self.pose[i];
                    }
                }
                // Simulate every bone.
                for i in 0..n {
                    let Some(parent) = self.parent[i] else {
                        continue;
                    };
                    let mut velocity = (self.location[i] - self.prev_location[i]) / self.dt_old;
                    self.prev_location[i] = self.location[i];
                    velocity *= 1.0 - DAMPING as $f;
                    velocity += gravity * dt;
                    self.location[i] += velocity * dt;
                    self.location[i] += move_vector * (1.0 - WORLD_DAMPING_LOCATION as $f);
                    self.location[i] += (move_rotation * self.prev_location[i]
                        - self.prev_location[i])
                        * (1.0 - WORLD_DAMPING_ROTATION as $f);
                    let base = self.location[parent] + (self.pose[i] - self.pose[parent]);
                    let pull =
                        (base - self.location[i]) * (1.0 - (1.0 - STIFFNESS as $f).powf(exponent));
                    self.location[i] += pull;
                }
                self.constrain(self.before, dt);
                // (The collision pass: no colliders.)
                self.constrain(self.after, dt);
                // Limits (none) and bone lengths.
                for i in 0..n {
                    let Some(parent) = self.parent[i] else {
                        continue;
                    };
                    let length = (self.pose[i] - self.pose[parent]).length();
                    self.location[i] =
                        (self.location[i] - self.location[parent]).normalize_or_zero() * length
                            + self.location[parent];
                }
                self.dt_old = dt;
            }

            fn point(&self, k: usize, i: usize) -> DVec3 {
                let v = self.location[k * (LEVELS + 2) + i];
                DVec3::new(v.x as f64, v.y as f64, v.z as f64)
            }
        }
    };
}

kawaii!(Kawaii, f64, DVec3, DQuat, |v: DVec3| v, |q: DQuat| q);
kawaii!(
    Kawaii32,
    f32,
    Vec3,
    Quat,
    |v: DVec3| v.as_vec3(),
    |q: DQuat| q.as_quat()
);

/// Tassel's output point of column `k`, level `i` (`LEVELS + 1`: the dummy tip), found
/// through the rig's point table.
fn tassel_point(sim: &CharacterSim, k: usize, i: usize) -> DVec3 {
    let rig = sim.chains();
    let sk = sim.skeleton();
    let points = rig.chain_points(k);
    let p = points
        .clone()
        .find(|&p| {
            let info = rig.point(p);
            match info.joint {
                Some(j) => i <= LEVELS && sk.name(j) == format!("skirt_{k}_{i}"),
                None => i == LEVELS + 1,
            }
        })
        .expect("the point exists");
    sim.chain_state().output_positions()[p].as_dvec3()
}

/// Tassel's classic skirt against the port, with or without the knee syncing the front.
fn compare_classic(sync: bool) -> f64 {
    let sk = skeleton();
    // The open ring: the last column is only ever a pair's `bone2` (its chain joins the
    // group through the other side of the pair).
    let cases = [
        (CompliancePreset::Leather, 0, 1, false),
        (CompliancePreset::Fat, 0, 1, false),
        (CompliancePreset::Muscle, 1, 2, false),
        (CompliancePreset::Leather, 0, 1, true),
    ];
    let mut worst_all = 0.0f64;
    for (preset, before, after, open) in cases {
        let compliance = Some(Compliance::Preset(preset));
        let mut rig = rig(TimeMode::Classic, compliance, before, after);
        if open {
            let last = format!("skirt_{}_", COLUMNS - 1);
            rig.bone_constraints.retain(|c| !c.bone1.starts_with(&last));
            assert_eq!(rig.bone_constraints.len(), (COLUMNS - 1) * LEVELS);
        }
        if sync {
            rig.sync_bones = vec![sync_bone()];
        }
        for motion in ["still", "sway", "step", "turn"] {
            for hz in [30.0f64, 60.0, 144.0] {
                let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
                let value = Some(preset.value() as f64);
                let mut kp = Kawaii::new(value, before, after, sync, open);
                let mut kp32 = Kawaii32::new(value, before, after, sync, open);
                // What the feature under test changes: the same port without it.
                let mut without = if sync {
                    Kawaii::new(value, before, after, false, open)
                } else {
                    Kawaii::new(None, 0, 0, false, false)
                };
                sim.frame(&locals_at(&sk, 0.0), Transform::IDENTITY, 0.0)
                    .unwrap();
                let (mut worst, mut rounding, mut effect) = (0.0f64, 0.0f64, 0.0f64);
                for f in 1..=120 {
                    let t = f as f64 / hz;
                    let (pos, rot) = component(motion, t);
                    let knee = knee_at(t);
                    kp.frame((pos, rot), 1.0 / hz, knee);
                    kp32.frame((pos, rot), 1.0 / hz, knee);
                    without.frame((pos, rot), 1.0 / hz, knee);
                    let comp = Transform::from_translation_rotation(pos.as_vec3(), rot.as_quat());
                    sim.frame(&locals_at(&sk, t), comp, (1.0 / hz) as f32)
                        .unwrap();
                    for k in 0..COLUMNS {
                        for i in 1..=LEVELS + 1 {
                            let got = tassel_point(&sim, k, i);
                            worst = worst.max((got - kp.point(k, i)).length());
                            rounding = rounding.max((kp32.point(k, i) - kp.point(k, i)).length());
                            effect = effect.max((without.point(k, i) - kp.point(k, i)).length());
                        }
                    }
                }
                let what = if sync { "sync bones" } else { "constraints" };
                println!(
                    "{preset:?}{} before {before} after {after}, {motion} {hz} Hz{}: Tassel vs \
                     KawaiiPhysics 1.20 (f64) {worst:.2e} m; f32 rounding {rounding:.2e} m; \
                     the {what} move points by up to {effect:.2e} m",
                    if open { " (open ring)" } else { "" },
                    if sync { ", knee synced" } else { "" }
                );
                assert!(
                    worst <= 2e-5_f64.max(2.0 * rounding),
                    "{preset:?} {motion} {hz} Hz: {worst} m (f32 rounding alone: {rounding} m)"
                );
                if motion != "still" || sync {
                    // The feature matters in this scene, or the test shows nothing.
                    assert!(
                        effect > 1e-3,
                        "{preset:?} {motion}: the {what} moved {effect} m"
                    );
                }
                worst_all = worst_all.max(worst);
            }
        }
    }
    worst_all
}

#[test]
fn classic_matches_kawaiiphysics_1_20_bone_constraints() {
    let worst = compare_classic(false);
    println!("worst over every case: {worst:.2e} m");
}

#[test]
fn classic_matches_kawaiiphysics_1_20_sync_bones() {
    let worst = compare_classic(true);
    println!("worst over every case, knee synced: {worst:.2e} m");
}

/// World positions of every skirt joint, sampled every 1/6 s, over 6 s of sway and turn.
fn fixed_run(rig: &RigSettings, hz: u32) -> (Vec<Vec<Vec3>>, Vec<Vec<Vec3>>) {
    let sk = skeleton();
    let mut sim = CharacterSim::new(sk.clone(), rig).unwrap();
    let (mut sim_pos, mut anim_pos) = (Vec::new(), Vec::new());
    for f in 0..=6 * hz {
        let t = f as f64 / hz as f64;
        let comp = Transform::from_translation_rotation(
            Vec3::new((0.3 * (std::f64::consts::TAU * t).sin()) as f32, 0.0, 0.0),
            Quat::from_rotation_y((0.5 * (std::f64::consts::TAU * 0.7 * t).sin()) as f32),
        );
        let dt = if f == 0 { 0.0 } else { 1.0 / hz as f32 };
        sim.frame(&locals_at(&sk, t), comp, dt).unwrap();
        if (f * 6) % hz == 0 {
            let world = |ms: &[Transform]| -> Vec<Vec3> {
                ms.iter()
                    .map(|m| comp.transform_point(m.translation))
                    .collect()
            };
            sim_pos.push(world(&sim.pose().models));
            anim_pos.push(world(&sim.animated_models()));
        }
    }
    (sim_pos, anim_pos)
}

#[test]
fn fixed_mode_with_bone_constraints_and_sync_bones_is_frame_rate_independent() {
    for (preset, sync) in [
        (CompliancePreset::Leather, false),
        (CompliancePreset::Fat, false),
        (CompliancePreset::Fat, true),
    ] {
        let mut rig = rig(TimeMode::Fixed, Some(Compliance::Preset(preset)), 1, 2);
        if sync {
            rig.sync_bones = vec![sync_bone()];
        }
        let (reference, anim) = fixed_run(&rig, 144);
        let (mut dev2, mut n) = (0.0f64, 0usize);
        for (s, a) in reference.iter().zip(&anim) {
            for (x, y) in s.iter().zip(a) {
                dev2 += (*x - *y).length_squared() as f64;
                n += 1;
            }
        }
        let dev_rms = (dev2 / n as f64).sqrt();
        for hz in [30, 60] {
            let (other, _) = fixed_run(&rig, hz);
            let d2: f64 = other
                .iter()
                .zip(&reference)
                .flat_map(|(s, r)| s.iter().zip(r))
                .map(|(x, y)| (*x - *y).length_squared() as f64)
                .sum();
            let rel = (d2 / n as f64).sqrt() / dev_rms;
            println!(
                "{preset:?}{}: {hz} Hz vs 144 Hz: {:.3} % of the RMS dynamic deviation ({:.1} mm)",
                if sync { ", knee synced" } else { "" },
                100.0 * rel,
                1e3 * dev_rms
            );
            assert!(rel <= 0.01, "{preset:?} at {hz} Hz: {:.2} %", 100.0 * rel);
        }
    }
}

/// Mean |distance − rest distance| of the constrained neighbours' points over a violent
/// run (fixed mode, 60 Hz, the character flung sideways and spun).
fn neighbour_strain(rig: &RigSettings) -> f64 {
    let sk = skeleton();
    let mut sim = CharacterSim::new(sk.clone(), rig).unwrap();
    let rest = sk.rest().to_vec();
    let rest_models = tassel::Pose::rest(&sk).models;
    let index: Vec<(usize, usize)> = pairs()
        .iter()
        .map(|(a, b)| (sk.find(a).unwrap(), sk.find(b).unwrap()))
        .collect();
    let (mut sum, mut n) = (0.0f64, 0usize);
    for f in 0..=180 {
        let t = f as f32 / 60.0;
        let comp = Transform::from_translation_rotation(
            Vec3::new(1.5 * (6.0 * t).sin(), 0.0, 0.0),
            Quat::from_rotation_y(2.0 * t),
        );
        sim.frame(&rest, comp, if f == 0 { 0.0 } else { 1.0 / 60.0 })
            .unwrap();
        let m = &sim.pose().models;
        for &(a, b) in &index {
            assert!(m[a].translation.is_finite() && m[b].translation.is_finite());
            let now = (m[a].translation - m[b].translation).length();
            let was = (rest_models[a].translation - rest_models[b].translation).length();
            sum += (now - was).abs() as f64;
            n += 1;
        }
    }
    sum / n as f64
}

#[test]
fn constraints_hold_the_columns_together_under_violent_motion() {
    let free = neighbour_strain(&rig(TimeMode::Fixed, None, 0, 0));
    let leather = neighbour_strain(&rig(
        TimeMode::Fixed,
        Some(Compliance::Preset(CompliancePreset::Leather)),
        1,
        2,
    ));
    let fat = neighbour_strain(&rig(
        TimeMode::Fixed,
        Some(Compliance::Preset(CompliancePreset::Fat)),
        1,
        2,
    ));
    println!(
        "mean neighbour strain: free {:.2} mm, fat {:.2} mm, leather {:.2} mm",
        1e3 * free,
        1e3 * fat,
        1e3 * leather
    );
    assert!(
        free > 2e-3,
        "the motion does not strain a free skirt ({free} m)"
    );
    assert!(leather < 0.5 * free, "leather {leather} m vs free {free} m");
    assert!(leather < fat && fat < free, "{leather} < {fat} < {free}");
}

#[test]
fn patterns_pair_the_kth_matches_in_skeleton_order() {
    let sk = skeleton();
    let listed = rig(
        TimeMode::Fixed,
        Some(Compliance::Preset(CompliancePreset::Rubber)),
        0,
        1,
    );
    // The same pairs from patterns: column k with column k+1 for k < 7 (the k-th match of
    // each pattern in skeleton order), and the ring's closing pairs by name.
    let mut patterned = listed.clone();
    patterned.bone_constraints.clear();
    for k in 0..COLUMNS - 1 {
        patterned.bone_constraints.push(BoneConstraintSettings {
            bone1_pattern: format!("skirt_{k}_[1-3]"),
            bone2_pattern: format!("skirt_{}_[123]", k + 1),
            ..Default::default()
        });
    }
    for i in 1..=LEVELS {
        patterned
            .bone_constraints
            .push(BoneConstraintSettings::between(
                &format!("skirt_{}_{i}", COLUMNS - 1),
                &format!("skirt_0_{i}"),
            ));
    }
    let mut a = CharacterSim::new(sk.clone(), &listed).unwrap();
    let mut b = CharacterSim::new(sk.clone(), &patterned).unwrap();
    let rest = sk.rest().to_vec();
    for f in 0..90 {
        let comp = Transform::from_translation(Vec3::new(0.4 * (f as f32 * 0.2).sin(), 0.0, 0.0));
        let dt = if f == 0 { 0.0 } else { 1.0 / 60.0 };
        a.frame(&rest, comp, dt).unwrap();
        b.frame(&rest, comp, dt).unwrap();
        common::assert_pose_bits(&sk, &format!("frame {f}"), b.pose(), a.pose());
    }
    // One pattern over all columns at once pairs in skeleton order too: the k-th of
    // `skirt_[0-6]_[1-3]` (0_1, 0_2, 0_3, 1_1, …) with the k-th of `skirt_[1-7]_[1-3]`.
    let mut one = patterned.clone();
    one.bone_constraints = vec![BoneConstraintSettings {
        bone1_pattern: "skirt_[0-6]_[1-3]".into(),
        bone2_pattern: "skirt_[1-7]_[1-3]".into(),
        ..Default::default()
    }];
    one.bone_constraints
        .extend(patterned.bone_constraints[COLUMNS - 1..].iter().cloned());
    let mut c = CharacterSim::new(sk.clone(), &one).unwrap();
    let mut a = CharacterSim::new(sk.clone(), &listed).unwrap();
    for f in 0..30 {
        let comp = Transform::from_translation(Vec3::new(0.4 * (f as f32 * 0.2).sin(), 0.0, 0.0));
        let dt = if f == 0 { 0.0 } else { 1.0 / 60.0 };
        a.frame(&rest, comp, dt).unwrap();
        c.frame(&rest, comp, dt).unwrap();
    }
    common::assert_pose_bits(&sk, "one pattern", c.pose(), a.pose());
}

#[test]
fn the_rig_file_reads_and_writes_bone_constraints() {
    let text = r#"
bone_constraint_global_compliance_type = "rubber"
bone_constraint_iteration_count_before_collision = 1
bone_constraint_iteration_count_after_collision = 3
auto_add_child_dummy_bone_constraint = false

[[chain]]
name = "a"
root = "skirt_0_0"

[[chain]]
name = "b"
root = "skirt_1_0"

[[bone_constraint]]
bone1 = "skirt_0_1"
bone2 = "skirt_1_1"

[[bone_constraint]]
bone1_pattern = "skirt_0_[23]"
bone2_pattern = "skirt_1_[23]"
compliance = 2.5e-6

[[bone_constraint]]
bone1 = "skirt_0_3"
bone2 = "skirt_1_3"
compliance = "concrete"
"#;
    let rig = RigSettings::from_toml_str(text).unwrap();
    assert_eq!(
        rig.bone_constraint_global_compliance_type,
        Compliance::Preset(CompliancePreset::Rubber)
    );
    assert_eq!(rig.bone_constraint_iteration_count_before_collision, 1);
    assert_eq!(rig.bone_constraint_iteration_count_after_collision, 3);
    assert!(!rig.auto_add_child_dummy_bone_constraint);
    assert_eq!(rig.bone_constraints.len(), 3);
    assert_eq!(
        rig.bone_constraints[1].compliance,
        Some(Compliance::Value(2.5e-6))
    );
    assert_eq!(
        rig.bone_constraints[2].compliance,
        Some(Compliance::Preset(CompliancePreset::Concrete))
    );
    let again = RigSettings::from_toml_str(&rig.to_toml_string().unwrap()).unwrap();
    assert_eq!(again, rig);
    // Defaults: KawaiiPhysics 1.20's (leather, no pass before collision, one after, dummy
    // tips joined).
    let plain =
        RigSettings::from_toml_str("[[chain]]\nname = \"a\"\nroot = \"skirt_0_0\"\n").unwrap();
    assert_eq!(
        plain.bone_constraint_global_compliance_type.value(),
        0.000_000_001
    );
    assert_eq!(plain.bone_constraint_iteration_count_before_collision, 0);
    assert_eq!(plain.bone_constraint_iteration_count_after_collision, 1);
    assert!(plain.auto_add_child_dummy_bone_constraint);
    assert_eq!(
        plain,
        RigSettings {
            chains: plain.chains.clone(),
            ..Default::default()
        }
    );
    // The compiled rig: 1 + 2 + 1 constraints, both chains in one group.
    let sim = CharacterSim::new(skeleton(), &rig).unwrap();
    assert!(sim.chains().has_bone_constraints());
}

/// The error of compiling `rig` on the skirt skeleton.
fn error_of(rig: &RigSettings) -> String {
    match RigSettings::from_toml_str(&rig.to_toml_string().unwrap()) {
        Err(e) => return e.to_string(),
        Ok(parsed) => assert_eq!(&parsed, rig),
    }
    match CharacterSim::new(skeleton(), rig) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("accepted: {rig:?}"),
    }
}

#[test]
fn bad_constraints_are_errors_that_name_the_entry() {
    let base = rig(TimeMode::Fixed, Some(Compliance::default()), 0, 1);
    let with = |c: BoneConstraintSettings| {
        let mut r = base.clone();
        r.bone_constraints.push(c);
        r
    };
    let n = base.bone_constraints.len() + 1;
    let cases: Vec<(RigSettings, Vec<String>)> = vec![
        (
            with(BoneConstraintSettings::between("skirt_0_1", "skirt_0_1")),
            vec![format!("#{n}"), "itself".into()],
        ),
        (
            with(BoneConstraintSettings::between("skirt_0_0", "skirt_1_1")),
            vec![format!("#{n}"), "skirt_0_0".into(), "not simulated".into()],
        ),
        (
            with(BoneConstraintSettings::between("hips", "skirt_1_1")),
            vec![format!("#{n}"), "hips".into(), "not simulated".into()],
        ),
        (
            with(BoneConstraintSettings::between("skirt_0_1", "nope")),
            vec![format!("#{n}"), "nope".into()],
        ),
        (
            with(BoneConstraintSettings {
                bone1_pattern: "cape_.*".into(),
                bone2_pattern: "skirt_1_.*".into(),
                ..Default::default()
            }),
            vec![
                format!("#{n}"),
                "bone1_pattern".into(),
                "matches no bone".into(),
            ],
        ),
        (
            with(BoneConstraintSettings {
                bone1_pattern: "skirt_0_[12]".into(),
                bone2_pattern: "skirt_1_[123]".into(),
                ..Default::default()
            }),
            vec![format!("#{n}"), "2".into(), "3".into()],
        ),
        (
            with(BoneConstraintSettings {
                bone1_pattern: "skirt_0_(".into(),
                bone2_pattern: "skirt_1_1".into(),
                ..Default::default()
            }),
            vec![format!("#{n}"), "regular expression".into()],
        ),
        (
            with(BoneConstraintSettings {
                compliance: Some(Compliance::Value(-1e-6)),
                ..BoneConstraintSettings::between("skirt_0_1", "skirt_2_1")
            }),
            vec![format!("#{n}"), "compliance".into()],
        ),
        (
            with(BoneConstraintSettings {
                bone1: "skirt_0_1".into(),
                bone2_pattern: "skirt_1_1".into(),
                ..Default::default()
            }),
            vec![format!("#{n}"), "pattern".into()],
        ),
        (
            {
                let mut r = base.clone();
                r.bone_constraint_global_compliance_type = Compliance::Value(f32::NAN);
                r
            },
            vec!["bone_constraint_global_compliance_type".into()],
        ),
        (
            {
                let mut r = base.clone();
                r.bone_constraint_iteration_count_after_collision = 1_000_000;
                r
            },
            vec!["bone_constraint_iteration_count_after_collision".into()],
        ),
        (
            {
                let mut r = base.clone();
                r.chains[3].target_framerate = 30.0;
                r
            },
            vec!["skirt_3".into(), "target_framerate".into()],
        ),
    ];
    for (rig, words) in cases {
        let e = error_of(&rig);
        for w in &words {
            assert!(e.contains(w.as_str()), "'{e}' does not name {w}");
        }
    }
    // An unknown preset name is a parse error that lists the presets.
    let text = "[[bone_constraint]]\nbone1 = \"a\"\nbone2 = \"b\"\ncompliance = \"steel\"\n";
    let e = RigSettings::from_toml_str(text).unwrap_err().to_string();
    assert!(e.contains("steel") && e.contains("leather"), "{e}");
}

#[test]
fn constrained_skirts_survive_hitches_teleports_and_step_per_character_in_crowds() {
    let sk = skeleton();
    for mode in [TimeMode::Fixed, TimeMode::Classic] {
        let mut r = rig(mode, Some(Compliance::Preset(CompliancePreset::Fat)), 1, 2);
        for c in &mut r.chains {
            c.teleport_distance = 1.0;
        }
        let mut sim = CharacterSim::new(sk.clone(), &r).unwrap();
        let rest = sk.rest().to_vec();
        let mut x = 0.0f32;
        for f in 0..120 {
            let dt = match f {
                0 => 0.0,
                40 => 0.5,
                41 => 0.0,
                _ => 1.0 / 60.0,
            };
            x += if f == 70 { 5.0 } else { 0.01 };
            sim.frame(
                &rest,
                Transform::from_translation(Vec3::new(x, 0.0, 0.0)),
                dt,
            )
            .unwrap();
            assert!(
                sim.pose().models.iter().all(|m| m.is_finite()),
                "{mode:?} frame {f}"
            );
        }
        assert!(
            sim.chain_state().teleport_count() >= 1,
            "{mode:?}: no teleport seen"
        );
        // After the teleport the skirt hangs near its pose again, not swinging from the
        // old place 5 m away.
        let tip = sk.find("skirt_0_3").unwrap();
        let d =
            (sim.pose().models[tip].translation - sim.animated_models()[tip].translation).length();
        assert!(
            d < 0.2,
            "{mode:?}: tip {d} m from its pose after the teleport"
        );

        // Crowds: such a rig runs per character (CharacterSim), not in a ChainCrowd.
        let rig = Arc::new(CharacterRig::new(sk.clone(), &r).unwrap());
        assert_eq!(CrowdKind::of(&rig), None);
        let chains = Arc::new(ChainRig::new(&sk, &r).unwrap());
        let e = ChainCrowd::new(Arc::new(sk.clone()), chains).unwrap_err();
        assert!(e.to_string().contains("bone constraints"), "{e}");
    }
}

/// Distance from `p` to the segment `a`–`b`.
fn to_segment(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    (p - (a + ab * t)).length()
}

#[test]
fn the_example_skirt_of_chains_runs_the_demo_on_the_builtin_character() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/rigs/skirt-chains.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let rig = RigSettings::from_toml_str(&text).unwrap();
    let c = tassel::builtin::character();
    let mut sim = CharacterSim::new(c.skeleton.clone(), &rig).unwrap();
    assert!(sim.chains().has_bone_constraints() && sim.chains().has_sync_bones());
    assert_eq!(sim.chains().chain_count(), 8);
    // The same skirt without its constraints (and sync bones), for comparison.
    let mut free_rig = rig.clone();
    free_rig.bone_constraints.clear();
    free_rig.sync_bones.clear();
    let mut free = CharacterSim::new(c.skeleton.clone(), &free_rig).unwrap();
    let script = tassel::builtin::DemoScript;
    let mut animator = script.animator(&c);
    let mut locals = c.skeleton.rest().to_vec();
    let sk = &c.skeleton;
    let pairs: Vec<(usize, usize)> = pairs()
        .iter()
        .map(|(a, b)| (sk.find(a).unwrap(), sk.find(b).unwrap()))
        .collect();
    let rest = tassel::Pose::rest(sk).models;
    let skirt: Vec<usize> = (0..sk.len())
        .filter(|&j| sk.name(j).starts_with("skirt_") && !sk.name(j).ends_with("_0"))
        .collect();
    let (mut strain, mut strain_free, mut n) = (0.0f64, 0.0f64, 0usize);
    let hz = 60.0f32;
    for f in 0..=(tassel::builtin::DemoScript::DURATION * hz) as usize {
        let t = f as f32 / hz;
        let dt = if f == 0 { 0.0 } else { 1.0 / hz };
        let m = script.at(t);
        script.pose(&c, &mut animator, &m, dt, &mut locals).unwrap();
        sim.frame(&locals, m.component, dt).unwrap();
        free.frame(&locals, m.component, dt).unwrap();
        let models = &sim.pose().models;
        assert!(models.iter().all(|m| m.is_finite()), "frame {f}");
        // No skirt joint inside a leg: each joint at least the capsule's radius from
        // its axis (less 1 mm of rounding), the capsules placed by hand from the
        // animated leg bones and the rig's offsets.
        let animated = sim.animated_models();
        for col in &rig.colliders {
            let tassel::collide::Shape::Capsule { radius, length } = col.shape else {
                unreachable!("the example's colliders are capsules");
            };
            let bone = animated[sk.find(&col.bone).unwrap()];
            let centre = bone.transform_point(col.offset);
            let axis = bone.rotation * Vec3::Y * (0.5 * length);
            for &j in &skirt {
                let d = to_segment(models[j].translation, centre - axis, centre + axis);
                assert!(
                    d >= radius - 1e-3,
                    "frame {f}: '{}' {:.1} mm inside '{}'",
                    sk.name(j),
                    1e3 * (radius - d),
                    col.name
                );
            }
        }
        for &(a, b) in &pairs {
            let was = (rest[a].translation - rest[b].translation).length();
            let d = |ms: &[Transform]| (ms[a].translation - ms[b].translation).length();
            strain += (d(models) - was).abs() as f64;
            strain_free += (d(&free.pose().models) - was).abs() as f64;
            n += 1;
        }
    }
    let (strain, strain_free) = (strain / n as f64, strain_free / n as f64);
    println!(
        "demo run: mean neighbour strain {:.2} mm with the constraints, {:.2} mm without",
        1e3 * strain,
        1e3 * strain_free
    );
    assert!(strain < strain_free, "{strain} vs {strain_free}");
}

#[test]
fn sync_bones_read_from_the_rig_file_and_bad_ones_are_named() {
    let text = r#"
[[chain]]
name = "front"
root = "skirt_0_0"
dummy_bone_length = 0.05

[[sync_bone]]
bone = "knee_l"
global_scale = [1.0, 0.5, 1.0]
scale_curve_by_delta_distance = [[0.0, 1.0], [0.4, 0.5]]
apply_direction_z = "positive"
apply_direction_x = "none"
enable_distance_attenuation = true
attenuation_inner_radius = 0.25
attenuation_outer_radius = 0.6
max_attenuation_rate = 0.7

[[sync_bone.target_root]]
bone = "skirt_0_0"
scale_curve_by_bone_length_rate = [[0.0, 0.4], [1.0, 1.0]]
"#;
    let rig = RigSettings::from_toml_str(text).unwrap();
    let s = &rig.sync_bones[0];
    assert_eq!(s.apply_direction_z, SyncDirection::Positive);
    assert_eq!(s.apply_direction_x, SyncDirection::None);
    assert_eq!(s.apply_direction_y, SyncDirection::Both);
    assert!(s.target_roots[0].include_child_bones);
    // Halfway between the keys 0.4 and 1.0 (f32 rounding aside).
    assert!((s.target_roots[0].scale_curve_by_bone_length_rate.eval(0.5) - 0.7).abs() < 1e-6);
    let again = RigSettings::from_toml_str(&rig.to_toml_string().unwrap()).unwrap();
    assert_eq!(again, rig);
    // A chain's root as the target root: the bones below it take the movement (the
    // root stays animated), so the chain's tip leaves its pose when the knee swings.
    let sk = skeleton();
    let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
    assert!(sim.chains().has_sync_bones());
    let tip = sk.find("skirt_0_3").unwrap();
    let mut moved = 0.0f32;
    for f in 0..60 {
        let t = f as f64 / 60.0;
        sim.frame(
            &locals_at(&sk, t),
            Transform::IDENTITY,
            if f == 0 { 0.0 } else { 1.0 / 60.0 },
        )
        .unwrap();
        moved = moved.max(
            sim.chain_state().target_positions()[3]
                .distance(sim.animated_models()[tip].translation),
        );
    }
    assert!(moved > 0.01, "the synced target moved {moved} m");
    let rig_of = |edit: &dyn Fn(&mut SyncBoneSettings)| {
        let mut r = rig.clone();
        edit(&mut r.sync_bones[0]);
        r
    };
    let cases: Vec<(RigSettings, &[&str])> = vec![
        (
            rig_of(&|s| s.bone = "nope".into()),
            &["sync_bone #1", "nope"],
        ),
        (
            rig_of(&|s| s.target_roots[0].bone = "hips".into()),
            &["sync_bone #1", "hips", "no chain"],
        ),
        (
            rig_of(&|s| s.global_scale = Vec3::new(1.5, 1.0, 1.0)),
            &["sync_bone #1", "global_scale"],
        ),
        (
            rig_of(&|s| s.attenuation_outer_radius = -1.0),
            &["sync_bone #1", "attenuation_outer_radius"],
        ),
        (
            rig_of(&|s| s.max_attenuation_rate = f32::NAN),
            &["sync_bone #1", "max_attenuation_rate"],
        ),
        (
            rig_of(&|s| s.target_roots.clear()),
            &["sync_bone #1", "target_root"],
        ),
        (
            rig_of(&|s| s.scale_curve_by_delta_distance = Curve::new(vec![[1.0, 1.0], [0.0, 1.0]])),
            &["sync_bone #1", "scale_curve_by_delta_distance"],
        ),
    ];
    for (r, words) in cases {
        let e = match RigSettings::from_toml_str(&r.to_toml_string().unwrap()) {
            Err(e) => e.to_string(),
            Ok(_) => CharacterSim::new(sk.clone(), &r).unwrap_err().to_string(),
        };
        for w in words {
            assert!(e.contains(w), "'{e}' does not name {w}");
        }
    }
    // Crowds step such characters one by one.
    let rig = Arc::new(CharacterRig::new(sk.clone(), &rig).unwrap());
    assert_eq!(CrowdKind::of(&rig), None);
}
