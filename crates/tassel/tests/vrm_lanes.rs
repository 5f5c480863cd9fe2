//! The VRM springs' update with several springs side by side in SIMD lanes against the
//! scalar update (the readable reference): the same bits, frame after frame, in every
//! mode, on rigs that use every part of the lane plan.

mod common;

use glam::{Quat, Vec3};
use tassel::crowd::lanes::LANES;
use tassel::crowd::SimdUse;
use tassel::dynamics::vrm::{
    VrmCollider, VrmColliderGroup, VrmJoint, VrmMode, VrmOptions, VrmRig, VrmShape, VrmSpring,
    VrmSpringBones, VrmTail,
};
use tassel::dynamics::RigSettings;
use tassel::{builtin, CharacterSim, LocalToModelJob, Skeleton, SkeletonBuilder, Transform};

/// The character's world transform and animated pose at frame `f`: a sway, a bob, a turn
/// and a roll, joint `swing` swinging, a 10 m teleport at frame 450.
fn motion(sk: &Skeleton, swing: usize, f: usize, locals: &mut [Transform]) -> Transform {
    let t = f as f32 / 60.0;
    locals.copy_from_slice(sk.rest());
    locals[swing].rotation =
        sk.rest()[swing].rotation * Quat::from_rotation_x(0.6 * (3.0 * t + 1.0).sin());
    let jump = if f >= 450 { 10.0 } else { 0.0 };
    Transform::from_translation_rotation(
        Vec3::new((3.0 * t).sin() * 0.5 + jump, 0.1 * (5.0 * t).sin(), t),
        Quat::from_rotation_y(0.8 * (2.0 * t).sin()) * Quat::from_rotation_z(1.2 * (0.7 * t).sin()),
    )
}

/// 60 Hz with a paused frame and a hitch.
fn dt_at(f: usize) -> f32 {
    match f {
        200 => 0.0,
        300 => 0.25,
        _ => 1.0 / 60.0,
    }
}

/// One character per way of running the update (scalar, portable lanes, AVX2 lanes where
/// the CPU has them) through 600 frames: every local and model transform the same bits
/// after every frame. Returns the largest turn of a spring joint from its rest rotation.
fn assert_lanes_match(
    sk: &Skeleton,
    bones: &VrmSpringBones,
    (mode, step_rate): (VrmMode, f32),
) -> f32 {
    let options = VrmOptions {
        mode,
        step_rate,
        teleport_distance: 2.0,
        ..Default::default()
    };
    let ways = [
        SimdUse::Scalar,
        SimdUse::Portable,
        SimdUse::Avx2,
        SimdUse::Auto,
    ];
    let mut sims: Vec<CharacterSim> = ways
        .iter()
        .map(|&w| {
            let mut s = CharacterSim::with_vrm(sk.clone(), &RigSettings::default(), bones, options)
                .unwrap();
            s.set_simd(w);
            s
        })
        .collect();
    let swing = sims[0].vrm().links[0].parent.unwrap_or(0);
    let mut locals = sk.rest().to_vec();
    let mut turned = 0.0f32;
    for f in 0..600 {
        let transform = motion(sk, swing, f, &mut locals);
        let dt = dt_at(f);
        let reference = sims[0].frame(&locals, transform, dt).unwrap().clone();
        let resets = sims[0].vrm_state().reset_count();
        // The animated model pose, whichever way the frame left it (composed, or composed
        // when asked for): the pose job's, bit for bit.
        let mut animated = vec![Transform::IDENTITY; sk.len()];
        LocalToModelJob {
            skeleton: sk,
            root: Transform::IDENTITY,
            locals: &locals,
            models: &mut animated,
        }
        .run()
        .unwrap();
        for (w, sim) in ways.iter().zip(&mut sims).skip(1) {
            let pose = sim.frame(&locals, transform, dt).unwrap();
            for j in 0..sk.len() {
                assert_eq!(
                    (
                        common::transform_bits(&pose.locals[j]),
                        common::transform_bits(&pose.models[j])
                    ),
                    (
                        common::transform_bits(&reference.locals[j]),
                        common::transform_bits(&reference.models[j])
                    ),
                    "{mode:?} at {step_rate} Hz, {w:?}: frame {f}, joint '{}': {:?} vs {:?}",
                    sk.name(j),
                    pose.locals[j],
                    reference.locals[j]
                );
            }
            assert_eq!(sim.vrm_state().reset_count(), resets);
        }
        for (w, sim) in ways.iter().zip(&sims) {
            let got = sim.animated_models();
            // A second view while the first is held (a shared read, never a deadlock).
            assert_eq!(sim.animated_models().len(), got.len());
            for j in 0..sk.len() {
                assert_eq!(
                    common::transform_bits(&got[j]),
                    common::transform_bits(&animated[j]),
                    "{w:?}: frame {f}, animated model of '{}'",
                    sk.name(j)
                );
            }
        }
        for l in &sims[0].vrm().links {
            turned = turned.max(
                reference.locals[l.joint]
                    .rotation
                    .angle_between(l.rest_local.rotation),
            );
        }
    }
    // The first frame and the teleport.
    assert_eq!(sims[0].vrm_state().reset_count(), 2, "{mode:?}");
    turned
}

