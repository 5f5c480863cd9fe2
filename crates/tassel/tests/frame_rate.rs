//! Every solver of the built-in character is frame-rate independent in fixed mode
//! (issue 15): the character swayed ±0.3 m at 1 Hz along X (as `tassel simulate --builtin
//! --mode fixed --motion sin --amp 0.3 --freq 1 --axis x`) and turned ±0.5 rad at 0.7 Hz,
//! rendered at 30, 60 and 144 Hz for 6 s. For each solver, over the joints it moves and
//! their children, the RMS difference of their world positions at the instants the runs
//! share (every 1/6 s) against the 144 Hz run, relative to the RMS of their dynamic
//! deviation (simulated minus animated position) at 144 Hz, must be at most 1 %.
//!
//! Measured (this test's output): chains 0.01 %, springs 0.71 %, cloth 0.09 %, rope 0.35 %
//! at 30 Hz; at most 0.24 % at 60 Hz. Before the fixed-step solvers took the character's
//! transform from a cubic path through the last frames, the rope stepped with the frame's
//! end pose and the cloth limited lengths once per frame: cloth 13.8 %, rope 17.4 %.
//!
//! The same again with every capsule of the rig tapered (issue 62: 1.3× as wide at its +Y
//! end, 0.8× at its −Y end), the legs the skirt and the charm touch among them.

use glam::{Quat, Vec3};
use tassel::builtin;
use tassel::dynamics::chain::TimeMode;
use tassel::{CharacterSim, Transform};

const SECONDS: f64 = 6.0;

fn component(t: f64) -> Transform {
    Transform::from_translation_rotation(
        Vec3::new((0.3 * (std::f64::consts::TAU * t).sin()) as f32, 0.0, 0.0),
        Quat::from_rotation_y(if std::env::var("NOTURN").is_ok() {
            0.0
        } else {
            (0.5 * (std::f64::consts::TAU * 0.7 * t).sin()) as f32
        }),
    )
}

/// The solvers of the built-in rig and the joints each one moves (its own and their
/// children).
fn groups(sim: &CharacterSim) -> Vec<(&'static str, Vec<usize>)> {
    let sk = sim.skeleton();
    let with_children = |own: Vec<usize>| {
        let mut out = own.clone();
        for j in 0..sk.len() {
            if sk.parent(j).is_some_and(|p| own.contains(&p)) && !out.contains(&j) {
                out.push(j);
            }
        }
        out.sort_unstable();
        out
    };
    let chains: Vec<usize> = sim.chains().rotating_joints().map(|(j, _, _)| j).collect();
    let springs: Vec<usize> = (0..sim.springs().len())
        .map(|i| sim.springs().joint(i))
        .collect();
    let cloth: Vec<usize> = sim.cloths().simulated_joints().collect();
    let ropes: Vec<usize> = sim.ropes().simulated_joints().collect();
    vec![
        ("chains", with_children(chains)),
        ("springs", with_children(springs)),
        ("cloth", with_children(cloth)),
        ("rope", with_children(ropes)),
    ]
}

/// World positions (simulated, animated) of every joint at each instant k/6 s.
fn run(hz: u32, tapered: bool) -> (Vec<Vec<Vec3>>, Vec<Vec<Vec3>>) {
    let c = builtin::character();
    let mut rig = c.rig.clone();
    if tapered {
        for col in &mut rig.colliders {
            if let tassel::collide::Shape::Capsule { radius, length } = col.shape {
                col.shape = tassel::collide::Shape::TaperedCapsule {
                    radius0: 1.3 * radius,
                    radius1: 0.8 * radius,
                    length,
                };
            }
        }
    }
    for chain in &mut rig.chains {
        chain.mode = TimeMode::Fixed;
    }
    let mut sim = CharacterSim::new(c.skeleton.clone(), &rig).unwrap();
    let rest = c.skeleton.rest().to_vec();
    let (mut sim_pos, mut anim_pos) = (Vec::new(), Vec::new());
    let frames = (SECONDS * hz as f64).round() as u32;
    for f in 0..=frames {
        let t = f as f64 / hz as f64;
        let comp = component(t);
        sim.frame(&rest, comp, if f == 0 { 0.0 } else { 1.0 / hz as f32 })
            .unwrap();
        if (f * 6) % hz == 0 {
            sim_pos.push(
                sim.pose()
                    .models
                    .iter()
                    .map(|m| comp.transform_point(m.translation))
                    .collect(),
            );
            anim_pos.push(
                sim.animated_models()
                    .iter()
                    .map(|m| comp.transform_point(m.translation))
                    .collect(),
            );
        }
    }
    (sim_pos, anim_pos)
}

#[test]
fn every_solver_of_the_builtin_character_is_frame_rate_independent() {
    let c = builtin::character();
    let sim = CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap();
    let groups = groups(&sim);
    let mut failures = Vec::new();
    for tapered in [false, true] {
        let (reference, anim) = run(144, tapered);
        let shapes = if tapered { ", capsules tapered" } else { "" };
        for (name, joints) in &groups {
            assert!(!joints.is_empty(), "the built-in rig has no {name}");
            let (mut dev2, mut n) = (0.0f64, 0usize);
            for (s, a) in reference.iter().zip(&anim) {
                for &j in joints {
                    dev2 += (s[j] - a[j]).length_squared() as f64;
                    n += 1;
                }
            }
            let dev_rms = (dev2 / n as f64).sqrt();
            for hz in [30, 60] {
                let (other, _) = run(hz, tapered);
                assert_eq!(other.len(), reference.len());
                let (mut d2, mut worst) = (0.0f64, 0.0f32);
                for (s, r) in other.iter().zip(&reference) {
                    for &j in joints {
                        d2 += (s[j] - r[j]).length_squared() as f64;
                        worst = worst.max((s[j] - r[j]).length());
                    }
                }
                let rel = (d2 / n as f64).sqrt() / dev_rms;
                println!(
                "{name}{shapes}: {hz} Hz vs 144 Hz: {:.2} % of the RMS dynamic deviation ({:.1} mm); \
                 largest difference {:.2} mm",
                100.0 * rel,
                1e3 * dev_rms,
                1e3 * worst
            );
                if rel > 0.01 {
                    failures.push(format!("{name}{shapes} at {hz} Hz: {:.2} %", 100.0 * rel));
                }
            }
        }
    }
    assert!(failures.is_empty(), "over 1 %: {}", failures.join(", "));
}
