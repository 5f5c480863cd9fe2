//! Twin bone chains of one character side by side in SIMD lanes against the scalar chain
//! job (the readable reference): the same bits, frame after frame, on rigs whose twins
//! use every chain feature and collider shape, with chains the lanes do not take beside
//! them, and when the code is switched between frames.

mod common;

use tassel::crowd::lanes::LANES;
use tassel::crowd::SimdUse;
use tassel::dynamics::chain::{ChainRig, TimeMode};
use tassel::dynamics::RigSettings;
use tassel::{builtin, CharacterSim, Skeleton, Transform};

/// The character's world transform and animated pose at frame `f`: a sway, a bob and a
/// turn, the root and joint `swing` swinging, a 10 m jump at frame 450.
fn motion(sk: &Skeleton, swing: usize, f: usize, locals: &mut [Transform]) -> Transform {
    let jump = if f >= 450 { 10.0 } else { 0.0 };
    common::sway(sk, swing, f as f32 / 60.0, jump, locals)
}

/// One character per way of running the chains (scalar, portable lanes, AVX2 lanes at
/// most and the widest lanes where the CPU has them, and one switched between scalar and
/// lanes every 37 frames) through
/// `frames` frames with a reset at frame 400: every local and model transform, every
/// chain point and the reset count the same after every frame. The joints `squashed`
/// have no length (their local translation zero) in frames 100 to 249. Returns the
/// largest distance a point moved from its animated target (the chains really swung).
fn assert_lanes_match(
    sk: &Skeleton,
    rig: &RigSettings,
    swing: usize,
    frames: usize,
    squashed: &[usize],
) -> f32 {
    let ways = [
        SimdUse::Scalar,
        SimdUse::Portable,
        SimdUse::Avx2,
        SimdUse::Auto,
        SimdUse::Scalar,
    ];
    let mut sims: Vec<CharacterSim> = ways
        .iter()
        .map(|&simd| {
            let mut sim = CharacterSim::new(sk.clone(), rig).unwrap();
            sim.set_simd(simd);
            sim
        })
        .collect();
    let mut locals = sk.rest().to_vec();
    let mut swung = 0.0f32;
    for f in 0..frames {
        if f == 400 {
            sims.iter_mut().for_each(CharacterSim::reset);
        }
        if f % 37 == 0 {
            let simd = if (f / 37) % 2 == 0 {
                SimdUse::Scalar
            } else {
                SimdUse::Auto
            };
            sims[4].set_simd(simd);
        }
        let component = motion(sk, swing, f, &mut locals);
        if (100..250).contains(&f) {
            for &j in squashed {
                locals[j].translation = glam::Vec3::ZERO;
            }
        }
        let dt = common::dt_with_hitches(f);
        let poses: Vec<_> = sims
            .iter_mut()
            .map(|sim| sim.frame(&locals, component, dt).unwrap().clone())
            .collect();
        let reference = &sims[0];
        for (k, (sim, pose)) in sims.iter().zip(&poses).enumerate().skip(1) {
            let what = format!("frame {f}, way {k} ({:?})", ways[k]);
            common::assert_pose_bits(sk, &what, pose, &poses[0]);
            let (a, b) = (sim.chain_state(), reference.chain_state());
            for (p, (x, y)) in a
                .output_positions()
                .iter()
                .zip(b.output_positions())
                .enumerate()
            {
                assert_eq!(
                    x.to_array().map(f32::to_bits),
                    y.to_array().map(f32::to_bits),
                    "frame {f}, way {k}, point {p}"
                );
            }
            assert_eq!(a.teleport_count(), b.teleport_count(), "frame {f}, way {k}");
        }
        let state = reference.chain_state();
        for (out, target) in state
            .output_positions()
            .iter()
            .zip(state.target_positions())
        {
            swung = swung.max(out.distance(*target));
        }
    }
    assert!(
        sims[0].chain_state().teleport_count() >= 2,
        "the jump and the reset restart the chains"
    );
    swung
}

