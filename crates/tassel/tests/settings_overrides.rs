//! Timed settings overrides (KawaiiPhysics' `StartPhysicsSettingsOverride`, issue 62 item
//! 7) beyond the port in `kawaii_1_21.rs`: `fixed` mode the same at 30, 60 and 144 Hz; the
//! radius and limit-angle scales held as invariants (no point nearer a sphere than the
//! scaled radius, no bone past the scaled cone); the bookkeeping (envelope values, the cap
//! of eight, stops, names); bad input refused by name; the animation events; the lanes
//! and the scalar path giving the same bits under an override.

use glam::{DVec3, Quat, Vec3};
use tassel::collide::Shape;
use tassel::crowd::SimdUse;
use tassel::dynamics::chain::{
    envelope_alpha, ChainSettings, ClassicGravity, OverrideTiming, SettingsScale, TimeMode,
    MAX_OVERRIDES,
};
use tassel::dynamics::{ColliderSettings, RigSettings};
use tassel::{CharacterSim, Skeleton, Transform};

mod common;
use common::hair::{component, skeleton, BONES};
use common::kawaii::{hair_chain, rms};

fn rig(mode: TimeMode) -> RigSettings {
    RigSettings {
        chains: vec![hair_chain(mode, ClassicGravity::PerFrame)],
        ..Default::default()
    }
}

/// An override of every setting the hair uses: stiffer and less damped, following more of
/// the character's motion.
fn loose() -> SettingsScale {
    SettingsScale {
        damping: 0.4,
        stiffness: 5.0,
        world_damping_location: 0.6,
        world_damping_rotation: 0.5,
        ..SettingsScale::ONE
    }
}

