//! Procedural wind (issue 62 item 7, KawaiiPhysics' `ProceduralWind` on its master branch
//! after 1.21) beyond the port in `kawaii_forces.rs`: KawaiiPhysics' own test expectations
//! (`KawaiiPhysicsProceduralWindTest.cpp` at `fb90c52`: its hash snapshot values, the noise's
//! range, continuity and grid values, the sines' phases, the ripple's travel, the strength
//! cycle's bounds, the gust envelopes and stops), the rig keys read, written and refused by
//! name, and the events.

use glam::Vec3;
use tassel::dynamics::chain::{
    smooth_noise, stable_hash, ExternalForceSettings, ForceKind, ProceduralWindSettings, TimeMode,
};
use tassel::dynamics::RigSettings;
use tassel::{CharacterSim, Transform};

mod common;
use common::hair::skeleton;

fn near(what: &str, got: f32, want: f32) {
    assert!((got - want).abs() <= 1e-4, "{what}: got {got}, want {want}");
}

/// KawaiiPhysics' `StableHash` snapshot values (`NoiseProperties`), and its noise: in
/// [-1, 1], continuous (steps of 0.01 move it by at most 0.1), equal to the grid values at
/// integers (the smoothstep's ends), the channels independent.
#[test]
fn hash_and_noise_as_kawaiiphysics_tests_them() {
    assert_eq!(stable_hash(0, 0, 0), 672_839_204);
    assert_eq!(stable_hash(123, 0, 0), 961_409_981);
    assert_eq!(stable_hash(123, 1, 0), 688_218_621);
    assert_eq!(stable_hash(123, -1, 0), 2_476_066_305);
    assert_eq!(stable_hash(-17, 42, 3), 1_090_092_324);
    let mut prev = smooth_noise(-8.0, 2468, 0);
    for i in 0..=2000 {
        let u = -8.0 + i as f32 * 0.01;
        let v = smooth_noise(u, 2468, 0);
        assert!((-1.0..=1.0).contains(&v), "u {u}: {v}");
        assert!((v - prev).abs() <= 0.1, "u {u}: {prev} → {v}");
        prev = v;
    }
    // At the grid points the smoothstep gives the cell's value; between them something
    // else (the noise is not constant).
    let mut differs = false;
    for g in -8..=8 {
        let at = smooth_noise(g as f32, 2468, 1);
        let mid = smooth_noise(g as f32 + 0.5, 2468, 1);
        let next = smooth_noise(g as f32 + 1.0, 2468, 1);
        assert!(
            (mid - 0.5 * (at + next)).abs() < 1e-6,
            "the smoothstep is 1/2 halfway"
        );
        differs |= at != next;
    }
    assert!(differs);
    let channels_differ = (0..128).any(|i| {
        let u = -3.0 + i as f32 * 0.071;
        let c = [0, 1, 2].map(|ch| smooth_noise(u, 1357, ch));
        (c[0] - c[1]).abs() > 1e-4 || (c[1] - c[2]).abs() > 1e-4
    });
    assert!(channels_differ);
}

