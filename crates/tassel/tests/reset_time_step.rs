//! A frame that starts a solver again (the first frame, or the one after `reset`) does no
//! step: its time step changes nothing. So a character's first frame may come with the
//! frame's `dt` (as in a crowd, where one `dt` serves every character) or with 0 (as
//! `CharacterSim`'s docs suggest) and every later frame has the same bits.

use glam::{Quat, Vec3};
use tassel::dynamics::chain::TimeMode;
use tassel::dynamics::vrm::{VrmMode, VrmOptions};
use tassel::dynamics::RigSettings;
use tassel::{builtin, CharacterSim, Skeleton, Transform};

/// The character's transform and pose at frame `f`: a sway, a bob and a turn, the root
/// swinging.
fn motion(sk: &Skeleton, f: usize, locals: &mut [Transform]) -> Transform {
    let t = f as f32 / 60.0;
    locals.copy_from_slice(sk.rest());
    locals[0].rotation = sk.rest()[0].rotation * Quat::from_rotation_z(0.3 * (2.0 * t).sin());
    Transform::from_translation_rotation(
        Vec3::new(0.02 + 0.5 * (3.0 * t).sin(), 0.1 * (5.0 * t).sin(), 0.7 * t),
        Quat::from_rotation_y(0.4 * (2.0 * t).sin()),
    )
}

fn bits(t: &Transform) -> Vec<u32> {
    t.translation
        .to_array()
        .into_iter()
        .chain(t.rotation.to_array())
        .chain(t.scale.to_array())
        .map(f32::to_bits)
        .collect()
}

/// Two copies of `sim` through the same frames; at frame 0 and at `reset_at` (after a
/// `reset`) one takes `dt = 0` and the other 1/60 s. Every later frame, every joint: the
/// same bits. Returns how far the simulated joints swung from rest (that they did).
fn assert_reset_frames_ignore_dt(sim: CharacterSim, what: &str) -> f32 {
    let sk = sim.skeleton().clone();
    let (mut zero, mut step) = (sim.clone(), sim);
    let mut locals = sk.rest().to_vec();
    let reset_at = 70;
    let joints = step.simulated_joints().to_vec();
    let mut swing = 0.0f32;
    for f in 0..150 {
        let at = motion(&sk, f, &mut locals);
        if f == reset_at {
            zero.reset();
            step.reset();
        }
        let h = 1.0 / 60.0;
        let restart = f == 0 || f == reset_at;
        let a = zero
            .frame(&locals, at, if restart { 0.0 } else { h })
            .unwrap()
            .clone();
        let b = step.frame(&locals, at, h).unwrap();
        for j in 0..sk.len() {
            assert_eq!(
                bits(&a.locals[j]),
                bits(&b.locals[j]),
                "{what}: frame {f}, joint '{}'",
                sk.name(j)
            );
        }
        for &j in &joints {
            swing = swing.max(b.locals[j].rotation.angle_between(sk.rest()[j].rotation));
        }
    }
    swing
}

#[test]
fn vrm_springs_reset_frames_ignore_dt() {
    let (sk, bones) = builtin::bench_vrm(4, 5, 2);
    for mode in [VrmMode::Spec, VrmMode::ThreeVrm, VrmMode::Fixed] {
        let options = VrmOptions {
            mode,
            ..Default::default()
        };
        let sim =
            CharacterSim::with_vrm(sk.clone(), &RigSettings::default(), &bones, options).unwrap();
        let swing = assert_reset_frames_ignore_dt(sim, &format!("VRM {mode:?}"));
        assert!(
            swing > 0.05,
            "VRM {mode:?}: the springs swing ({swing} rad)"
        );
    }
}

#[test]
fn chains_reset_frames_ignore_dt() {
    let (sk, rig) = builtin::bench_character(4, 5, 2);
    for mode in [TimeMode::Fixed, TimeMode::Classic] {
        let mut rig = rig.clone();
        for c in &mut rig.chains {
            c.mode = mode;
        }
        let sim = CharacterSim::new(sk.clone(), &rig).unwrap();
        let swing = assert_reset_frames_ignore_dt(sim, &format!("chains {mode:?}"));
        assert!(
            swing > 0.05,
            "chains {mode:?}: the chains swing ({swing} rad)"
        );
    }
}
