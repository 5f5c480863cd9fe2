//! The crowd path against the single-character path: the same bits, frame after frame,
//! for every character, whatever the thread count.

mod common;

use common::transform_bits as bits;
use glam::{Quat, Vec3};
use std::sync::Arc;
use tassel::crowd::{CrowdPose, SimdUse, VrmCrowd};
use tassel::dynamics::vrm::{VrmMode, VrmOptions, VrmRig, VrmSpringBones};
use tassel::dynamics::RigSettings;
use tassel::{builtin, CharacterSim, Skeleton, Transform};

/// Character `i`'s world transform and animated pose at frame `f`: its own phase of a
/// sway, a bob and a turn, the root and one more joint swinging, a teleport of character 2
/// at frame 100.
fn motion(sk: &Skeleton, swing: usize, i: usize, f: usize, locals: &mut [Transform]) -> Transform {
    let t = f as f32 / 60.0 + 0.37 * i as f32;
    locals.copy_from_slice(sk.rest());
    locals[0].rotation = sk.rest()[0].rotation * Quat::from_rotation_z(0.3 * (2.0 * t).sin());
    locals[swing].rotation =
        sk.rest()[swing].rotation * Quat::from_rotation_x(0.5 * (3.0 * t + 1.0).sin());
    let jump = if i == 2 && f >= 100 { 10.0 } else { 0.0 };
    Transform::from_translation_rotation(
        Vec3::new((3.0 * t).sin() * 0.5 + jump, 0.1 * (5.0 * t).sin(), t),
        Quat::from_rotation_y(0.4 * (2.0 * t).sin()),
    )
}

/// Frame `f`'s time step: 60 Hz with a paused frame and a hitch.
fn dt_at(f: usize) -> f32 {
    match f {
        200 => 0.0,
        300 => 0.25,
        _ => 1.0 / 60.0,
    }
}

/// `n` characters through `frames` frames in a crowd and one `CharacterSim` each: every
/// local and model transform of every character has the same bits after every frame.
/// Returns how many link rotations were compared.
fn assert_crowd_matches(
    sk: &Skeleton,
    bones: &VrmSpringBones,
    (mode, step_rate): (VrmMode, f32),
    n: usize,
    frames: usize,
) -> usize {
    let options = VrmOptions {
        mode,
        step_rate,
        teleport_distance: 2.0,
        ..Default::default()
    };
    let rig = Arc::new(VrmRig::new(sk, bones, options).unwrap());
    let swing = rig.links[0].parent.unwrap_or(0);
    let mut crowd = VrmCrowd::new(Arc::new(sk.clone()), rig.clone()).unwrap();
    let mut sims: Vec<CharacterSim> = (0..n)
        .map(|_| {
            crowd.add();
            let mut sim =
                CharacterSim::with_vrm(sk.clone(), &RigSettings::default(), bones, options)
                    .unwrap();
            // The readable reference (the lane path is tested against it in vrm_lanes.rs).
            sim.set_simd(SimdUse::Scalar);
            sim
        })
        .collect();
    let mut inputs = vec![(Transform::IDENTITY, sk.rest().to_vec()); n];
    let mut locals = sk.rest().to_vec();
    let mut models = sk.rest().to_vec();
    let mut compared = 0;
    for f in 0..frames {
        if f == 400 {
            crowd.reset(3).unwrap();
            sims[3].reset();
        }
        for (i, (t, l)) in inputs.iter_mut().enumerate() {
            *t = motion(sk, swing, i, f, l);
        }
        let dt = dt_at(f);
        crowd
            .frame(dt, |i| CrowdPose {
                transform: inputs[i].0,
                locals: &inputs[i].1,
            })
            .unwrap();
        for (i, sim) in sims.iter_mut().enumerate() {
            let pose = sim.frame(&inputs[i].1, inputs[i].0, dt).unwrap();
            locals.copy_from_slice(&inputs[i].1);
            crowd.write_pose(i, &mut locals, &mut models).unwrap();
            for j in 0..sk.len() {
                assert_eq!(
                    bits(&locals[j]),
                    bits(&pose.locals[j]),
                    "{mode:?}: frame {f}, character {i}, joint '{}': crowd {:?} vs single {:?}",
                    sk.name(j),
                    locals[j],
                    pose.locals[j]
                );
                assert_eq!(bits(&models[j]), bits(&pose.models[j]), "frame {f}");
            }
            assert_eq!(
                crowd.reset_count(i),
                Some(sim.vrm_state().reset_count()),
                "character {i}"
            );
            compared += rig.links.len();
        }
    }
    // The motion really moved the springs, and the teleport and the reset were seen.
    let swung = (0..rig.links.len())
        .map(|k| {
            crowd
                .rotation(0, k)
                .unwrap()
                .angle_between(rig.links[k].rest_local.rotation)
        })
        .fold(0.0f32, f32::max);
    assert!(swung > 0.05, "{mode:?}: springs barely moved ({swung} rad)");
    assert_eq!(
        crowd.reset_count(2),
        Some(2),
        "the teleport resets character 2"
    );
    assert_eq!(crowd.reset_count(3), Some(2), "the reset of character 3");
    compared
}