const MODES: [(VrmMode, f32); 4] = [
    (VrmMode::Spec, 60.0),
    (VrmMode::ThreeVrm, 60.0),
    (VrmMode::Fixed, 60.0),
    (VrmMode::Fixed, 90.0),
];

/// [`assert_lanes_match`] in every mode, each with springs that really moved.
fn assert_lanes_match_in_every_mode(sk: &Skeleton, bones: &VrmSpringBones) {
    for mode in MODES {
        let turned = assert_lanes_match(sk, bones, mode);
        assert!(
            turned > 0.05,
            "{mode:?}: the springs barely moved ({turned} rad)"
        );
    }
}

/// A rig that uses every part of the lane plan: 14 hair springs of 1 to 6 joints (lanes
/// idle in a group's later rows), two sets of colliders (every shape, inside and out, one
/// collider listed twice), two centres, per-joint parameters that differ from lane to
/// lane, tails as joints and as offsets, and a spring that branches: spring "b" turns
/// `b0`, `b1`, `b2`, `b3`, spring "y" turns `y2`, `y3`, which hang below `b1`; joints
/// below spring joints that no spring turns (tails, an ornament with a child); colliders
/// on a joint whose parent nothing else reads (`head` below `neck`) and on the ornament
/// below spring joints (fixed mode's step pose must hold their ancestors).
fn every_part() -> (Skeleton, VrmSpringBones) {
    let mut b = SkeletonBuilder::new();
    // A root at -0 (the pose jobs compose it under the identity, which gives +0; a
    // path that took the root's local as its model would show).
    let root = b.add(
        "root",
        None,
        Transform::from_translation(Vec3::new(-0.0, 0.0, -0.0)),
    );
    let body = b.add("body", Some(root), Transform::from_translation(Vec3::Y));
    let lengths = [1usize, 2, 3, 4, 5, 6, 3, 3, 2, 4, 5, 6, 2, 4];
    let mut chains = Vec::new();
    for (c, &len) in lengths.iter().enumerate() {
        let a = c as f32 * 0.45;
        let dir = Vec3::new(0.3 * a.sin(), -1.0, 0.3 * a.cos()).normalize();
        let mut p = b.add(
            format!("h{c}_0"),
            Some(body),
            Transform::new(
                Vec3::new(0.12 * a.sin(), 0.05, 0.12 * a.cos()),
                Quat::from_rotation_y(a),
                Vec3::ONE,
            ),
        );
        let mut joints = vec![p];
        for k in 1..len {
            // One spring joint scaled (the step pose must carry the links' scales).
            let scale = if (c, k) == (4, 2) {
                Vec3::new(1.0, 1.2, 0.9)
            } else {
                Vec3::ONE
            };
            p = b.add(
                format!("h{c}_{k}"),
                Some(p),
                Transform::new(dir * 0.06, Quat::IDENTITY, scale),
            );
            joints.push(p);
            if c == 5 && k == 2 {
                // An ornament below a spring joint that no spring turns, with a child.
                let o = b.add(
                    "ornament",
                    Some(p),
                    Transform::from_translation(Vec3::X * 0.03),
                );
                b.add(
                    "ornament_tip",
                    Some(o),
                    Transform::from_translation(Vec3::X * 0.02),
                );
            }
        }
        if c % 3 == 0 {
            // A tail joint that no spring turns.
            b.add(
                format!("h{c}_tail"),
                Some(p),
                Transform::from_translation(dir * 0.05),
            );
        }
        chains.push(joints);
    }
    let step = Transform::from_translation(Vec3::new(0.0, -0.06, 0.01));
    let b0 = b.add(
        "b0",
        Some(body),
        Transform::from_translation(Vec3::new(0.0, 0.0, -0.1)),
    );
    let b1 = b.add("b1", Some(b0), step);
    let b2 = b.add("b2", Some(b1), step);
    let b3 = b.add("b3", Some(b2), step);
    let y2 = b.add(
        "y2",
        Some(b1),
        Transform::from_translation(Vec3::new(0.03, -0.05, 0.0)),
    );
    let y3 = b.add("y3", Some(y2), step);
    let neck = b.add(
        "neck",
        Some(body),
        Transform::new(Vec3::Y * 0.1, Quat::from_rotation_z(0.2), Vec3::ONE),
    );
    let head = b.add(
        "head",
        Some(neck),
        Transform::from_translation(Vec3::Y * 0.1),
    );
    let (sk, _) = b.build().unwrap();
    let ornament = sk.find("ornament").unwrap();

    let mut bones = VrmSpringBones::default();
    let shapes = [
        VrmShape::Sphere {
            offset: Vec3::new(0.1, -0.15, 0.0),
            radius: 0.08,
            inside: false,
        },
        VrmShape::Capsule {
            offset: Vec3::new(-0.1, -0.1, 0.05),
            tail: Vec3::new(0.1, -0.2, 0.05),
            radius: 0.05,
            inside: false,
        },
        VrmShape::Plane {
            offset: Vec3::new(0.0, -0.25, 0.0),
            normal: Vec3::new(0.1, 1.0, 0.0),
        },
        VrmShape::Sphere {
            offset: Vec3::new(0.0, -0.1, 0.0),
            radius: 0.3,
            inside: true,
        },
        VrmShape::Capsule {
            offset: Vec3::ZERO,
            tail: Vec3::new(0.0, -0.4, 0.0),
            radius: 0.28,
            inside: true,
        },
    ];
    for shape in shapes {
        bones.colliders.push(VrmCollider { joint: body, shape });
    }
    bones.colliders.push(VrmCollider {
        joint: head,
        shape: VrmShape::Sphere {
            offset: Vec3::new(0.0, -0.2, 0.05),
            radius: 0.06,
            inside: false,
        },
    });
    bones.colliders.push(VrmCollider {
        joint: ornament,
        shape: VrmShape::Sphere {
            offset: Vec3::ZERO,
            radius: 0.03,
            inside: false,
        },
    });
    bones.collider_groups.push(VrmColliderGroup {
        name: "a".into(),
        colliders: vec![0, 1, 0],
    });
    bones.collider_groups.push(VrmColliderGroup {
        name: "b".into(),
        colliders: vec![2, 3, 4, 5, 6],
    });
    let spring = |name: String, joints: &[usize], groups: Vec<usize>, center, seed: usize| {
        let joints = joints
            .iter()
            .enumerate()
            .map(|(k, &j)| VrmJoint {
                joint: j,
                tail: match (joints.get(k + 1), sk.children(j).last()) {
                    (Some(&t), _) => VrmTail::Joint(t),
                    (None, Some(t)) => VrmTail::Joint(t),
                    (None, None) => VrmTail::Local(Vec3::new(0.0, -0.05, 0.02)),
                },
                hit_radius: 0.01 + 0.005 * ((seed + k) % 3) as f32,
                stiffness: 0.4 + 0.3 * ((seed + k) % 4) as f32,
                gravity_power: 0.5 + 0.25 * (k % 3) as f32,
                gravity_dir: Vec3::new(0.1 * (seed % 3) as f32, -1.0, 0.0),
                drag_force: 0.1 + 0.1 * (seed % 5) as f32,
                limit: None,
            })
            .collect();
        VrmSpring {
            name,
            joints,
            collider_groups: groups,
            center,
        }
    };
    for (c, joints) in chains.iter().enumerate() {
        let (groups, center) = match c {
            6 | 9 | 10 => (vec![1], None),
            7 => (vec![1], Some(body)),
            8 => (vec![1], Some(root)),
            _ => (vec![0], None),
        };
        bones
            .springs
            .push(spring(format!("h{c}"), joints, groups, center, c));
    }
    bones
        .springs
        .push(spring("b".into(), &[b0, b1, b2, b3], vec![0], None, 3));
    bones
        .springs
        .push(spring("y".into(), &[y2, y3], vec![0], None, 4));
    (sk, bones)
}

