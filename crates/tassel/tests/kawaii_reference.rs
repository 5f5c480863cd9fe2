//! `classic` against KawaiiPhysics 1.10 itself: an independent port, in f64 and in this
//! file, of `FAnimNode_KawaiiPhysics::SimulateModifyBones` as 1.10 ships it (the version
//! seed 000 quotes; its source read from the plugin's `20221203-v1.10.0` tag): per bone
//! in order, Verlet velocity over the previous frame's dt with damping, the component's
//! own move and turn as inertia scaled by (1 − world damping), gravity (1.10's default
//! `½·g·dt²`, or `g·dt` with the old-physics console variable), the pull toward the pose
//! relative to the already-updated parent with the `TargetFramerate · dt` exponent, then
//! the bone length restored. No wind, colliders or limits here: with those the documented
//! differences apply (docs/rig.md).
//!
//! A 6-bone hair chain under a head, 120 frames at 30, 60 and 144 Hz, the character
//! still, swaying, stepped and turning: the joints of Tassel's written pose agree with the
//! port to 2e-5 m.

use glam::{DQuat, DVec3, Quat, Vec3};
use tassel::dynamics::chain::{ClassicGravity, TimeMode};
use tassel::dynamics::RigSettings;
use tassel::{CharacterSim, Transform};

mod common;
use common::hair::{component, pose, skeleton, BONES};

use common::kawaii::{
    DAMPING, GRAVITY, STIFFNESS, TARGET_FPS, WORLD_DAMPING_LOCATION, WORLD_DAMPING_ROTATION,
};

/// KawaiiPhysics 1.10's `SimulateModifyBones`, component space, in a float type of
/// choice: `Kawaii` in f64 (UE5's FVector is double: the reference), `Kawaii32` in f32
/// (how far rounding alone moves the same update, for scale).
macro_rules! kawaii {
    ($name:ident, $f:ty, $v:ty, $q:ty, $to_v:expr, $to_q:expr) => {
        struct $name {
            location: Vec<$v>,
            prev_location: Vec<$v>,
            dt_old: $f,
            prev_comp: ($v, $q),
            old_gravity: bool,
        }

        impl $name {
            fn new(old_gravity: bool) -> Self {
                let p: Vec<$v> = pose().into_iter().map($to_v).collect();
                Self {
                    location: p.clone(),
                    prev_location: p,
                    dt_old: 1.0 / TARGET_FPS as $f,
                    prev_comp: (<$v>::ZERO, <$q>::IDENTITY),
                    old_gravity,
                }
            }

            fn frame(&mut self, comp: (DVec3, DQuat), dt: f64) {
                let comp: ($v, $q) = (($to_v)(comp.0), ($to_q)(comp.1));
                let dt = dt as $f;
                let pose: Vec<$v> = pose().into_iter().map($to_v).collect();
                let inv = comp.1.inverse();
                // SkelCompMoveVector = Comp⁻¹(PrevComp.location); SkelCompMoveRotation =
                // Comp⁻¹.rotation · PrevComp.rotation (teleport thresholds not reached).
                let move_vector = inv * (self.prev_comp.0 - comp.0);
                let move_rotation = inv * self.prev_comp.1;
                self.prev_comp = comp;
                let exponent = TARGET_FPS as $f * dt;
                let gravity_cs = inv * ($to_v)(DVec3::from(GRAVITY));
                for i in 0..=BONES {
                    if i == 0 {
                        self.prev_location[0] = self.location[0];
                        self.location[0] = pose[0];
                        continue;
                    }
                    let parent = i - 1;
                    let mut velocity = (self.location[i] - self.prev_location[i]) / self.dt_old;
                    self.prev_location[i] = self.location[i];
                    velocity *= 1.0 - DAMPING as $f;
                    self.location[i] += velocity * dt;
                    self.location[i] += move_vector * (1.0 - WORLD_DAMPING_LOCATION as $f);
                    self.location[i] += (move_rotation * self.prev_location[i]
                        - self.prev_location[i])
                        * (1.0 - WORLD_DAMPING_ROTATION as $f);
                    if self.old_gravity {
                        self.location[i] += gravity_cs * dt;
                    } else {
                        self.location[i] += 0.5 * gravity_cs * dt * dt;
                    }
                    let base = self.location[parent] + (pose[i] - pose[parent]);
                    let pull =
                        (base - self.location[i]) * (1.0 - (1.0 - STIFFNESS as $f).powf(exponent));
                    self.location[i] += pull;
                    let length = (pose[i] - pose[parent]).length();
                    self.location[i] =
                        (self.location[i] - self.location[parent]).normalize_or_zero() * length
                            + self.location[parent];
                }
                self.dt_old = dt;
            }

            fn joint(&self, j: usize) -> DVec3 {
                DVec3::new(
                    self.location[j].x as f64,
                    self.location[j].y as f64,
                    self.location[j].z as f64,
                )
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

#[test]
fn classic_matches_kawaiiphysics_1_10_without_contacts() {
    let sk = skeleton();
    let mut worst_all = 0.0f64;
    for (gravity, old) in [
        (ClassicGravity::HalfDtSquared, false),
        (ClassicGravity::PerFrame, true),
    ] {
        let rig = RigSettings {
            chains: vec![common::kawaii::hair_chain(TimeMode::Classic, gravity)],
            ..Default::default()
        };
        for motion in ["still", "sway", "step", "turn"] {
            for hz in [30.0f64, 60.0, 144.0] {
                let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
                let mut kp = Kawaii::new(old);
                let mut kp32 = Kawaii32::new(old);
                let rest = sk.rest().to_vec();
                // Frame 0 places both on the pose (Tassel: dt = 0; KawaiiPhysics: init).
                sim.frame(&rest, Transform::IDENTITY, 0.0).unwrap();
                let (mut worst, mut rounding) = (0.0f64, 0.0f64);
                for f in 1..=120 {
                    let t = f as f64 / hz;
                    let (pos, rot) = component(motion, t);
                    kp.frame((pos, rot), 1.0 / hz);
                    kp32.frame((pos, rot), 1.0 / hz);
                    let comp = Transform::from_translation_rotation(pos.as_vec3(), rot.as_quat());
                    sim.frame(&rest, comp, (1.0 / hz) as f32).unwrap();
                    for j in 1..=BONES {
                        let got = sim.pose().models[j].translation.as_dvec3();
                        worst = worst.max((got - kp.joint(j)).length());
                        rounding = rounding.max((kp32.joint(j) - kp.joint(j)).length());
                    }
                }
                println!(
                    "{gravity:?} {motion} {hz} Hz: Tassel vs KawaiiPhysics (f64) {worst:.2e} m; \
                     KawaiiPhysics f32 vs f64 {rounding:.2e} m"
                );
                // 2e-5 m, or — where the update itself is that sensitive to rounding
                // (½·g·dt² leaves the hair nearly weightless) — within twice what f32
                // rounding alone does to KawaiiPhysics' own update.
                assert!(
                    worst <= 2e-5_f64.max(2.0 * rounding),
                    "{gravity:?} {motion} {hz} Hz: {worst} m (f32 rounding alone: {rounding} m)"
                );
                worst_all = worst_all.max(worst);
            }
        }
    }
    println!("worst over every case: {worst_all:.2e} m");
}