/// Every mode; fixed at the frame rate and at 90 Hz (steps between frames, lanes with
/// different step counts after a reset).
const MODES: [(VrmMode, f32); 4] = [
    (VrmMode::Spec, 60.0),
    (VrmMode::ThreeVrm, 60.0),
    (VrmMode::Fixed, 60.0),
    (VrmMode::Fixed, 90.0),
];

#[test]
fn vrm_crowd_gives_the_single_character_bits_on_the_bench_rig() {
    let (sk, bones) = builtin::bench_vrm(16, 8, 8);
    for mode in MODES {
        // 11 characters: a full lane group and a partial one.
        let compared = assert_crowd_matches(&sk, &bones, mode, 11, 600);
        assert_eq!(compared, 11 * 600 * 16 * 7);
    }
}

/// Springs with a centre, a plane and inside colliders, a tail given as an offset and a
/// spring whose first joint is a skeleton root.
#[test]
fn vrm_crowd_gives_the_single_character_bits_with_centres_planes_and_inside_shapes() {
    use tassel::dynamics::vrm::{
        VrmCollider, VrmColliderGroup, VrmJoint, VrmShape, VrmSpring, VrmTail,
    };
    let (sk, mut bones) = builtin::bench_vrm(4, 6, 4);
    bones.colliders.push(VrmCollider {
        joint: 0,
        shape: VrmShape::Plane {
            offset: Vec3::new(0.0, -0.2, 0.0),
            normal: Vec3::new(0.2, 1.0, 0.1),
        },
    });
    bones.colliders.push(VrmCollider {
        joint: 0,
        shape: VrmShape::Sphere {
            offset: Vec3::new(0.0, -0.1, 0.0),
            radius: 0.33,
            inside: true,
        },
    });
    bones.colliders.push(VrmCollider {
        joint: 0,
        shape: VrmShape::Capsule {
            offset: Vec3::new(0.0, 0.1, 0.0),
            tail: Vec3::new(0.0, -0.4, 0.0),
            radius: 0.3,
            inside: true,
        },
    });
    bones.collider_groups.push(VrmColliderGroup {
        name: "new".into(),
        colliders: vec![4, 5, 6],
    });
    for s in &mut bones.springs {
        s.collider_groups.push(1);
    }
    bones.springs[1].center = Some(0);
    bones.springs[2].center = Some(sk.find("c2_0").unwrap());
    bones.springs.push(VrmSpring {
        name: "root".into(),
        joints: vec![VrmJoint {
            joint: 0,
            tail: VrmTail::Local(Vec3::new(0.0, 0.1, 0.05)),
            stiffness: 0.5,
            drag_force: 0.2,
            ..Default::default()
        }],
        collider_groups: vec![],
        center: None,
    });
    for mode in MODES {
        assert_crowd_matches(&sk, &bones, mode, 9, 600);
    }
}