/// A bone of no length in some twins for a while: its rotator has no direction to turn
/// toward and keeps its animated rotation in those lanes (the others turn), and the
/// rotator below it reads that animated rotation as its parent's.
#[test]
fn twin_chains_in_lanes_keep_a_bone_of_no_length_as_animated() {
    let (sk, rig) = builtin::bench_character(16, 8, 8);
    let squashed: Vec<usize> = [0, 3, 9, 12]
        .iter()
        .map(|c| sk.find(&format!("c{c}_4")).unwrap())
        .collect();
    let swung = assert_lanes_match(&sk, &rig, 3, 500, &squashed);
    assert!(swung > 0.02, "chains barely moved ({swung} m)");
}

#[test]
fn twin_chains_in_lanes_give_the_scalar_bits_on_the_bench_rig() {
    let (sk, rig) = builtin::bench_character(16, 8, 8);
    let chains = ChainRig::new(&sk, &rig).unwrap();
    assert_eq!(
        chains.lane_groups(),
        16usize.div_ceil(LANES),
        "16 twins: groups of {LANES}"
    );
    let swung = assert_lanes_match(&sk, &rig, 3, 600, &[]);
    assert!(swung > 0.02, "chains barely moved ({swung} m)");
}

/// Twins with every chain feature (three per feature, so groups of three), beside chains
/// the lanes do not take (one of a kind, one that collides with the world) and a group
/// split (twenty-one twins: sixteen and five, or eight, eight and five); boxes, a plane, a
/// keep-inside sphere, a turned capsule.
#[test]
fn twin_chains_in_lanes_give_the_scalar_bits_with_every_feature() {
    let (sk, mut rig) = builtin::bench_character(50, 6, 6);
    for (c, ch) in rig.chains.iter_mut().enumerate() {
        ch.stiffness = 0.2;
        ch.teleport_distance = 2.0;
        // Different seeds among twins: each lane has its own wind generator.
        ch.wind.seed = c as u64;
        match c {
            0..=26 => common::chain_feature(ch, c / 3, c as u64),
            27 => ch.damping = 0.3,          // one of a kind: scalar
            28 => ch.world_collision = true, // the lanes have no world: scalar
            _ => {}                          // twenty-one plain twins
        }
    }
    common::every_collider_shape(&mut rig);
    let chains = ChainRig::new(&sk, &rig).unwrap();
    // Nine features of three, the 21 plain chains 29..=49 in groups of `LANES` (16: 29..=44
    // and 45..=49; 8: three groups).
    // A group split (checked when compiled).
    const { assert!(!21usize.is_multiple_of(LANES)) };
    assert_eq!(chains.lane_groups(), 9 + 21usize.div_ceil(LANES));
    let swung = assert_lanes_match(&sk, &rig, 2, 600, &[]);
    assert!(swung > 0.02, "chains barely moved ({swung} m)");
}

/// The built-in character's chains (its two locks are twins), both time modes.
#[test]
fn twin_chains_in_lanes_give_the_scalar_bits_on_the_builtin_character() {
    let c = builtin::character();
    for mode in [TimeMode::Fixed, TimeMode::Classic] {
        let mut rig = RigSettings {
            chains: c.rig.chains.clone(),
            colliders: c.rig.colliders.clone(),
            ..Default::default()
        };
        for ch in &mut rig.chains {
            ch.mode = mode;
        }
        let chains = ChainRig::new(&c.skeleton, &rig).unwrap();
        assert!(chains.lane_groups() >= 1, "{mode:?}: no twins");
        let swing = c.skeleton.len() / 2;
        let swung = assert_lanes_match(&c.skeleton, &rig, swing, 500, &[]);
        assert!(swung > 0.01, "{mode:?}: chains barely moved ({swung} m)");
    }
}
