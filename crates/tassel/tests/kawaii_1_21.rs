//! `kawaii` mode against KawaiiPhysics 1.21's fixed substepping: an independent port, in
//! f64 and in this file, of `FAnimNode_KawaiiPhysics::SimulateModifyBones` with
//! `bUseFixedSubstepping` (1.21's default; source read at the plugin's `20260624-v1.21.0`
//! tag: `AnimNode_KawaiiPhysicsSimulation.cpp`, `UpdateSkelCompMove` and the end of
//! `EvaluateSkeletalControl_AnyThread` in `AnimNode_KawaiiPhysics.cpp`).
//!
//! Its clock is KawaiiPhysics' own f32 arithmetic (the step `1.0f / TargetFramerate`, the
//! accumulator `max(acc + dt, KINDA_SMALL_NUMBER)` capped at `MaxSubsteps` steps, the whole
//! steps taken, `MoveFrac = step / elapsed`, the consumed fraction); the physics is f64
//! (UE5's FVector). Each substep: the pose lerped from last frame's to this frame's at
//! `k / n`, the root on it; per bone the velocity over the last step, damping, gravity as
//! an acceleration (`v += g·dt`), `x += v·dt`, the share of the character's move and turn
//! as inertia, the pull with exponent `TargetFramerate · dt`; then (1.20's phase order)
//! every bone's length restored from the root down. `PreSkelCompTransform` advances by
//! the consumed fraction. No wind, colliders or limits.
//!
//! A 6-bone hair chain under a head, 120 frames at 30, 60 and 144 Hz (and a hitch), the
//! character still, swaying, stepped and turning, and the head nodding (the pose itself
//! moving, so the substeps' pose interpolation shows): Tassel's written joints agree with
//! the port to 2e-5 m, or within twice what f32 rounding alone does to the same update.

use glam::{DQuat, DVec3, Quat, Vec3};
use tassel::dynamics::chain::{ClassicGravity, TimeMode};
use tassel::dynamics::RigSettings;
use tassel::{CharacterSim, Transform};

mod common;
use common::hair::{component, pose, skeleton, BONES};
use common::kawaii::{
    DAMPING, GRAVITY, STIFFNESS, TARGET_FPS, WORLD_DAMPING_LOCATION, WORLD_DAMPING_ROTATION,
};

const MAX_SUBSTEPS: u32 = 4;

/// The head's nod: the root bone turns about +X by this much at `t` (the rest pose is
/// the hair's pose turned about the root point).
fn nod(motion: &str, t: f64) -> f64 {
    if motion == "nod" {
        0.5 * (std::f64::consts::TAU * 0.8 * t).sin()
    } else {
        0.0
    }
}

/// The pose (component space, f64) with the root turned by `angle` about +X.
fn pose_at(angle: f64) -> Vec<DVec3> {
    let p = pose();
    let turn = DQuat::from_rotation_x(angle);
    p.iter().map(|&x| p[0] + turn * (x - p[0])).collect()
}