/// The same crowd on one thread and on two, and on the baseline SSE2 path: the same bits.
#[test]
fn vrm_crowd_is_the_same_on_one_and_two_threads() {
    let (sk, bones) = builtin::bench_vrm(8, 6, 8);
    let rig = Arc::new(VrmRig::new(&sk, &bones, VrmOptions::spec()).unwrap());
    let sk = Arc::new(sk);
    let run = |threads: usize, simd: SimdUse| -> Vec<u32> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut crowd = VrmCrowd::new(sk.clone(), rig.clone()).unwrap();
        crowd.set_simd(simd);
        for _ in 0..37 {
            crowd.add();
        }
        let mut inputs = vec![(Transform::IDENTITY, sk.rest().to_vec()); 37];
        pool.install(|| {
            for f in 0..300 {
                for (i, (t, l)) in inputs.iter_mut().enumerate() {
                    *t = motion(&sk, 1, i, f, l);
                }
                crowd
                    .frame(1.0 / 60.0, |i| CrowdPose {
                        transform: inputs[i].0,
                        locals: &inputs[i].1,
                    })
                    .unwrap();
            }
        });
        (0..37)
            .flat_map(|i| (0..rig.links.len()).map(move |k| (i, k)))
            .flat_map(|(i, k)| crowd.rotation(i, k).unwrap().to_array())
            .map(f32::to_bits)
            .collect()
    };
    let one = run(1, SimdUse::Auto);
    assert_eq!(one, run(2, SimdUse::Auto), "1 vs 2 threads");
    assert_eq!(one, run(2, SimdUse::Auto), "run to run");
    assert_eq!(
        one,
        run(2, SimdUse::Avx2),
        "the widest lanes and AVX2 at most"
    );
    assert_eq!(
        one,
        run(2, SimdUse::Portable),
        "the widest lanes and no AVX"
    );
}

/// Bad input names the character, which is held (its state as before); every other
/// character, in its lane group too, steps exactly as in a crowd given only good input;
/// the next good frame goes on. In `spec` mode, and in `fixed` mode with 90 Hz steps, where
/// the held character's last output was an output step's (frame 1 ends half a step after
/// its step) and the frame it is held in ends on a step for everyone else (frame 2).
#[test]
fn vrm_crowd_rejects_bad_input_by_character() {
    let fixed = VrmOptions {
        mode: VrmMode::Fixed,
        step_rate: 90.0,
        ..Default::default()
    };
    for (options, held_at) in [(VrmOptions::spec(), 1), (fixed, 2)] {
        held_by_character(options, held_at);
    }
}

fn held_by_character(options: VrmOptions, held_at: usize) {
    let (sk, bones) = builtin::bench_vrm(4, 5, 2);
    let rig = Arc::new(VrmRig::new(&sk, &bones, options).unwrap());
    let sk = Arc::new(sk);
    let mut crowd = VrmCrowd::new(sk.clone(), rig.clone()).unwrap();
    for _ in 0..20 {
        crowd.add();
    }
    let rest = sk.rest().to_vec();
    let mut bad = rest.clone();
    bad[3].translation.x = f32::NAN;
    let at =
        |f: usize, i: usize| Transform::from_translation(Vec3::X * (f as f32 * 0.05 + i as f32));
    // The same crowd given good input throughout: the reference for everyone but 17.
    let mut good = crowd.clone();
    for f in 0..held_at {
        for c in [&mut crowd, &mut good] {
            c.frame(1.0 / 60.0, |i| CrowdPose {
                transform: at(f, i),
                locals: &rest,
            })
            .unwrap();
        }
    }
    let links = rig.links.len();
    let bits = |c: &VrmCrowd, i: usize| -> Vec<[u32; 4]> {
        (0..links)
            .map(|k| c.rotation(i, k).unwrap().to_array().map(f32::to_bits))
            .collect()
    };
    let before: Vec<_> = (0..20).map(|i| bits(&crowd, i)).collect();
    let err = crowd
        .frame(1.0 / 60.0, |i| CrowdPose {
            transform: at(held_at, i),
            locals: if i == 17 { &bad } else { &rest },
        })
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("crowd character 17") && err.contains(sk.name(3)),
        "{err}"
    );
    let held: Vec<usize> = crowd.held().map(|(i, _)| i).collect();
    assert_eq!(held, [17]);
    good.frame(1.0 / 60.0, |i| CrowdPose {
        transform: at(held_at, i),
        locals: &rest,
    })
    .unwrap();
    for i in 0..20 {
        if i == 17 {
            assert_eq!(bits(&crowd, i), before[i], "17 is held");
        } else {
            assert_ne!(bits(&crowd, i), before[i], "character {i} stepped");
            assert_eq!(bits(&crowd, i), bits(&good, i), "character {i}");
        }
    }
    let short = &rest[..3];
    let err = crowd
        .frame(1.0 / 60.0, |i| CrowdPose {
            transform: at(held_at + 1, i),
            locals: if i == 4 { short } else { &rest },
        })
        .unwrap_err();
    assert!(err.to_string().contains("expected"), "{err}");
    assert!(crowd
        .frame(f32::NAN, |_| CrowdPose {
            transform: Transform::IDENTITY,
            locals: &rest,
        })
        .is_err());
    crowd
        .frame(1.0 / 60.0, |i| CrowdPose {
            transform: at(held_at + 2, i),
            locals: &rest,
        })
        .unwrap();
    assert!(crowd.rotation(20, 0).is_none() && crowd.reset(20).is_err());
}

