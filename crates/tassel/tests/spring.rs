//! The spring controller against the closed-form damped oscillator, at three render rates
//! and three damping regimes; plus the error reset, the displacement limit and the channel
//! filters.

use glam::Vec3;
use tassel::dynamics::spring::{SpringJob, SpringRig, SpringSettings, SpringState};
use tassel::{Skeleton, Transform};

/// A root and one bone 0.2 m above it.
fn skeleton() -> Skeleton {
    Skeleton::new(
        vec!["root".into(), "bob".into()],
        vec![None, Some(0)],
        vec![
            Transform::IDENTITY,
            Transform::from_translation(Vec3::new(0.0, 0.2, 0.0)),
        ],
    )
    .unwrap()
}

/// x(t) of x'' = −k·x − b·x', x(0) = x0, x'(0) = 0.
fn closed_form(k: f32, b: f32, x0: f32, t: f32) -> f32 {
    let (k, b, x0, t) = (k as f64, b as f64, x0 as f64, t as f64);
    let w0 = k.sqrt();
    let zeta = b / (2.0 * w0);
    let x = if (zeta - 1.0).abs() < 1e-9 {
        x0 * (-w0 * t).exp() * (1.0 + w0 * t)
    } else if zeta < 1.0 {
        let wd = w0 * (1.0 - zeta * zeta).sqrt();
        x0 * (-zeta * w0 * t).exp() * ((wd * t).cos() + zeta * w0 / wd * (wd * t).sin())
    } else {
        let s = (zeta * zeta - 1.0).sqrt();
        let (r1, r2) = (-w0 * (zeta - s), -w0 * (zeta + s));
        x0 * (r2 * (r1 * t).exp() - r1 * (r2 * t).exp()) / (r2 - r1)
    };
    x as f32
}

struct Run {
    sk: Skeleton,
    rig: SpringRig,
    state: SpringState,
}

impl Run {
    fn new(settings: SpringSettings) -> Self {
        let sk = skeleton();
        let rig = SpringRig::new(&sk, &[settings]).unwrap();
        let state = SpringState::new(&rig);
        Self { sk, rig, state }
    }

    /// One frame with the bone animated at `bone_pos`; returns the bone's model position.
    fn frame(&mut self, component: Transform, bone_pos: Vec3, dt: f32) -> Transform {
        let mut locals = self.sk.rest().to_vec();
        locals[1].translation = bone_pos;
        let mut models = locals.clone();
        tassel::LocalToModelJob {
            skeleton: &self.sk,
            root: Transform::IDENTITY,
            locals: &locals,
            models: &mut models,
        }
        .run()
        .unwrap();
        SpringJob {
            skeleton: &self.sk,
            rig: &self.rig,
            state: &mut self.state,
            component,
            dt,
            locals: &mut locals,
            models: &mut models,
        }
        .run()
        .unwrap();
        models[1]
    }
}

#[test]
fn release_follows_the_damped_oscillator_at_any_frame_rate() {
    let k = (std::f32::consts::TAU * 1.0).powi(2); // 1 Hz natural frequency
    let x0 = 0.05;
    for (label, zeta) in [
        ("under-damped", 0.2f32),
        ("critically damped", 1.0),
        ("over-damped", 2.0),
    ] {
        let b = 2.0 * zeta * k.sqrt();
        for hz in [30.0f32, 60.0, 144.0] {
            let mut run = Run::new(SpringSettings {
                name: "s".into(),
                bone: "bob".into(),
                stiffness: k,
                damping: b,
                use_rotation: false,
                error_reset_threshold: 1.0,
                ..Default::default()
            });
            // Settle at the animated position, then pluck the bone x0 along −X and let go.
            let target = Vec3::new(0.0, 0.2, 0.0);
            run.frame(Transform::IDENTITY, target, 0.0);
            run.state.displace(0, Vec3::new(-x0, 0.0, 0.0));
            let frames = (2.0 * hz).round() as usize;
            let mut worst = 0.0f32;
            for f in 1..=frames {
                let t = f as f32 / hz;
                let got = run.frame(Transform::IDENTITY, target, 1.0 / hz).translation;
                let want = target.x - closed_form(k, b, x0, t);
                worst = worst.max((got.x - want).abs());
                assert!((got.y - 0.2).abs() < 1e-6 && got.z.abs() < 1e-6);
            }
            println!(
                "{label} at {hz} Hz: worst error {:.3} % of x0",
                100.0 * worst / x0
            );
            assert!(
                worst < 0.01 * x0,
                "{label} at {hz} Hz: worst error {worst} m ({:.2} % of x0)",
                100.0 * worst / x0
            );
        }
    }
}