#[test]
fn lanes_give_the_scalar_bits_with_every_part_of_the_plan() {
    let (sk, bones) = every_part();
    let rig = VrmRig::new(&sk, &bones, VrmOptions::default()).unwrap();
    // By hand: without a centre, at the top: the 9 hair springs and "b" with colliders "a"
    // (list 0, 1, 0) and h6, h9, h10 with colliders "b" (2, 3, 4, 5, 6): 13 columns,
    // longest first h5, h11 (6 links), h4, h10 (5)... The first group's list is "a"'s;
    // h10's adds five entries to rows of 6 (30 tests) where a group of its own would cost
    // 5 x (4 + 5) = 45: taken, and every later column's list is then inside. So 13 columns
    // in groups of LANES; h7 and h8 (each its own centre) one group each; "y" hangs below
    // "b"'s link b1: a group of its own after them.
    assert_eq!(rig.lane_groups(), 13usize.div_ceil(LANES) + 3);
    assert_lanes_match_in_every_mode(&sk, &bones);
}

#[test]
fn lanes_give_the_scalar_bits_on_the_bench_rig() {
    // 24 springs with the same colliders: one full group and one of 8 (16 lanes), or
    // three full groups (8 lanes).
    let (sk, bones) = builtin::bench_vrm(24, 8, 8);
    let rig = VrmRig::new(&sk, &bones, VrmOptions::default()).unwrap();
    assert_eq!(rig.lane_groups(), 24usize.div_ceil(LANES));
    assert_lanes_match_in_every_mode(&sk, &bones);
}