/// Every kind of bad local the single-character check rejects (not finite, beyond the
/// coordinate limit, not a unit rotation), on every joint of the skeleton (with joints the
/// crowd computes and joints it only checks), makes the frame fail naming that character
/// and that joint; what the check accepts (a rotation slightly off unit) passes.
#[test]
fn vrm_crowd_checks_every_joint_of_every_character() {
    let (sk, bones) = builtin::bench_vrm(3, 4, 2);
    // An extra joint no spring reads: checked, not computed.
    let mut b = tassel::SkeletonBuilder::new();
    for j in 0..sk.len() {
        b.add(sk.name(j), sk.parent(j), sk.rest()[j]);
    }
    let extra = b.add("extra", Some(0), Transform::IDENTITY);
    let (built, remap) = b.build().unwrap();
    // Depth-first already: the joints the bones name keep their indices.
    assert!((0..extra).all(|j| remap[j] == j), "{remap:?}");
    let extra = remap[extra];
    let sk = Arc::new(built);
    let rig = Arc::new(VrmRig::new(&sk, &bones, VrmOptions::spec()).unwrap());
    let rest = sk.rest().to_vec();
    type Spoil = fn(&mut Transform);
    let corrupt: [(&str, Spoil); 5] = [
        ("NaN translation", |t| t.translation.y = f32::NAN),
        ("infinite scale", |t| t.scale.z = f32::INFINITY),
        ("huge translation", |t| t.translation.x = 1e30),
        ("rotation of length 2", |t| t.rotation *= 2.0),
        ("NaN rotation", |t| t.rotation.w = f32::NAN),
    ];
    let mut crowd = VrmCrowd::new(sk.clone(), rig).unwrap();
    for _ in 0..11 {
        crowd.add();
    }
    for j in 0..sk.len() {
        for (what, spoil) in &corrupt {
            let mut bad = rest.clone();
            spoil(&mut bad[j]);
            let err = crowd
                .frame(1.0 / 60.0, |i| CrowdPose {
                    transform: Transform::IDENTITY,
                    locals: if i == 9 { &bad } else { &rest },
                })
                .expect_err(&format!("{what} on joint {j} passed"))
                .to_string();
            assert!(
                err.contains("crowd character 9") && err.contains(&format!("'{}'", sk.name(j))),
                "{what} on joint {j}: {err}"
            );
        }
        // Within the check's tolerance (|len² − 1| ≤ 0.21): accepted.
        let mut fine = rest.clone();
        fine[j].rotation *= 1.05;
        crowd
            .frame(1.0 / 60.0, |i| CrowdPose {
                transform: Transform::IDENTITY,
                locals: if i == 9 { &fine } else { &rest },
            })
            .unwrap_or_else(|e| panic!("joint {j}: {e}"));
    }
    assert_eq!(sk.name(extra), "extra");
}