/// `ConstantOnly`, `SinePhase`, `RipplePropagation`, `StrengthCycleBounds`.
#[test]
fn parts_as_kawaiiphysics_tests_them() {
    let constant = ProceduralWindSettings {
        constant_force: 7.25,
        ..Default::default()
    };
    for t in [0.0, 0.1, 0.5, 1.0, 3.75] {
        let s = constant.sample(t, 0.5, 0.0, 0);
        near("constant", s.constant, 7.25);
        near("total", s.total, 7.25);
    }
    let period = 2.0;
    let sway = ProceduralWindSettings {
        sway_force: 1.0,
        sway_period: period,
        ..Default::default()
    };
    near(
        "sway P/4",
        sway.sample(period * 0.25, 0.0, 0.0, 0).sway,
        1.0,
    );
    let t = 0.37;
    near(
        "sway periodic",
        sway.sample(t, 0.0, 0.0, 0).sway,
        sway.sample(t + period, 0.0, 0.0, 0).sway,
    );
    let shifted = ProceduralWindSettings {
        sway_phase_offset: 90.0,
        ..sway.clone()
    };
    near(
        "sway offset 90 at 0",
        shifted.sample(0.0, 0.0, 0.0, 0).sway,
        1.0,
    );
    near(
        "an offset is a time shift",
        shifted.sample(t, 0.0, 0.0, 0).sway,
        sway.sample(t + period * 0.25, 0.0, 0.0, 0).sway,
    );
    let ripple = ProceduralWindSettings {
        ripple_force: 1.0,
        ripple_period: period,
        ripple_phase_offset: 90.0,
        ..Default::default()
    };
    near("ripple phase", ripple.sample(0.0, 0.0, 0.0, 0).ripple, 1.0);
    near(
        "ripple periodic",
        ripple.sample(t, 0.35, 0.0, 0).ripple,
        ripple.sample(t + period, 0.35, 0.0, 0).ripple,
    );
    // 180° at the tip: root and tip in opposite phase; the crest moves toward the tip.
    let wave = ProceduralWindSettings {
        ripple_force: 1.0,
        ripple_period: 2.0,
        ripple_tip_phase_delay: 180.0,
        ..Default::default()
    };
    let (root, tip) = (wave.ripple(0.5, 0.0), wave.ripple(0.5, 1.0));
    assert!(root * tip < 0.0, "root {root}, tip {tip}");
    let crest = |t: f32| {
        (0..=1000)
            .max_by(|&a, &b| {
                let (x, y) = (a as f32 / 1000.0, b as f32 / 1000.0);
                wave.ripple(t, x).total_cmp(&wave.ripple(t, y))
            })
            .unwrap()
    };
    assert!(crest(1.0) > crest(0.5), "{} → {}", crest(0.5), crest(1.0));
    // The strength cycle stays in its range; min = max is a constant; a reversed range
    // starts at its max end with a 90° offset.
    let mut cycle = ProceduralWindSettings {
        strength_cycle_range: [0.2, 1.5],
        strength_cycle_period: 1.37,
        strength_cycle_phase_offset: 17.0,
        ..Default::default()
    };
    for i in 0..1000 {
        let c = cycle.sample(i as f32 * 0.013, 0.0, 0.0, 0).strength_cycle;
        assert!((0.2 - 1e-4..=1.5 + 1e-4).contains(&c), "{c}");
    }
    cycle.strength_cycle_range = [0.625, 0.625];
    for t in [0.0, 0.4, 1.7, 8.0] {
        near(
            "constant cycle",
            cycle.sample(t, 0.0, 0.0, 0).strength_cycle,
            0.625,
        );
    }
    // (Tassel refuses a reversed range in a rig file; `sample` still lerps one.)
    cycle.strength_cycle_range = [1.5, 0.25];
    cycle.strength_cycle_period = 2.0;
    cycle.strength_cycle_phase_offset = 90.0;
    near(
        "reversed",
        cycle.sample(0.0, 0.0, 0.0, 0).strength_cycle,
        0.25,
    );
    // The total: (constant + sway + ripple) × cycle + random + gust.
    let all = ProceduralWindSettings {
        constant_force: 0.5,
        sway_force: 0.3,
        ripple_force: 0.2,
        strength_cycle_range: [0.5, 1.5],
        random_force: 0.4,
        ..Default::default()
    };
    let s = all.sample(0.7, 0.3, 0.25, 9);
    near(
        "total",
        s.total,
        (s.constant + s.sway + s.ripple) * s.strength_cycle + s.random + s.gust,
    );
    assert!(s.random != 0.0 && s.random.abs() <= 0.4);
    // The direction: +X by default, normalised, inside its cone, and wandering.
    assert_eq!(ProceduralWindSettings::default().direction(3.0, 1), Vec3::X);
    let cone = ProceduralWindSettings {
        wind_direction: Vec3::new(0.0, 0.0, 2.0),
        wind_direction_noise_angle: 20.0,
        wind_direction_noise_period: 0.5,
        ..Default::default()
    };
    let dirs: Vec<Vec3> = (0..200)
        .map(|i| cone.direction(i as f32 * 0.05, 5))
        .collect();
    for d in &dirs {
        assert!((d.length() - 1.0).abs() < 1e-5);
        assert!(d.angle_between(Vec3::Z).to_degrees() <= 20.0 + 1e-3, "{d}");
    }
    assert!(dirs
        .iter()
        .any(|d| d.angle_between(Vec3::Z).to_degrees() > 5.0));
}

