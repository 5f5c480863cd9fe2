//! Tapered capsules (KawaiiPhysics master's `FTaperedCapsuleLimit`, issue 62) in every
//! solver that uses rig colliders: no point ends a frame inside one, at 30, 60, 144 and
//! 200 Hz, with the character shaken so the shapes move fast against the points; a rig
//! file names them and their bad values are refused by name. (Against KawaiiPhysics'
//! rule itself: `kawaii_contacts.rs`, the f64 port; the crowds and lanes against the
//! single path: `chain_crowd.rs`, `chain_lanes.rs`.)

mod common;

use glam::{Quat, Vec3};
use tassel::builtin::{self, DemoScript};
use tassel::collide::Shape;
use tassel::dynamics::chain::{ChainSettings, TimeMode};
use tassel::dynamics::{ColliderSettings, RigSettings};
use tassel::{CharacterSim, Transform};

const RATES: [f32; 4] = [30.0, 60.0, 144.0, 200.0];

/// A chain of six bones hanging from the anchor, and a tapered capsule (wide end up,
/// tilted) below the anchor that the chain drapes over.
fn rig(mode: TimeMode) -> RigSettings {
    RigSettings {
        chains: vec![ChainSettings {
            name: "hair".into(),
            root: "anchor".into(),
            mode,
            damping: 0.05,
            stiffness: 0.05,
            radius: 0.02,
            gravity: Vec3::new(0.0, -4.0, 0.0),
            ..Default::default()
        }],
        colliders: vec![ColliderSettings {
            mirror: None,
            mirror_bone: String::new(),
            name: "cone".into(),
            bone: "anchor".into(),
            offset: Vec3::new(0.05, -0.3, 0.0),
            rotation: Quat::from_rotation_z(0.7),
            shape: Shape::TaperedCapsule {
                radius0: 0.12,
                radius1: 0.03,
                length: 0.3,
            },
        }],
        ..Default::default()
    }
}

#[test]
fn chains_never_end_a_frame_inside_a_fast_tapered_capsule() {
    for mode in [TimeMode::Fixed, TimeMode::Classic, TimeMode::Kawaii] {
        for hz in RATES {
            let sk = common::line(6, 0.08, Vec3::new(0.3, -1.0, 0.1).normalize(), Vec3::ZERO);
            let mut sim = CharacterSim::new(sk.clone(), &rig(mode)).unwrap();
            let rest = sk.rest().to_vec();
            let (mut worst, mut touching) = (f32::MIN, 0);
            let frames = (4.0 * hz) as usize;
            for f in 0..frames {
                // Shaken hard: the shape, fixed to the character, sweeps through the
                // lagging chain at up to 3 m/s.
                let t = f as f32 / hz;
                let comp = Transform::from_translation_rotation(
                    Vec3::new(0.3 * (9.0 * t).sin(), 0.2 * (7.0 * t).cos(), 0.0),
                    Quat::from_rotation_z(0.3 * (5.0 * t).sin()),
                );
                let dt = if f == 0 { 0.0 } else { 1.0 / hz };
                sim.frame(&rest, comp, dt).unwrap();
                let state = sim.chain_state();
                let placed = state.placed_colliders();
                assert!(matches!(placed[0].shape, Shape::TaperedCapsule { .. }));
                for (p, &x) in state.output_positions().iter().enumerate().skip(1) {
                    assert!(x.is_finite(), "{mode:?} {hz} Hz frame {f}: point {p} {x}");
                    let d = placed[0].penetration(x, sim.chains().point_radius(p));
                    worst = worst.max(d);
                    touching += usize::from(d > -1e-3);
                }
            }
            assert!(
                worst <= 1e-4,
                "{mode:?} {hz} Hz: a point ended a frame {worst} m inside the tapered capsule"
            );
            assert!(
                touching > frames / 4,
                "{mode:?} {hz} Hz: the chain touched the shape on {touching} point-frames"
            );
        }
    }
}