/// Characters swapped mid-run (`swap`: across lane groups and within one), removed
/// (`swap_remove`, the last taking the index) and added again: everyone left carries on
/// with the bits of their own `CharacterSim`, and a character added into a freed lane
/// starts afresh.
#[test]
fn vrm_crowd_removes_and_adds_characters() {
    let (sk, bones) = builtin::bench_vrm(6, 5, 8);
    for (mode, step_rate) in [(VrmMode::Spec, 60.0), (VrmMode::Fixed, 90.0)] {
        let options = VrmOptions {
            mode,
            step_rate,
            ..Default::default()
        };
        let rig = Arc::new(VrmRig::new(&sk, &bones, options).unwrap());
        let mut crowd = VrmCrowd::new(Arc::new(sk.clone()), rig).unwrap();
        let new_sim = || {
            CharacterSim::with_vrm(sk.clone(), &RigSettings::default(), &bones, options).unwrap()
        };
        // (identity for the motion's phase, its own simulation), in crowd index order.
        let mut people: Vec<(usize, CharacterSim)> = (0..17).map(|id| (id, new_sim())).collect();
        for _ in 0..17 {
            crowd.add();
        }
        let mut next_id = 17;
        let mut inputs: Vec<(Transform, Vec<Transform>)> = Vec::new();
        let (mut locals, mut models) = (sk.rest().to_vec(), sk.rest().to_vec());
        for f in 0..300 {
            match f {
                60 => {
                    // Across lane groups, within one, and a character with itself.
                    for (a, b) in [(1, 16), (4, 6), (2, 2)] {
                        crowd.swap(a, b).unwrap();
                        people.swap(a, b);
                    }
                }
                100 => {
                    for i in [3, 15, 0, 8] {
                        crowd.swap_remove(i).unwrap();
                        people.swap_remove(i);
                    }
                }
                150 => {
                    for _ in 0..3 {
                        assert_eq!(crowd.add(), people.len());
                        people.push((next_id, new_sim()));
                        next_id += 1;
                    }
                    assert_eq!(crowd.reset_count(people.len() - 1), Some(0));
                }
                _ => {}
            }
            assert_eq!(crowd.len(), people.len());
            inputs.resize(people.len(), (Transform::IDENTITY, sk.rest().to_vec()));
            for (k, (id, _)) in people.iter().enumerate() {
                let (t, l) = &mut inputs[k];
                *t = motion(&sk, 1, *id, f, l);
            }
            crowd
                .frame(1.0 / 60.0, |i| CrowdPose {
                    transform: inputs[i].0,
                    locals: &inputs[i].1,
                })
                .unwrap();
            // Every character's link rotations in one walk, against each one's own sim.
            let links = &crowd.rig().links;
            let mut all = vec![Quat::IDENTITY; people.len() * links.len()];
            crowd.rotations(&mut all).unwrap();
            assert!(
                crowd.rotations(&mut all[1..]).is_err(),
                "a wrong length is refused"
            );
            for (k, (id, sim)) in people.iter_mut().enumerate() {
                let pose = sim.frame(&inputs[k].1, inputs[k].0, 1.0 / 60.0).unwrap();
                for (l, link) in links.iter().enumerate() {
                    assert_eq!(
                        all[k * links.len() + l].to_array().map(f32::to_bits),
                        pose.locals[link.joint]
                            .rotation
                            .to_array()
                            .map(f32::to_bits),
                        "{mode:?} frame {f}: character {id}, link {l}: rotations()"
                    );
                }
                locals.copy_from_slice(&inputs[k].1);
                crowd.write_pose(k, &mut locals, &mut models).unwrap();
                for j in 0..sk.len() {
                    assert_eq!(
                        bits(&locals[j]),
                        bits(&pose.locals[j]),
                        "{mode:?} frame {f}: character {id} at index {k}, joint {j}"
                    );
                }
            }
        }
        assert!(crowd.swap_remove(crowd.len()).is_err());
        assert!(crowd.swap(0, crowd.len()).is_err() && crowd.swap(crowd.len(), 0).is_err());
        while !crowd.is_empty() {
            crowd.swap_remove(0).unwrap();
        }
        crowd.frame(1.0 / 60.0, |_| unreachable!()).unwrap();
    }
}