#[test]
fn owner_motion_resets_limits_and_filters() {
    let base = SpringSettings {
        name: "s".into(),
        bone: "bob".into(),
        use_rotation: false,
        ..Default::default()
    };
    let rest = Vec3::new(0.0, 0.2, 0.0);
    // Constant owner velocity: the bone is carried along, no lag builds up.
    let mut run = Run::new(base.clone());
    run.frame(Transform::IDENTITY, rest, 0.0);
    for f in 1..=120 {
        let comp = Transform::from_translation(Vec3::new(2.0 * f as f32 / 60.0, 0.0, 0.0));
        let p = run.frame(comp, rest, 1.0 / 60.0);
        assert!(
            p.translation.abs_diff_eq(rest, 1e-4),
            "frame {f}: {}",
            p.translation
        );
    }
    // Unreal's owner velocity hides steady motion; with owner_velocity_scale 0 a sudden stop
    // from 2 m/s swings the bone forward — never past the displacement limit.
    let mut run = Run::new(SpringSettings {
        limit_displacement: 0.02,
        owner_velocity_scale: 0.0,
        ..base.clone()
    });
    run.frame(Transform::IDENTITY, rest, 0.0);
    let mut x = 0.0;
    let mut max_disp = 0.0f32;
    for f in 1..=120 {
        if f <= 30 {
            x += 2.0 / 60.0;
        }
        let p = run.frame(
            Transform::from_translation(Vec3::new(x, 0.0, 0.0)),
            rest,
            1.0 / 60.0,
        );
        if f > 30 {
            max_disp = max_disp.max((p.translation - rest).length());
        }
    }
    assert!(max_disp > 0.01 && max_disp <= 0.02 + 1e-5, "{max_disp}");
    // Error reset: a 5 m teleport (not carried by owner velocity) snaps the bone back.
    let mut run = Run::new(SpringSettings {
        owner_velocity_scale: 0.0,
        ..base.clone()
    });
    run.frame(Transform::IDENTITY, rest, 0.0);
    let p = run.frame(
        Transform::from_translation(Vec3::new(5.0, 0.0, 0.0)),
        rest,
        1.0 / 60.0,
    );
    assert!(p.translation.abs_diff_eq(rest, 1e-4));
    assert!(run.state.reset_count() >= 1);
    // Filters: only Y may move; a sideways kick leaves X and Z animated.
    let mut run = Run::new(SpringSettings {
        translate: [false, true, false],
        ..base.clone()
    });
    run.frame(Transform::IDENTITY, rest, 0.0);
    let p = run.frame(
        Transform::IDENTITY,
        rest + Vec3::new(0.05, 0.05, 0.05),
        1.0 / 60.0,
    );
    assert!((p.translation.x - 0.05).abs() < 1e-6 && (p.translation.z - 0.05).abs() < 1e-6);
    assert!(
        (p.translation.y - 0.25).abs() > 1e-3,
        "Y lags behind its target"
    );
    // Bad settings are named.
    let e = SpringRig::new(
        &skeleton(),
        &[SpringSettings {
            stiffness: -1.0,
            ..base.clone()
        }],
    )
    .unwrap_err();
    assert!(e.to_string().contains("stiffness"));
    let e = SpringRig::new(
        &skeleton(),
        &[SpringSettings {
            bone: "nope".into(),
            ..base
        }],
    )
    .unwrap_err();
    assert!(e.to_string().contains("nope"));
}