fn wind_rig(mode: TimeMode) -> RigSettings {
    RigSettings {
        chains: vec![common::kawaii::hair_chain(
            mode,
            tassel::dynamics::chain::ClassicGravity::PerFrame,
        )],
        external_forces: vec![ExternalForceSettings {
            name: "breeze".into(),
            kind: ForceKind::ProceduralWind,
            procedural_wind: ProceduralWindSettings {
                constant_force: 0.0,
                ..Default::default()
            },
            ..Default::default()
        }],
        ..Default::default()
    }
}

/// The gust's strength after each of `frames` half-second frames (classic: one step of
/// the frame's length; the wind's clock runs at 1×), the events applied before frame `k`
/// from `events[k]`.
fn gust_over(events: &[(usize, &str)], frames: usize) -> Vec<f32> {
    let sk = skeleton();
    let mut sim = CharacterSim::new(sk.clone(), &wind_rig(TimeMode::Classic)).unwrap();
    sim.frame(sk.rest(), Transform::IDENTITY, 0.0).unwrap();
    let mut out = Vec::new();
    for f in 1..=frames {
        for (_, e) in events.iter().filter(|(k, _)| *k == f) {
            assert!(sim.apply_event(e).unwrap(), "{e}");
        }
        sim.frame(sk.rest(), Transform::IDENTITY, 0.5).unwrap();
        let (_, s, _) = sim.chain_state().wind_sample("breeze", 0).unwrap();
        out.push(s.gust);
    }
    out
}

/// `GustEnvelope`, `GustEnvelopeHold`, `RequestGustStop` through the events: a gust
/// starts at the wind's time when its step takes it in, rises, holds, decays; a stop
/// fades from the current strength; a stop of 0 ends it; gusts stack.
#[test]
fn gusts_as_kawaiiphysics_tests_them() {
    // 5 over 1 s, no hold, 2 s down: 2.5, 5, 3.75, 2.5, 1.25, 0.
    let g = gust_over(&[(1, "tassel:gust breeze strength=5 rise=1 decay=2")], 7);
    for (got, want) in g.iter().zip([2.5, 5.0, 3.75, 2.5, 1.25, 0.0, 0.0]) {
        near("gust", *got, want);
    }
    // A 2 s hold.
    let g = gust_over(
        &[(1, "tassel:gust breeze strength=5 rise=1 hold=2 decay=2")],
        11,
    );
    for (got, want) in g
        .iter()
        .zip([2.5, 5.0, 5.0, 5.0, 5.0, 5.0, 3.75, 2.5, 1.25, 0.0, 0.0])
    {
        near("held gust", *got, want);
    }
    // Stopped at 1 s into a 2 s rise (strength 5 then), fading over 1 s.
    let g = gust_over(
        &[
            (1, "tassel:gust breeze strength=10 rise=2 decay=3"),
            (3, "tassel:stop_gust breeze 1"),
        ],
        5,
    );
    for (got, want) in g.iter().zip([2.5, 5.0, 2.5, 0.0, 0.0]) {
        near("stopped gust", *got, want);
    }
    // A stop of 0: gone at once; a start and a stop before the same frame: the stop wins.
    let g = gust_over(
        &[
            (1, "tassel:gust breeze strength=10 rise=1 hold=5"),
            (3, "tassel:stop_gust breeze 0"),
            (5, "tassel:gust breeze strength=10 hold=5"),
            (5, "tassel:stop_gust breeze 0"),
        ],
        6,
    );
    for (got, want) in g.iter().zip([5.0, 10.0, 0.0, 0.0, 0.0, 0.0]) {
        near("ended gust", *got, want);
    }
    // Two at once add up.
    let g = gust_over(
        &[
            (1, "tassel:gust breeze strength=1 hold=10"),
            (2, "tassel:gust breeze strength=2 hold=10"),
        ],
        3,
    );
    for (got, want) in g.iter().zip([1.0, 3.0, 3.0]) {
        near("stacked gusts", *got, want);
    }
}