/// `frame_parts` (the lane groups cut into shares the caller runs, as a game engine's
/// task pool does) gives `frame`'s bits whatever the number of parts and the order or
/// threads they run in, holds a bad character the same way, and runs no part on a bad
/// time step.
#[test]
fn vrm_crowd_parts_give_the_frame_bits() {
    let (sk, bones) = builtin::bench_vrm(8, 6, 8);
    let rig = Arc::new(VrmRig::new(&sk, &bones, VrmOptions::default()).unwrap());
    assert_eq!(rig.options.mode, VrmMode::Fixed);
    let sk = Arc::new(sk);
    let n = 37;
    // parts: 0 = `frame` itself; else how many parts, run backwards or on scoped threads.
    let run = |parts: usize, threads: bool| -> (Vec<u32>, usize, f32) {
        let mut crowd = VrmCrowd::new(sk.clone(), rig.clone()).unwrap();
        for _ in 0..n {
            crowd.add();
        }
        let mut inputs = vec![(Transform::IDENTITY, sk.rest().to_vec()); n];
        let mut held = 0;
        for f in 0..200 {
            for (i, (t, l)) in inputs.iter_mut().enumerate() {
                *t = motion(&sk, 1, i, f, l);
            }
            if f == 50 {
                inputs[20].1[1].rotation = Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0);
            }
            let input = |i: usize| CrowdPose {
                transform: inputs[i].0,
                locals: &inputs[i].1,
            };
            let result = if parts == 0 {
                crowd.frame(dt_at(f), input)
            } else {
                crowd.frame_parts(dt_at(f), input, parts, |jobs| {
                    common::run_parts(jobs, threads, |job| job.run())
                })
            };
            if f == 50 {
                assert!(result
                    .unwrap_err()
                    .to_string()
                    .contains("crowd character 20"));
                assert_eq!(crowd.held().map(|(i, _)| i).collect::<Vec<_>>(), [20]);
                held += 1;
            } else {
                result.unwrap();
            }
        }
        let bits = (0..n)
            .flat_map(|i| (0..rig.links.len()).map(move |k| (i, k)))
            .flat_map(|(i, k)| crowd.rotation(i, k).unwrap().to_array())
            .map(f32::to_bits)
            .collect();
        let swing = (0..n)
            .flat_map(|i| {
                rig.links
                    .iter()
                    .enumerate()
                    .map(move |(k, l)| (i, k, l.joint))
            })
            .map(|(i, k, j)| {
                crowd
                    .rotation(i, k)
                    .unwrap()
                    .angle_between(sk.rest()[j].rotation)
            })
            .fold(0.0f32, f32::max);
        (bits, held, swing)
    };
    let (frame, held, swing) = run(0, false);
    assert_eq!(held, 1);
    // The springs moved (the comparison is not of rest poses).
    assert!(swing > 0.1, "largest swing {swing} rad");
    for parts in [1, 2, 3, 5] {
        for threads in [false, true] {
            assert_eq!(
                frame,
                run(parts, threads).0,
                "{parts} parts, threads {threads}"
            );
        }
    }
    // A bad time step: an error, and no part to run.
    let mut crowd = VrmCrowd::new(sk.clone(), rig.clone()).unwrap();
    crowd.add();
    let rest = sk.rest().to_vec();
    let mut ran = 0;
    let e = crowd.frame_parts(
        -1.0,
        |_| CrowdPose {
            transform: Transform::IDENTITY,
            locals: &rest,
        },
        2,
        |jobs| ran += jobs.count(),
    );
    assert!(e.is_err());
    assert_eq!(ran, 0);
}