/// The output is the target plus the spring's deviation, so a bone carried by its owner
/// never lags the character by the time carried to the next step: at frame rates that
/// leave a remainder (50 and 144 Hz against 120 Hz steps), walking at 5 m/s keeps the bone
/// on its animated position (the output used to trail by up to 5 m/s × 1/120 s ≈ 4 cm),
/// and a 1 km teleport leaves it at its animated position (it used to be left 485 m
/// behind: found by the simulation fuzzer).
#[test]
fn a_carried_bone_never_lags_its_moving_owner() {
    let rest = Vec3::new(0.0, 0.2, 0.0);
    for hz in [30.0f32, 50.0, 144.0] {
        let mut run = Run::new(SpringSettings {
            name: "s".into(),
            bone: "bob".into(),
            use_rotation: false,
            ..Default::default()
        });
        run.frame(Transform::IDENTITY, rest, 0.0);
        let mut x = 0.0;
        for f in 1..=(2.0 * hz) as usize {
            x += 5.0 / hz;
            let p = run.frame(
                Transform::from_translation(Vec3::new(x, 0.0, 0.0)),
                rest,
                1.0 / hz,
            );
            assert!(
                p.translation.abs_diff_eq(rest, 1e-4),
                "{hz} Hz frame {f}: {} (animated {rest})",
                p.translation
            );
        }
        x += 1000.0;
        let p = run.frame(
            Transform::from_translation(Vec3::new(x, 0.0, 0.0)),
            rest,
            1.0 / hz,
        );
        assert!(
            p.translation.abs_diff_eq(rest, 1e-3),
            "{hz} Hz after a 1 km teleport: {}",
            p.translation
        );
        // A move in a frame of 1e-30 s is no infinite velocity.
        for dt in [1e-30, 1e-30, 1.0 / hz] {
            x += 0.5;
            let p = run.frame(
                Transform::from_translation(Vec3::new(x, 0.0, 0.0)),
                rest,
                dt,
            );
            assert!(
                p.translation.is_finite() && (p.translation - rest).length() < 0.05,
                "{hz} Hz, dt {dt}: {}",
                p.translation
            );
        }
    }
}

/// The stability check against the closed form: an undamped spring integrated by
/// kick-drift-kick is stable exactly while ω·h ≤ 2 (k·h² ≤ 4), and growth is 1 there;
/// damping alone, while b·h ≤ 4. A stiffness of 3.4e38 (finite, so it passed the old
/// checks) overflowed to NaN, and a merely too-high one ran away to 4e17 m: both found by
/// the simulation fuzzer, both refused now with a message naming the spring.
#[test]
fn unstable_settings_are_refused_at_the_stability_edge() {
    let s = |k: f32, b: f32, h: f32| SpringSettings {
        name: "s".into(),
        bone: "bob".into(),
        stiffness: k,
        damping: b,
        fixed_time_step: h,
        cutoff_damping: 1e9,
        ..Default::default()
    };
    let h = 0.01;
    assert!((s(3.99 / (h * h), 0.0, h).step_growth() - 1.0).abs() < 1e-6);
    assert!(s(3.99 / (h * h), 0.0, h).validate().is_ok());
    let e = s(4.01 / (h * h), 0.0, h)
        .validate()
        .unwrap_err()
        .to_string();
    assert!(e.contains("unstable") && e.contains("spring 's'"), "{e}");
    assert!(s(f32::MAX, 4.0, 1.0 / 120.0).validate().is_err());
    // Damping of b·h = 4 makes c = −1: the velocity flips sign and grows.
    assert!(s(0.0, 4.01 / h, h).validate().is_err());
    assert!(s(0.0, 3.99 / h, h).validate().is_ok());
    // The defaults and the built-in character's chest springs are far from the edge.
    assert!(SpringSettings::default().step_growth() < 1.0);
    let e = tassel::CharacterSim::new(
        tassel::builtin::character().skeleton,
        &tassel::builtin::character().rig,
    );
    assert!(e.is_ok());
}