/// Springs with different collider lists in one group: on the bench rig of four strands
/// around four colliders, strands 0 and 2 test them all and strands 1 and 3 none (both
/// lists ascending: one group, a collider mask per lane). The colliders do reach strands
/// 1 and 3 when listed (checked first), so lanes that tested colliders their links do not
/// list would lose the scalar bits.
#[test]
fn springs_with_different_colliders_share_a_group_and_keep_the_scalar_bits() {
    let (sk, all) = builtin::bench_vrm(4, 8, 4);
    let mut some = all.clone();
    for (k, s) in some.springs.iter_mut().enumerate() {
        if k % 2 == 1 {
            s.collider_groups.clear();
        }
    }
    let rig = VrmRig::new(&sk, &some, VrmOptions::default()).unwrap();
    assert_eq!(rig.lane_groups(), 1);
    // Strand 1's last joint with and without the colliders, scalar.
    let run = |b: &VrmSpringBones| {
        let mut sim = CharacterSim::with_vrm(
            sk.clone(),
            &RigSettings::default(),
            b,
            VrmOptions::default(),
        )
        .unwrap();
        sim.set_simd(SimdUse::Scalar);
        let swing = sim.vrm().links[0].parent.unwrap_or(0);
        let mut locals = sk.rest().to_vec();
        let joint = sk.find("c1_7").unwrap();
        let mut out = Vec::new();
        for f in 0..600 {
            let t = motion(&sk, swing, f, &mut locals);
            out.push(sim.frame(&locals, t, dt_at(f)).unwrap().locals[joint].rotation);
        }
        out
    };
    let (touched, free) = (run(&all), run(&some));
    let felt = touched.iter().zip(&free).filter(|(a, b)| a != b).count();
    assert!(
        felt > 10,
        "the colliders reach strand 1 on {felt} frames only"
    );
    assert_lanes_match_in_every_mode(&sk, &some);
}

/// Rigs the lanes cannot take run the scalar update (and still agree, trivially).
#[test]
fn rigs_the_lanes_cannot_take_run_the_scalar_update() {
    // A spring joint at the skeleton root.
    let (sk, mut bones) = every_part();
    bones.springs.push(VrmSpring {
        name: "root".into(),
        joints: vec![VrmJoint {
            joint: 0,
            ..Default::default()
        }],
        ..Default::default()
    });
    let rig = VrmRig::new(&sk, &bones, VrmOptions::default()).unwrap();
    assert_eq!(rig.lane_groups(), 0);
    // A spring below a simulated joint that is not a spring joint: "y" without "b1".
    let (sk, mut bones) = every_part();
    let b = bones.springs.iter().position(|s| s.name == "b").unwrap();
    bones.springs[b].joints.truncate(1);
    let rig = VrmRig::new(&sk, &bones, VrmOptions::default()).unwrap();
    assert_eq!(rig.lane_groups(), 0);
    assert_lanes_match(&sk, &bones, (VrmMode::Spec, 60.0));
    // A centre that a spring moves.
    let (sk, mut bones) = every_part();
    bones.springs[3].center = Some(sk.find("h0_0").unwrap());
    let rig = VrmRig::new(&sk, &bones, VrmOptions::default()).unwrap();
    assert_eq!(rig.lane_groups(), 0);
}