/// The built-in character with its leg capsules tapered (each 1.3× as wide at its +Y
/// end, 0.8× at its −Y end) through the demo: the skirt's cloth points, and the charm's
/// rope points (which collide with the left thigh), stay out of them at every rate.
#[test]
fn the_skirt_stays_out_of_tapered_legs_at_every_rate() {
    let mut c = builtin::character();
    let mut tapered = 0;
    for col in &mut c.rig.colliders {
        if let Shape::Capsule { radius, length } = col.shape {
            col.shape = Shape::TaperedCapsule {
                radius0: 1.3 * radius,
                radius1: 0.8 * radius,
                length,
            };
            tapered += 1;
        }
    }
    assert!(tapered >= 4, "the legs are capsules");
    let legs: Vec<usize> = ["thigh_l", "thigh_r", "shin_l", "shin_r"]
        .iter()
        .map(|n| {
            c.rig
                .colliders
                .iter()
                .position(|col| col.name == *n)
                .unwrap()
        })
        .collect();
    let sk = &c.skeleton;
    let script = DemoScript;
    for hz in RATES {
        let mut sim = CharacterSim::new(sk.clone(), &c.rig).unwrap();
        let mut animator = script.animator(&c);
        let mut locals = sk.rest().to_vec();
        let dt = 1.0 / hz;
        let frames = (DemoScript::DURATION * hz).round() as usize;
        let (mut worst, mut near) = (f32::MIN, 0usize);
        let (mut worst_rope, mut near_rope) = (f32::MIN, 0usize);
        let thigh = c
            .rig
            .colliders
            .iter()
            .position(|col| col.name == "thigh_l")
            .unwrap();
        assert!(c.rig.ropes[0].colliders.contains(&"thigh_l".to_string()));
        for f in 0..=frames {
            let m = script.at(f as f32 * dt);
            let step = if f == 0 { 0.0 } else { dt };
            script
                .pose(&c, &mut animator, &m, step, &mut locals)
                .unwrap();
            sim.frame(&locals, m.component, step).unwrap();
            let cloth = sim.cloth_state();
            let placed = cloth.placed_colliders();
            for &li in &legs {
                assert!(matches!(placed[li].shape, Shape::TaperedCapsule { .. }));
                for &p in cloth.world_positions() {
                    assert!(p.is_finite());
                    let d = placed[li].penetration(p, 0.0);
                    worst = worst.max(d);
                    near += usize::from(d > -0.03);
                }
            }
            for &p in &sim.ropes().output_positions(0)[1..] {
                assert!(p.is_finite());
                let d = placed[thigh].penetration(p, 0.0);
                worst_rope = worst_rope.max(d);
                near_rope += usize::from(d > -0.03);
            }
        }
        println!(
            "{hz} Hz: worst rope point {worst_rope:.5} m into the tapered thigh; {near_rope} near"
        );
        assert!(
            near_rope > 0,
            "{hz} Hz: the charm never came near the thigh"
        );
        assert!(
            worst_rope <= 1e-3,
            "{hz} Hz: a rope point ended {worst_rope} m inside the tapered thigh"
        );
        println!("{hz} Hz: worst cloth point {worst:.5} m into a tapered leg; {near} near");
        assert!(near > 0, "{hz} Hz: the legs never came near the skirt");
        assert!(
            worst <= 1e-3,
            "{hz} Hz: a cloth point ended {worst} m inside a tapered leg"
        );
    }
}

/// A rig file names the shape as KawaiiPhysics does (snake case); each value is checked
/// by name, with the collider's name in the message.
#[test]
fn rig_files_name_tapered_capsules_and_bad_values_are_refused() {
    let sk = common::line(3, 0.1, -Vec3::Y, Vec3::ZERO);
    let file = |r0: &str, r1: &str, len: &str| {
        format!(
            "[[chain]]\nname = \"hair\"\nroot = \"anchor\"\n\n[[collider]]\nname = \"cone\"\n\
             bone = \"anchor\"\nshape = \"tapered_capsule\"\nradius0 = {r0}\nradius1 = {r1}\n\
             length = {len}\n"
        )
    };
    let rig = RigSettings::from_toml_str(&file("0.1", "0.05", "0.2")).unwrap();
    assert_eq!(
        rig.colliders[0].shape,
        Shape::TaperedCapsule {
            radius0: 0.1,
            radius1: 0.05,
            length: 0.2
        }
    );
    assert!(CharacterSim::new(sk.clone(), &rig).is_ok());
    for (r0, r1, len, bad) in [
        ("-0.1", "0.05", "0.2", "radius0 -0.1"),
        ("0.1", "-0.05", "0.2", "radius1 -0.05"),
        ("0.1", "0.05", "-0.2", "length -0.2"),
        ("nan", "0.05", "0.2", "radius0 NaN"),
    ] {
        let err = RigSettings::from_toml_str(&file(r0, r1, len))
            .map_err(|e| e.to_string())
            .and_then(|rig| {
                CharacterSim::new(sk.clone(), &rig)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            })
            .expect_err(bad);
        assert!(
            err.contains("cone") && err.contains(bad),
            "{bad}: the message names the collider and the value: {err}"
        );
    }
}