macro_rules! kawaii_121 {
    ($name:ident, $f:ty, $v:ty, $q:ty, $to_v:expr, $to_q:expr) => {
        struct $name {
            location: Vec<$v>,
            prev_location: Vec<$v>,
            prev_pose: Vec<$v>,
            dt_old: $f,
            pre_comp: ($v, $q),
            accumulator: f32,
            /// Damping, stiffness, world damping location and rotation (KawaiiPhysics'
            /// floats), as this frame's `UpdatePhysicsSettingsOfModifyBones` set them.
            settings: [f32; 4],
        }

        impl $name {
            fn new() -> Self {
                let p: Vec<$v> = pose().into_iter().map($to_v).collect();
                Self {
                    location: p.clone(),
                    prev_location: p.clone(),
                    prev_pose: p,
                    dt_old: 1.0 / TARGET_FPS as $f,
                    pre_comp: (<$v>::ZERO, <$q>::IDENTITY),
                    accumulator: 0.0,
                    settings: [
                        DAMPING as f32,
                        STIFFNESS as f32,
                        WORLD_DAMPING_LOCATION as f32,
                        WORLD_DAMPING_ROTATION as f32,
                    ],
                }
            }

            fn frame(&mut self, comp: (DVec3, DQuat), pose_now: Vec<DVec3>, frame_dt: f32) {
                let comp: ($v, $q) = (($to_v)(comp.0), ($to_q)(comp.1));
                let pose_now: Vec<$v> = pose_now.into_iter().map($to_v).collect();
                // The clock, in KawaiiPhysics' f32.
                let fixed_dt: f32 = 1.0f32 / TARGET_FPS as f32;
                let raw = (self.accumulator + frame_dt).max(1.0e-4);
                let mut acc = raw.min(MAX_SUBSTEPS as f32 * fixed_dt);
                let dropped = raw - acc;
                let steps = (acc / fixed_dt).floor() as i32;
                acc -= steps as f32 * fixed_dt;
                self.accumulator = acc;
                let move_frac = (fixed_dt / raw) as $f;
                let consume = ((steps as f32 * fixed_dt + dropped) / raw).clamp(0.0, 1.0);
                // UpdateSkelCompMove: from PreSkelCompTransform to this frame's.
                let inv = comp.1.inverse();
                let move_vector = inv * (self.pre_comp.0 - comp.0);
                let move_rotation = inv * self.pre_comp.1;
                let h = fixed_dt as $f;
                let exponent = (TARGET_FPS as f32 * fixed_dt) as $f;
                let gravity_cs = inv * ($to_v)(DVec3::from(GRAVITY));
                let [damping, stiffness, wd_location, wd_rotation] = self.settings.map(|x| x as $f);
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
                    for i in 1..=BONES {
                        let parent = i - 1;
                        let mut velocity =
                            (self.location[i] - self.prev_location[i]) / self.dt_old.max(1.0e-4);
                        self.prev_location[i] = self.location[i];
                        velocity *= 1.0 - damping;
                        velocity += gravity_cs * h;
                        self.location[i] += velocity * h;
                        self.location[i] += sub_move * (1.0 - wd_location);
                        self.location[i] += (sub_rotation * self.prev_location[i]
                            - self.prev_location[i])
                            * (1.0 - wd_rotation);
                        let base = self.location[parent] + (target[i] - target[parent]);
                        let pull =
                            (base - self.location[i]) * (1.0 - (1.0 - stiffness).powf(exponent));
                        self.location[i] += pull;
                    }
                    for i in 1..=BONES {
                        let parent = i - 1;
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

kawaii_121!(Kawaii121, f64, DVec3, DQuat, |v: DVec3| v, |q: DQuat| q);
kawaii_121!(
    Kawaii121f32,
    f32,
    Vec3,
    Quat,
    |v: DVec3| v.as_vec3(),
    |q: DQuat| q.as_quat()
);

/// The hair's animated locals for a nod of `angle`: the root bone turned.
fn locals(rest: &[Transform], angle: f64) -> Vec<Transform> {
    let mut l = rest.to_vec();
    l[0].rotation = DQuat::from_rotation_x(angle).as_quat();
    l
}

fn kawaii_rig() -> RigSettings {
    let mut chain = common::kawaii::hair_chain(TimeMode::Kawaii, ClassicGravity::PerFrame);
    chain.max_substeps = MAX_SUBSTEPS;
    RigSettings {
        chains: vec![chain],
        ..Default::default()
    }
}

#[test]
fn kawaii_matches_kawaiiphysics_1_21_fixed_substepping() {
    let sk = skeleton();
    let rig = kawaii_rig();
    let mut worst_all = 0.0f64;
    for motion in ["still", "sway", "step", "turn", "nod"] {
        for (label, hz) in [
            ("30", 30.0f64),
            ("60", 60.0),
            ("144", 144.0),
            ("hitch", 60.0),
        ] {
            let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
            let mut kp = Kawaii121::new();
            let mut kp32 = Kawaii121f32::new();
            let rest = sk.rest().to_vec();
            // Frame 0 places both on the pose (Tassel: dt = 0; KawaiiPhysics: init).
            sim.frame(&rest, Transform::IDENTITY, 0.0).unwrap();
            let (mut worst, mut rounding, mut swing) = (0.0f64, 0.0f64, 0.0f64);
            let mut t = 0.0f64;
            for f in 1..=120 {
                // The hitch: a 0.25 s frame (more than 4 substeps: time is dropped).
                let dt = if label == "hitch" && f == 50 {
                    0.25
                } else {
                    1.0 / hz
                };
                t += dt;
                let (pos, rot) = component(if motion == "nod" { "still" } else { motion }, t);
                let angle = nod(motion, t);
                let dt32 = dt as f32;
                kp.frame((pos, rot), pose_at(angle), dt32);
                kp32.frame((pos, rot), pose_at(angle), dt32);
                let comp = Transform::from_translation_rotation(pos.as_vec3(), rot.as_quat());
                sim.frame(&locals(&rest, angle), comp, dt32).unwrap();
                let animated = pose_at(angle);
                for j in 1..=BONES {
                    let got = sim.pose().models[j].translation.as_dvec3();
                    worst = worst.max((got - kp.joint(j)).length());
                    rounding = rounding.max((kp32.joint(j) - kp.joint(j)).length());
                    swing = swing.max((kp.joint(j) - animated[j]).length());
                }
            }
            println!(
                "{motion} {label} Hz: Tassel vs KawaiiPhysics 1.21 (f64) {worst:.2e} m; \
                 its f32 vs f64 {rounding:.2e} m; the hair swings {swing:.3} m off the pose"
            );
            assert!(swing > 1e-3, "{motion} {label}: nothing moved");
            assert!(
                worst <= 2e-5_f64.max(2.0 * rounding),
                "{motion} {label} Hz: {worst} m (f32 rounding alone: {rounding} m)"
            );
            worst_all = worst_all.max(worst);
        }
    }
    println!("worst over every case: {worst_all:.2e} m");
}

/// The mode and its key in a rig file: `mode = "kawaii"` and `max_substeps` read, a
/// count out of 1..=16 refused with the chain and the key named; `--mode kawaii` sets
/// every chain; such chains step per character (not in crowd lanes).
#[test]
fn kawaii_keys_are_read_and_checked() {
    let ok =
        "[[chain]]\nname = \"hair\"\nroot = \"hair_0\"\nmode = \"kawaii\"\nmax_substeps = 16\n";
    let rig = RigSettings::from_toml_str(ok).unwrap();
    assert_eq!(rig.chains[0].mode, TimeMode::Kawaii);
    assert_eq!(rig.chains[0].max_substeps, 16);
    for bad in [0u32, 17] {
        let text = ok.replace("max_substeps = 16", &format!("max_substeps = {bad}"));
        let e = RigSettings::from_toml_str(&text).unwrap_err().to_string();
        assert!(e.contains("'hair'") && e.contains("max_substeps"), "{e}");
    }
    // Unset, the key is 4 (KawaiiPhysics' MaxSubsteps) and the file written back omits it.
    let plain = RigSettings::from_toml_str("[[chain]]\nroot = \"hair_0\"\n").unwrap();
    assert_eq!(plain.chains[0].max_substeps, 4);
    assert!(!plain.to_toml_string().unwrap().contains("max_substeps"));
    let mut asked = plain.clone();
    let (mode, _) = tassel::dynamics::SimMode::apply(
        Some(tassel::dynamics::SimMode::Kawaii),
        &mut asked,
        false,
    )
    .unwrap();
    assert_eq!(mode.name(), "kawaii");
    assert_eq!(asked.chains[0].mode, TimeMode::Kawaii);
    let sim = CharacterSim::new(skeleton(), &rig).unwrap();
    assert!(sim.rig().chains().needs_per_character());
    let sim = CharacterSim::new(skeleton(), &plain).unwrap();
    assert!(!sim.rig().chains().needs_per_character());
}

/// `max_substeps` caps a frame: after a 0.5 s hitch with 2 substeps allowed, the hair
/// (hanging under gravity, the character still) is where two 1/60 s frames put it: two
/// steps, the rest of the hitch dropped, nothing carried to the next frame.
#[test]
fn a_hitch_beyond_max_substeps_drops_the_time() {
    let sk = skeleton();
    let mut chain = common::kawaii::hair_chain(TimeMode::Kawaii, ClassicGravity::PerFrame);
    chain.max_substeps = 2;
    let rig = RigSettings {
        chains: vec![chain],
        ..Default::default()
    };
    let rest = sk.rest().to_vec();
    let run = |frames: &[f32]| {
        let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
        sim.frame(&rest, Transform::IDENTITY, 0.0).unwrap();
        for &dt in frames {
            sim.frame(&rest, Transform::IDENTITY, dt).unwrap();
        }
        sim.pose().models[BONES].translation
    };
    let hitch = run(&[0.5, 1.0 / 60.0]);
    let two = run(&[1.0 / 60.0, 1.0 / 60.0, 1.0 / 60.0]);
    assert!(
        (hitch - two).length() < 1e-6,
        "a 0.5 s frame then one: {hitch}; three frames of a step: {two}"
    );
    // And a frame shorter than a step moves nothing yet.
    let none = run(&[0.25 / 60.0]);
    let before = CharacterSim::new(sk.clone(), &rig).map(|mut s| {
        s.frame(&rest, Transform::IDENTITY, 0.0).unwrap();
        s.pose().models[BONES].translation
    });
    assert_eq!(none, before.unwrap());
}

/// KawaiiPhysics' timed settings overrides (its master branch after 1.21, read at
/// `fb90c52`): `ResolveWindBlowEnvelope`, `EvaluateEnvelopeAlpha01`,
/// `RequestPhysicsSettingsOverride` / `RequestStopPhysicsSettingsOverride`,
/// `ConsumeAndAdvancePhysicsSettingsOverrides` and
/// `ComputeEffectivePhysicsSettingsOverrideScale`, in its f32; scales in the order damping,
/// stiffness, world damping location, world damping rotation, radius, limit angle.
mod kp_override {
    const KINDA_SMALL_NUMBER: f32 = 1e-4;
    const MAX: usize = 8;

    pub fn envelope(duration: f32, rise: f32, decay: f32) -> (f32, f32, f32) {
        if duration <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let (rise, decay) = (rise.max(0.0), decay.max(0.0));
        let edge = rise + decay;
        if edge > duration && edge > 0.0 {
            let scale = duration / edge;
            return (rise * scale, 0.0, decay * scale);
        }
        (rise, (duration - edge).max(0.0), decay)
    }

    pub fn alpha01(rise: f32, hold: f32, decay: f32, elapsed: f32) -> f32 {
        if elapsed < 0.0 {
            return 0.0;
        }
        let (rise, hold, decay) = (rise.max(0.0), hold.max(0.0), decay.max(0.0));
        if rise > KINDA_SMALL_NUMBER && elapsed < rise {
            return elapsed / rise;
        }
        if elapsed < rise + hold {
            return 1.0;
        }
        if decay <= KINDA_SMALL_NUMBER {
            return 0.0;
        }
        let d = elapsed - rise - hold;
        if d < decay {
            return 1.0 - d / decay;
        }
        0.0
    }

    #[derive(Clone, Copy)]
    struct Item {
        scale: [f32; 6],
        rise: f32,
        hold: f32,
        decay: f32,
        elapsed: f32,
        peak: f32,
        handle: i64,
    }

    #[derive(Default)]
    pub struct Node {
        items: Vec<Item>,
        pending: Vec<Item>,
        stops: Vec<(i64, f32)>,
    }

    impl Node {
        pub fn start(
            &mut self,
            scale: [f32; 6],
            duration: f32,
            blend_in: f32,
            blend_out: f32,
            handle: i64,
        ) {
            let (rise, hold, decay) = envelope(duration, blend_in, blend_out);
            if self.pending.len() >= MAX {
                self.pending.remove(0);
            }
            self.pending.push(Item {
                scale,
                rise,
                hold,
                decay,
                elapsed: 0.0,
                peak: 1.0,
                handle,
            });
        }

        pub fn stop(&mut self, handle: i64, blend_out: f32) {
            if let Some(s) = self.stops.iter_mut().find(|s| s.0 == handle) {
                s.1 = blend_out;
                return;
            }
            self.stops.push((handle, blend_out));
        }

        pub fn consume(&mut self, dt: f32) {
            for i in &mut self.items {
                i.elapsed += dt;
            }
            self.items.append(&mut self.pending);
            for (h, out) in std::mem::take(&mut self.stops) {
                let mut k = self.items.len();
                while k > 0 {
                    k -= 1;
                    if self.items[k].handle != h {
                        continue;
                    }
                    if out <= KINDA_SMALL_NUMBER {
                        self.items.remove(k);
                        continue;
                    }
                    let it = &mut self.items[k];
                    it.peak *= alpha01(it.rise, it.hold, it.decay, it.elapsed);
                    it.rise = 0.0;
                    it.hold = 0.0;
                    it.decay = out;
                    it.elapsed = 0.0;
                }
            }
            let mut k = self.items.len();
            while k > 0 {
                k -= 1;
                let it = self.items[k];
                if it.elapsed >= it.rise + it.hold + it.decay {
                    self.items.remove(k);
                }
            }
            while self.items.len() > MAX {
                self.items.remove(0);
            }
        }

        pub fn effective(&self) -> [f32; 6] {
            let mut e = [1.0f32; 6];
            for it in &self.items {
                let a = it.peak * alpha01(it.rise, it.hold, it.decay, it.elapsed);
                for (x, s) in e.iter_mut().zip(it.scale) {
                    *x *= 1.0 + a * (s - 1.0);
                }
            }
            e
        }
    }
}

/// The overrides of the settings test: at 0.3 s a 0.8 s override (0.3 s in, 0.4 s out) of
/// every setting the hair uses; at 0.9 s one of the chain until stopped (0.2 s in; the two
/// multiply while both act); at 1.6 s that one stopped with 0.3 s out.
const OVERRIDE_A: [f32; 6] = [0.3, 4.0, 0.5, 0.2, 1.0, 1.0];
const OVERRIDE_B: [f32; 6] = [3.0, 0.5, 1.2, 1.1, 1.0, 1.0];

/// `kawaii` mode with timed settings overrides against the f64 port of 1.21's update, its
/// settings each frame from the f32 port of KawaiiPhysics' override bookkeeping: the
/// scales equal to the bit, the joints within 2e-5 m (or twice the f32 rounding), at 30,
/// 60 and 144 Hz; and the overrides move the hair (against the same run without them).
#[test]
fn kawaii_settings_overrides_match_kawaiiphysics() {
    use tassel::dynamics::chain::{OverrideTiming, SettingsScale};
    let sk = skeleton();
    let rig = kawaii_rig();
    for hz in [30u32, 60, 144] {
        for motion in ["sway", "turn"] {
            let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
            let mut plain = CharacterSim::new(sk.clone(), &rig).unwrap();
            let mut kp = Kawaii121::new();
            let mut kp32 = Kawaii121f32::new();
            let mut node = kp_override::Node::default();
            let rest = sk.rest().to_vec();
            sim.frame(&rest, Transform::IDENTITY, 0.0).unwrap();
            plain.frame(&rest, Transform::IDENTITY, 0.0).unwrap();
            let (mut worst, mut rounding, mut effect) = (0.0f64, 0.0f64, 0.0f64);
            let mut handle_b = None;
            let mut seen = [false; 2];
            for f in 1..=(2.4 * hz as f64) as u32 {
                // Requests made before frame `f`, between frames.
                if f == (0.3 * hz as f64).round() as u32 {
                    let s = SettingsScale::from_array(OVERRIDE_A);
                    let t = OverrideTiming {
                        duration: 0.8,
                        blend_in: 0.3,
                        blend_out: 0.4,
                    };
                    sim.start_settings_override(s, t, None, None).unwrap();
                    node.start(OVERRIDE_A, 0.8, 0.3, 0.4, 1);
                }
                if f == (0.9 * hz as f64).round() as u32 {
                    let s = SettingsScale::from_array(OVERRIDE_B);
                    let t = OverrideTiming {
                        duration: f32::INFINITY,
                        blend_in: 0.2,
                        blend_out: 0.5,
                    };
                    handle_b = Some(
                        sim.start_settings_override(s, t, Some("hair"), None)
                            .unwrap(),
                    );
                    node.start(OVERRIDE_B, f32::INFINITY, 0.2, 0.5, 2);
                }
                if f == (1.6 * hz as f64).round() as u32 {
                    assert!(sim.stop_settings_override(handle_b.unwrap(), 0.3));
                    node.stop(2, 0.3);
                }
                let dt = 1.0 / hz as f64;
                let t = f as f64 * dt;
                let (pos, rot) = component(motion, t);
                let dt32 = dt as f32;
                node.consume(dt32);
                let e = node.effective();
                let settings = [
                    (DAMPING as f32 * e[0]).clamp(0.0, 1.0),
                    (STIFFNESS as f32 * e[1]).clamp(0.0, 1.0),
                    (WORLD_DAMPING_LOCATION as f32 * e[2]).clamp(0.0, 1.0),
                    (WORLD_DAMPING_ROTATION as f32 * e[3]).clamp(0.0, 1.0),
                ];
                kp.settings = settings;
                kp32.settings = settings;
                kp.frame((pos, rot), pose_at(0.0), dt32);
                kp32.frame((pos, rot), pose_at(0.0), dt32);
                let comp = Transform::from_translation_rotation(pos.as_vec3(), rot.as_quat());
                sim.frame(&rest, comp, dt32).unwrap();
                plain.frame(&rest, comp, dt32).unwrap();
                let got = sim.settings_scale("hair").unwrap().to_array();
                assert_eq!(got, e, "{hz} Hz frame {f}: the scales");
                seen[0] |= e[1] > 3.9;
                seen[1] |= e[0] > 2.9;
                for j in 1..=BONES {
                    let x = sim.pose().models[j].translation.as_dvec3();
                    worst = worst.max((x - kp.joint(j)).length());
                    rounding = rounding.max((kp32.joint(j) - kp.joint(j)).length());
                    let y = plain.pose().models[j].translation.as_dvec3();
                    effect = effect.max((x - y).length());
                }
            }
            println!(
                "{motion} {hz} Hz with overrides: Tassel vs the port {worst:.2e} m (f32 \
                 rounding {rounding:.2e} m); the overrides move the hair up to {:.1} mm",
                1e3 * effect
            );
            assert!(
                seen[0] && seen[1],
                "{hz} Hz: each override reached its full scale"
            );
            assert!(
                effect > 5e-3,
                "{hz} Hz: the overrides moved the hair {effect} m"
            );
            assert!(
                worst <= 2e-5_f64.max(2.0 * rounding),
                "{motion} {hz} Hz: {worst} m (f32 rounding alone: {rounding} m)"
            );
        }
    }
}