/// With `owner_velocity_scale` 1 the owner's motion carries the bone step by step as a
/// displacement, consistent with the target when a step spans two frames: a teleport is
/// carried whole (no error reset needed: the bone stays on its animated position), and a
/// swaying character gives the same swing at 30, 50 and 144 Hz (measured: 0.27 mm and
/// 0.11 mm from 144 Hz; 12.5 mm at 30 Hz before). Before, each step added
/// this frame's owner velocity × step, which over- or under-shot the target by the
/// carried-over part of the step (a 1 km teleport with the reset off threw the bone to
/// its displacement limit; found by the simulation fuzzer).
#[test]
fn owner_motion_is_carried_exactly_at_any_frame_rate() {
    let rest = Vec3::new(0.0, 0.2, 0.0);
    let settings = SpringSettings {
        name: "s".into(),
        bone: "bob".into(),
        use_rotation: false,
        error_reset_threshold: 0.0,
        limit_displacement: 0.05,
        ..Default::default()
    };
    for hz in [30.0f32, 50.0, 144.0] {
        let mut run = Run::new(settings.clone());
        run.frame(Transform::IDENTITY, rest, 0.0);
        for _ in 0..10 {
            run.frame(Transform::IDENTITY, rest, 1.0 / hz);
        }
        let p = run.frame(
            Transform::from_translation(Vec3::new(1000.0, 0.0, 0.0)),
            rest,
            1.0 / hz,
        );
        assert!(
            p.translation.abs_diff_eq(rest, 1e-4),
            "{hz} Hz, teleport with the reset off: {}",
            p.translation
        );
    }
    // The swing of a bone whose animation bobs up and down (it lags: the spring), with
    // the character swaying sideways (carried: no swing from it): 30 and 50 Hz against
    // 144 Hz at shared instants.
    let swing = |hz: f32| -> Vec<(f32, Vec3)> {
        let mut run = Run::new(settings.clone());
        run.frame(Transform::IDENTITY, rest, 0.0);
        let mut out = Vec::new();
        for f in 1..=(2.0 * hz) as usize {
            let t = f as f32 / hz;
            let comp = Transform::from_translation(Vec3::new(0.3 * (6.0 * t).sin(), 0.0, 0.0));
            let bob = rest + Vec3::new(0.0, 0.02 * (9.0 * t).sin(), 0.0);
            let p = run.frame(comp, bob, 1.0 / hz);
            out.push((t, p.translation - bob));
        }
        out
    };
    let fine = swing(144.0);
    let at = |t: f32| {
        let i = fine.iter().position(|(ft, _)| *ft >= t - 1e-4).unwrap();
        fine[i].1
    };
    for hz in [30.0f32, 50.0] {
        let mut worst = 0.0f32;
        // At the instants both rates have a frame (every 1/6 s at 30 Hz, every 1/2 s at
        // 50 Hz).
        for (t, d) in swing(hz) {
            if (t * 144.0 - (t * 144.0).round()).abs() < 1e-3 {
                worst = worst.max((d - at(t)).length());
            }
        }
        println!("{hz} Hz against 144 Hz: worst {worst:.2e} m");
        assert!(worst < 5e-4, "{hz} Hz against 144 Hz: {worst} m");
        assert!(
            d_sideways_ok(&swing(hz)),
            "{hz} Hz: the sway swung the bone sideways"
        );
    }
}

/// The character's sideways sway is carried: the bone's deviation stays (almost) vertical.
fn d_sideways_ok(run: &[(f32, Vec3)]) -> bool {
    run.iter().all(|(_, d)| d.x.abs() < 1e-3)
}

/// The error reset also holds the output: an animated bone thrown 1e6 m away for a single
/// frame of 1/144 s (no step in it) and back leaves the spring bone at its animated
/// position, not 4e5 m away (found by the simulation fuzzer).
#[test]
fn a_target_thrown_away_for_one_frame_does_not_fling_the_bone() {
    let rest = Vec3::new(0.0, 0.2, 0.0);
    let mut run = Run::new(SpringSettings {
        name: "s".into(),
        bone: "bob".into(),
        use_rotation: false,
        max_steps_per_frame: 2,
        ..Default::default()
    });
    run.frame(Transform::IDENTITY, rest, 0.0);
    run.frame(Transform::IDENTITY, rest, 1.0 / 144.0);
    run.frame(Transform::IDENTITY, rest - Vec3::splat(1e6), 1.0 / 144.0);
    for f in 0..5 {
        let p = run.frame(Transform::IDENTITY, rest, 1.0 / 60.0);
        assert!(
            (p.translation - rest).length() <= 0.5,
            "frame {f} after: {} (animated {rest})",
            p.translation
        );
    }
}