/// World joint positions every 1/6 s over 3 s at `hz`, the character swaying and turning;
/// with `overrides`, a 1.5 s override from 0.5 s (0.25 s in, 0.5 s out) and one of the
/// damping until stopped from 1 s, stopped at 2 s (0.3 s out): requests made between
/// frames at times that are frame boundaries at 30, 60 and 144 Hz.
fn run(mode: TimeMode, hz: u32, overrides: bool) -> Vec<Vec<Vec3>> {
    let sk = skeleton();
    let mut sim = CharacterSim::new(sk.clone(), &rig(mode)).unwrap();
    let rest = sk.rest().to_vec();
    let mut out = Vec::new();
    let mut damp = None;
    for f in 0..=3 * hz {
        let t = f as f64 / hz as f64;
        let (p, r) = component("sway", t);
        let (_, turn) = component("turn", t);
        let comp = Transform::from_translation_rotation(p.as_vec3(), (r * turn).as_quat());
        let dt = if f == 0 { 0.0 } else { 1.0 / hz as f32 };
        sim.frame(&rest, comp, dt).unwrap();
        // Requests made after this frame, at `t`.
        if overrides && f == hz / 2 {
            let timing = OverrideTiming {
                duration: 1.5,
                blend_in: 0.25,
                blend_out: 0.5,
            };
            sim.start_settings_override(loose(), timing, None, None)
                .unwrap();
        }
        if overrides && f == hz {
            let scale = SettingsScale {
                damping: 4.0,
                ..SettingsScale::ONE
            };
            let timing = OverrideTiming {
                duration: f32::INFINITY,
                blend_in: 0.2,
                blend_out: 0.0,
            };
            damp = Some(
                sim.start_settings_override(scale, timing, None, None)
                    .unwrap(),
            );
        }
        if overrides && f == 2 * hz {
            assert!(sim.stop_settings_override(damp.unwrap(), 0.3));
        }
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

/// `fixed` mode keeps its clock per step: the overrides' look is the same at 30, 60 and
/// 144 Hz, within 1 % of how far they move the hair.
#[test]
fn fixed_mode_overrides_are_frame_rate_independent() {
    let reference = run(TimeMode::Fixed, 144, true);
    let effect = rms(&reference, &run(TimeMode::Fixed, 144, false));
    assert!(effect > 0.01, "the overrides move the hair {effect} m RMS");
    for hz in [30, 60] {
        let rel = rms(&run(TimeMode::Fixed, hz, true), &reference) / effect;
        println!(
            "fixed, {hz} Hz vs 144 Hz: {:.3} % of the overrides' RMS effect ({:.1} mm)",
            100.0 * rel,
            1e3 * effect
        );
        assert!(rel <= 0.01, "{hz} Hz: {:.2} %", 100.0 * rel);
    }
    // What KawaiiPhysics' own clock (`classic`) gives at the same rates, for the docs.
    let classic = run(TimeMode::Classic, 144, true);
    let classic_effect = rms(&classic, &run(TimeMode::Classic, 144, false));
    for hz in [30, 60] {
        let rel = rms(&run(TimeMode::Classic, hz, true), &classic) / classic_effect;
        println!(
            "classic, {hz} Hz vs 144 Hz: {:.2} % of the overrides' RMS effect (classic's own \
             frame-rate dependence included)",
            100.0 * rel
        );
    }
}

const SPHERE_R: f32 = 0.05;
const POINT_R: f32 = 0.01;

const BALL: Vec3 = Vec3::new(0.10, -0.28, -0.06);

/// The hair with a point radius and a sphere beside it that the swaying character swings
/// it into (`ball`), or with a 40° limit and no collider (collisions, which get the last
/// word, would push bones past a limit).
fn contact_rig(mode: TimeMode, ball: bool) -> RigSettings {
    let mut chain: ChainSettings = hair_chain(mode, ClassicGravity::PerFrame);
    chain.radius = POINT_R;
    if ball {
        chain.colliders = vec!["ball".into()];
    } else {
        chain.limit_angle = 40.0;
    }
    RigSettings {
        chains: vec![chain],
        // (A chain with no `colliders` collides with every collider.)
        colliders: vec![ColliderSettings {
            mirror: None,
            mirror_bone: String::new(),
            name: "ball".into(),
            bone: "hair_0".into(),
            offset: BALL,
            rotation: Quat::IDENTITY,
            shape: Shape::Sphere {
                radius: SPHERE_R,
                inside: false,
            },
        }]
        .into_iter()
        .filter(|_| ball)
        .collect(),
        ..Default::default()
    }
}

/// The radius and limit-angle scales act as the scaled settings would: while an override
/// of radius ×2.5 and limit ×0.25 holds, no point is nearer the sphere's centre than
/// its radius plus 2.5 point radii, and no bone is more than 10° off its animated
/// direction; without it, points come nearer than that and bones swing further (so the
/// checks can fail). In all three modes, at 30, 60 and 144 Hz.
#[test]
fn radius_and_limit_scales_hold_as_invariants() {
    let sk = skeleton();
    let rest = sk.rest().to_vec();
    let centre = common::hair::pose()[0] + BALL.as_dvec3();
    let animated: Vec<DVec3> = common::hair::pose();
    for mode in [TimeMode::Fixed, TimeMode::Classic, TimeMode::Kawaii] {
        for hz in [30u32, 60, 144] {
            let mut worst = [(f64::MAX, 0.0f64); 2];
            for (k, on) in [false, true].into_iter().enumerate() {
                let mut ball = CharacterSim::new(sk.clone(), &contact_rig(mode, true)).unwrap();
                let mut limit = CharacterSim::new(sk.clone(), &contact_rig(mode, false)).unwrap();
                if on {
                    let scale = SettingsScale {
                        radius: 2.5,
                        limit_angle: 0.25,
                        ..SettingsScale::ONE
                    };
                    let timing = OverrideTiming {
                        duration: f32::INFINITY,
                        blend_in: 0.0,
                        blend_out: 0.5,
                    };
                    for sim in [&mut ball, &mut limit] {
                        sim.start_settings_override(scale, timing, None, None)
                            .unwrap();
                    }
                }
                for f in 0..=2 * hz {
                    let t = f as f64 / hz as f64;
                    let (p, _) = component("sway", t);
                    let comp = Transform::from_translation(2.0 * p.as_vec3());
                    let dt = if f == 0 { 0.0 } else { 1.0 / hz as f32 };
                    ball.frame(&rest, comp, dt).unwrap();
                    limit.frame(&rest, comp, dt).unwrap();
                    let (m, n) = (&ball.pose().models, &limit.pose().models);
                    for j in 1..=BONES {
                        let x = m[j].translation.as_dvec3();
                        worst[k].0 = worst[k].0.min((x - centre).length());
                        let x = n[j].translation.as_dvec3();
                        let bone = x - n[j - 1].translation.as_dvec3();
                        let anim = animated[j] - animated[j - 1];
                        let a = bone.angle_between(anim).to_degrees();
                        worst[k].1 = worst[k].1.max(a);
                    }
                }
            }
            let scaled = (SPHERE_R + 2.5 * POINT_R) as f64;
            println!(
                "{mode:?} {hz} Hz: nearest the sphere's centre {:.1} mm without, {:.1} mm \
                 with (scaled radius {:.1} mm); widest bone angle {:.1}° without, {:.2}° with",
                1e3 * worst[0].0,
                1e3 * worst[1].0,
                1e3 * scaled,
                worst[0].1,
                worst[1].1
            );
            assert!(
                worst[0].0 < scaled - 1e-3,
                "without: never near the scaled radius"
            );
            assert!(worst[0].1 > 12.0, "without: never past the scaled limit");
            assert!(
                worst[1].0 >= scaled - 1e-4,
                "{mode:?} {hz} Hz: inside the scaled radius"
            );
            assert!(
                worst[1].1 <= 10.0 + 0.05,
                "{mode:?} {hz} Hz: past the scaled limit"
            );
        }
    }
}

/// KawaiiPhysics' own test values of the envelope (`KawaiiPhysicsSettingsOverrideTest`:
/// 0.2 s in, 0.6 s held, 0.2 s out), and the timing's split of a duration.
#[test]
fn envelope_values() {
    for (t, want) in [
        (0.0, 0.0),
        (0.1, 0.5),
        (0.2, 1.0),
        (0.5, 1.0),
        (0.8, 1.0),
        (0.9, 0.5),
        (1.0, 0.0),
        (-0.1, 0.0),
        (2.0, 0.0),
    ] {
        let got = envelope_alpha(0.2, 0.6, 0.2, t);
        assert!((got - want).abs() < 1e-5, "at {t} s: {got}, want {want}");
    }
}

fn hair_sim(mode: TimeMode) -> CharacterSim {
    let sk = skeleton();
    let mut sim = CharacterSim::new(sk.clone(), &rig(mode)).unwrap();
    sim.frame(sk.rest(), Transform::IDENTITY, 0.0).unwrap();
    sim
}

fn step(sim: &mut CharacterSim, dt: f32) {
    let rest = sim.skeleton().rest().to_vec();
    sim.frame(&rest, Transform::IDENTITY, dt).unwrap();
}

/// The scales over time: 0 in the frame that takes a request in (KawaiiPhysics' clock),
/// the blend in, the hold, a stop folding the current alpha into a decay, a stop of 0
/// removing at once, at most eight acting (the oldest dropped), names stopped and
/// cross-faded.
#[test]
fn bookkeeping() {
    let mut sim = hair_sim(TimeMode::Classic);
    let half = SettingsScale {
        stiffness: 0.5,
        ..SettingsScale::ONE
    };
    let timing = OverrideTiming {
        duration: 1.0,
        blend_in: 0.2,
        blend_out: 0.2,
    };
    let h = sim
        .start_settings_override(half, timing, None, None)
        .unwrap();
    let stiff = |sim: &CharacterSim| sim.settings_scale("hair").unwrap().stiffness;
    assert_eq!(stiff(&sim), 1.0, "queued, not yet taken in");
    step(&mut sim, 0.1);
    assert_eq!(stiff(&sim), 1.0, "taken in at alpha 0");
    step(&mut sim, 0.1);
    assert!((stiff(&sim) - 0.75).abs() < 1e-6, "{}", stiff(&sim)); // halfway in
    step(&mut sim, 0.1);
    step(&mut sim, 0.1);
    assert!((stiff(&sim) - 0.5).abs() < 1e-6, "held");
    // A stop at full: a decay of 0.4 s from 1.
    assert!(sim.stop_settings_override(h, 0.4));
    step(&mut sim, 0.1);
    assert!(
        (stiff(&sim) - 0.5).abs() < 1e-6,
        "the stop's first frame is its start"
    );
    step(&mut sim, 0.1);
    assert!((stiff(&sim) - 0.625).abs() < 1e-6, "{}", stiff(&sim));
    for _ in 0..4 {
        step(&mut sim, 0.1);
    }
    assert_eq!(stiff(&sim), 1.0, "ended");
    assert!(
        !sim.stop_settings_override(h, 0.1),
        "an ended handle stops nothing"
    );

    // Ten at once: eight act; each halves the stiffness.
    let hold = OverrideTiming {
        duration: f32::INFINITY,
        blend_in: 0.0,
        blend_out: 0.0,
    };
    let hs: Vec<_> = (0..10)
        .map(|_| sim.start_settings_override(half, hold, None, None).unwrap())
        .collect();
    step(&mut sim, 0.1);
    assert_eq!(sim.chain_state().settings_override_count(), MAX_OVERRIDES);
    assert!((stiff(&sim) - 0.5f32.powi(8)).abs() < 1e-9);
    assert!(
        !sim.stop_settings_override(hs[0], 0.0),
        "the oldest was dropped"
    );
    assert!(sim.stop_settings_override(hs[9], 0.0));
    step(&mut sim, 0.1);
    assert_eq!(
        sim.chain_state().settings_override_count(),
        MAX_OVERRIDES - 1
    );

    // Names: one stop ends every override of that name; starting a name again blends
    // the old one out over the new one's blend-in.
    let mut sim = hair_sim(TimeMode::Fixed);
    let a = sim
        .start_settings_override(half, hold, None, Some("slow"))
        .unwrap();
    step(&mut sim, 0.1);
    let again = OverrideTiming {
        blend_in: 0.5,
        ..hold
    };
    let b = sim
        .start_settings_override(half, again, None, Some("slow"))
        .unwrap();
    assert_ne!(a, b);
    step(&mut sim, 0.1);
    // (fixed's clock: both changed at the frame's start) the old at 0.8, the new at 0.2.
    let want = (1.0 - 0.5 * 0.8) * (1.0 - 0.5 * 0.2);
    assert!(
        (stiff(&sim) - want).abs() < 1e-6,
        "{} vs {want}",
        stiff(&sim)
    );
    assert_eq!(sim.stop_named_settings_override("slow", 0.0), 2);
    step(&mut sim, 0.1);
    assert_eq!(stiff(&sim), 1.0);
}

/// Bad input is refused with the problem named, and nothing is queued.
#[test]
fn bad_input_is_refused_by_name() {
    let mut sim = hair_sim(TimeMode::Fixed);
    let ok = OverrideTiming::default();
    for (what, scale) in [
        ("damping", f32::NAN),
        ("stiffness", -1.0),
        ("radius", f32::INFINITY),
    ] {
        let mut s = SettingsScale::ONE;
        assert!(s.set(what, scale));
        let e = sim
            .start_settings_override(s, ok, None, None)
            .unwrap_err()
            .to_string();
        assert!(e.contains(what), "{e}");
    }
    for (what, timing) in [
        (
            "duration",
            OverrideTiming {
                duration: 0.0,
                ..ok
            },
        ),
        (
            "duration",
            OverrideTiming {
                duration: f32::NAN,
                ..ok
            },
        ),
        (
            "blend_in",
            OverrideTiming {
                blend_in: -0.1,
                ..ok
            },
        ),
        (
            "blend_out",
            OverrideTiming {
                blend_out: f32::INFINITY,
                ..ok
            },
        ),
    ] {
        let e = sim
            .start_settings_override(SettingsScale::ONE, timing, None, None)
            .unwrap_err()
            .to_string();
        assert!(e.contains(what), "{e}");
    }
    let e = sim
        .start_settings_override(SettingsScale::ONE, ok, Some("tail"), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("'tail'"), "{e}");
    step(&mut sim, 0.1);
    assert_eq!(sim.chain_state().settings_override_count(), 0);
}

/// The animation events start and stop named overrides as the API does (the same bits),
/// and a malformed one is refused with the event named.
#[test]
fn animation_events_act_as_the_api() {
    let sk = skeleton();
    let mut by_event = hair_sim(TimeMode::Fixed);
    let mut by_api = hair_sim(TimeMode::Fixed);
    let scale = SettingsScale {
        stiffness: 3.0,
        radius: 2.0,
        ..SettingsScale::ONE
    };
    let timing = OverrideTiming {
        duration: 1.0,
        blend_in: 0.1,
        blend_out: 0.3,
    };
    assert!(by_event
        .apply_event(
            "tassel:override wind stiffness=3 radius=2 duration=1 blend_in=0.1 blend_out=0.3 \
             chain=hair"
        )
        .unwrap());
    by_api
        .start_settings_override(scale, timing, Some("hair"), Some("wind"))
        .unwrap();
    let rest = sk.rest().to_vec();
    for f in 1..=60 {
        if f == 30 {
            assert!(by_event
                .apply_event("tassel:stop_override wind 0.2")
                .unwrap());
            by_api.stop_named_settings_override("wind", 0.2);
        }
        let (p, _) = component("sway", f as f64 / 60.0);
        let comp = Transform::from_translation(p.as_vec3());
        by_event.frame(&rest, comp, 1.0 / 60.0).unwrap();
        by_api.frame(&rest, comp, 1.0 / 60.0).unwrap();
        common::assert_pose_bits(&sk, "event vs API", by_event.pose(), by_api.pose());
    }
    for bad in [
        "tassel:override",
        "tassel:override x stiffness",
        "tassel:override x stiffness=soft",
        "tassel:override x bounce=2",
        "tassel:override x duration=-1",
        "tassel:override x chain=tail",
        "tassel:stop_override",
        "tassel:stop_override x -1",
    ] {
        let e = by_event.apply_event(bad).unwrap_err().to_string();
        assert!(e.contains(bad), "{bad}: {e}");
    }
}

/// Overrides step on the scalar path (the lanes give the same bits without them): the
/// built-in character's twin chains under an override give the same bits with the lanes
/// on and off, before, during and after it.
#[test]
fn lanes_and_scalar_agree_under_an_override() {
    let c = tassel::builtin::character();
    let sk: Skeleton = c.skeleton.clone();
    let mut runs: Vec<CharacterSim> = [SimdUse::Auto, SimdUse::Scalar]
        .into_iter()
        .map(|simd| {
            let mut s = CharacterSim::new(sk.clone(), &c.rig).unwrap();
            s.set_simd(simd);
            s
        })
        .collect();
    assert!(
        runs[0].rig().chains().lane_groups() > 0,
        "the built-in has twin chains"
    );
    let mut locals = sk.rest().to_vec();
    for f in 0..120 {
        if f == 20 {
            for s in &mut runs {
                let timing = OverrideTiming {
                    duration: 1.0,
                    blend_in: 0.2,
                    blend_out: 0.2,
                };
                s.start_settings_override(loose(), timing, None, None)
                    .unwrap();
            }
        }
        let comp = common::sway(&sk, 3, f as f32 / 60.0, 0.0, &mut locals);
        let dt = if f == 0 { 0.0 } else { 1.0 / 60.0 };
        for s in &mut runs {
            s.frame(&locals, comp, dt).unwrap();
        }
        common::assert_pose_bits(&sk, "lanes vs scalar", runs[0].pose(), runs[1].pose());
    }
}