/// The keys in a rig file: read (a table under the force), written back (omitted when
/// unset), each out-of-range value refused with the force and the key named; the kind's
/// other keys refused; gust events refused by name.
#[test]
fn keys_are_read_written_and_refused() {
    let text = "[[chain]]\nname = \"hair\"\nroot = \"hair_0\"\n\n[[external_force]]\n\
                name = \"breeze\"\nkind = \"procedural_wind\"\n\n\
                [external_force.procedural_wind]\nconstant_force = 0.5\nsway_force = 0.25\n\
                ripple_tip_phase_delay = 90.0\nstrength_cycle_range = [0.5, 1.5]\n";
    let rig = RigSettings::from_toml_str(text).unwrap();
    let w = &rig.external_forces[0].procedural_wind;
    assert_eq!(rig.external_forces[0].kind, ForceKind::ProceduralWind);
    assert_eq!(
        (w.constant_force, w.sway_force, w.ripple_tip_phase_delay),
        (0.5, 0.25, 90.0)
    );
    assert_eq!(
        w.sway_period, 1.0,
        "unset keys take KawaiiPhysics' defaults"
    );
    let back = RigSettings::from_toml_str(&rig.to_toml_string().unwrap()).unwrap();
    assert_eq!(back, rig);
    let plain = RigSettings::from_toml_str(
        "[[chain]]\nroot = \"hair_0\"\n\n[[external_force]]\nname = \"push\"\n",
    )
    .unwrap();
    assert!(!plain.to_toml_string().unwrap().contains("procedural_wind"));
    for (key, bad) in [
        ("sway_period", "sway_period = 0.0"),
        ("random_force_period", "random_force_period = -1.0"),
        (
            "wind_direction_noise_angle",
            "wind_direction_noise_angle = 181.0",
        ),
        ("time_scale", "time_scale = -1.0"),
        ("constant_force", "constant_force = 1e7"),
        ("strength_cycle_range", "strength_cycle_range = [2.0, 1.0]"),
        ("ripple_tip_phase_delay", "ripple_tip_phase_delay = inf"),
    ] {
        // The key's line replaced, or added to the table.
        let t = match text.lines().find(|l| l.starts_with(&format!("{key} ="))) {
            Some(line) => text.replace(line, bad),
            None => format!("{text}{bad}\n"),
        };
        let e = RigSettings::from_toml_str(&t)
            .and_then(|r| CharacterSim::new(skeleton(), &r).map(|_| ()))
            .unwrap_err()
            .to_string();
        assert!(e.contains("'breeze'") && e.contains(key), "{bad}: {e}");
    }
    for bad in [
        "force_dir = [1.0, 0.0, 0.0]",
        "random_force_scale_range = [0.5, 2.0]",
    ] {
        let t = text.replace(
            "kind = \"procedural_wind\"\n",
            &format!("kind = \"procedural_wind\"\n{bad}\n"),
        );
        let e = RigSettings::from_toml_str(&t)
            .and_then(|r| CharacterSim::new(skeleton(), &r).map(|_| ()))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("'breeze'") && e.contains("procedural_wind"),
            "{bad}: {e}"
        );
    }
    // A procedural_wind table on another kind.
    let t = text.replace("kind = \"procedural_wind\"\n", "");
    let e = RigSettings::from_toml_str(&t)
        .and_then(|r| CharacterSim::new(skeleton(), &r).map(|_| ()))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("'breeze'") && e.contains("procedural_wind"),
        "{e}"
    );

    let mut sim = CharacterSim::new(skeleton(), &wind_rig(TimeMode::Fixed)).unwrap();
    let mut other = wind_rig(TimeMode::Fixed);
    other.external_forces.push(ExternalForceSettings {
        name: "push".into(),
        force_dir: Vec3::X,
        ..Default::default()
    });
    let mut both = CharacterSim::new(skeleton(), &other).unwrap();
    for (event, names) in [
        ("tassel:gust nothing strength=1", "'nothing'"),
        ("tassel:gust breeze strength=inf", "strength"),
        ("tassel:gust breeze rise=-1", "rise"),
        ("tassel:gust breeze gusty=1", "gusty"),
        ("tassel:stop_gust breeze -1", "blend_out"),
        ("tassel:stop_gust", "tassel:stop_gust"),
    ] {
        let e = sim.apply_event(event).unwrap_err().to_string();
        assert!(e.contains(names) && e.contains(event), "{event}: {e}");
    }
    let e = both
        .apply_event("tassel:gust push strength=1")
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a procedural wind"), "{e}");
}
