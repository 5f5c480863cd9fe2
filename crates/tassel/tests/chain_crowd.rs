//! The chain crowd path against the single-character path (`CharacterSim` with the same
//! chains): the same bits, frame after frame, for every character, whatever the thread
//! count.

mod common;

use glam::Vec3;
use std::sync::Arc;
use tassel::crowd::lanes::LANES;
use tassel::crowd::{ChainCrowd, CrowdPose, SimdUse};
use tassel::dynamics::chain::{ChainRig, TimeMode, Wind};
use tassel::dynamics::RigSettings;
use tassel::{builtin, CharacterSim, Skeleton, Transform};

/// Character `i`'s world transform and animated pose at frame `f`: its own phase of a
/// sway, a bob and a turn, the root and one more joint swinging, a teleport of character 2
/// at frame 100.
fn motion(sk: &Skeleton, swing: usize, i: usize, f: usize, locals: &mut [Transform]) -> Transform {
    let t = f as f32 / 60.0 + 0.37 * i as f32;
    let jump = if i == 2 && f >= 100 { 10.0 } else { 0.0 };
    common::sway(sk, swing, t, jump, locals)
}

/// `n` characters through `frames` frames in a crowd and one `CharacterSim` each: every
/// local and model transform and every chain point of every character has the same bits
/// after every frame. Returns the largest distance a point moved from its animated
/// target (the chains really swung).
fn assert_crowd_matches(
    sk: &Skeleton,
    rig: &RigSettings,
    swing: usize,
    n: usize,
    frames: usize,
) -> f32 {
    let chains = Arc::new(ChainRig::new(sk, rig).unwrap());
    let mut crowd = ChainCrowd::new(Arc::new(sk.clone()), chains.clone()).unwrap();
    let mut sims: Vec<CharacterSim> = (0..n)
        .map(|_| {
            crowd.add();
            CharacterSim::new(sk.clone(), rig).unwrap()
        })
        .collect();
    let mut inputs = vec![(Transform::IDENTITY, sk.rest().to_vec()); n];
    let mut locals = sk.rest().to_vec();
    let mut models = sk.rest().to_vec();
    let mut swung = 0.0f32;
    for f in 0..frames {
        if f == 400 {
            crowd.reset(3).unwrap();
            sims[3].reset();
        }
        for (i, (t, l)) in inputs.iter_mut().enumerate() {
            *t = motion(sk, swing, i, f, l);
        }
        let dt = common::dt_with_hitches(f);
        crowd
            .frame(dt, |i| CrowdPose {
                transform: inputs[i].0,
                locals: &inputs[i].1,
            })
            .unwrap();
        // Every character's rotations in one walk, against each one's own sim.
        let rotators: Vec<usize> = chains.rotator_joints().collect();
        let mut all = vec![glam::Quat::IDENTITY; n * rotators.len()];
        crowd.rotations(&mut all).unwrap();
        for (i, sim) in sims.iter_mut().enumerate() {
            let pose = sim.frame(&inputs[i].1, inputs[i].0, dt).unwrap();
            for (k, &j) in rotators.iter().enumerate() {
                assert_eq!(
                    all[i * rotators.len() + k].to_array().map(f32::to_bits),
                    pose.locals[j].rotation.to_array().map(f32::to_bits),
                    "frame {f}, character {i}, rotator {k}: rotations()"
                );
            }
            locals.copy_from_slice(&inputs[i].1);
            crowd.write_pose(i, &mut locals, &mut models).unwrap();
            for j in 0..sk.len() {
                assert_eq!(
                    common::transform_bits(&locals[j]),
                    common::transform_bits(&pose.locals[j]),
                    "frame {f}, character {i}, joint '{}': crowd {:?} vs single {:?}",
                    sk.name(j),
                    locals[j],
                    pose.locals[j]
                );
                assert_eq!(
                    common::transform_bits(&models[j]),
                    common::transform_bits(&pose.models[j]),
                    "frame {f}"
                );
            }
            let state = sim.chain_state();
            for (p, (single, target)) in state
                .output_positions()
                .iter()
                .zip(state.target_positions())
                .enumerate()
            {
                let c = crowd.point(i, p).unwrap();
                assert_eq!(
                    c.to_array().map(f32::to_bits),
                    single.to_array().map(f32::to_bits),
                    "frame {f}, character {i}, point {p}: crowd {c} vs single {single}"
                );
                swung = swung.max(single.distance(*target));
            }
            assert_eq!(
                crowd.teleport_count(i),
                Some(state.teleport_count()),
                "frame {f}, character {i}"
            );
        }
    }
    assert!(
        crowd.teleport_count(2).unwrap() >= 1,
        "the teleport resets character 2"
    );
    swung
}

#[test]
fn chain_crowd_gives_the_single_character_bits_on_the_bench_rig() {
    let (sk, rig) = builtin::bench_character(16, 8, 8);
    let swung = assert_crowd_matches(&sk, &rig, 1, 19, 600);
    assert!(swung > 0.02, "chains barely moved ({swung} m)");
}

#[test]
fn chain_crowd_gives_the_single_character_bits_on_the_builtin_character() {
    let c = builtin::character();
    let rig = RigSettings {
        chains: c.rig.chains.clone(),
        colliders: c.rig.colliders.clone(),
        ..Default::default()
    };
    assert!(!rig.chains.is_empty());
    for mode in [TimeMode::Fixed, TimeMode::Classic] {
        let mut rig = rig.clone();
        for ch in &mut rig.chains {
            ch.mode = mode;
        }
        let swing = c.skeleton.len() / 2;
        let swung = assert_crowd_matches(&c.skeleton, &rig, swing, 11, 500);
        assert!(swung > 0.01, "{mode:?}: chains barely moved ({swung} m)");
    }
}

/// Every chain feature the step has, chain by chain: wind with gusts, a cone limit, the
/// planar constraints, classic mode with each gravity rule, fixed steps at 90 Hz (steps
/// between frames, a powf pull), a step cap, warm-up steps, alpha, a chain that never
/// resets on a teleport; boxes, a plane, an inside limit, spheres and capsules.
#[test]
fn chain_crowd_gives_the_single_character_bits_with_every_feature() {
    let (sk, mut rig) = builtin::bench_character(9, 6, 6);
    for (c, ch) in rig.chains.iter_mut().enumerate() {
        ch.stiffness = 0.2;
        ch.teleport_distance = 2.0;
        common::chain_feature(ch, c, 7);
    }
    common::every_collider_shape(&mut rig);
    let swung = assert_crowd_matches(&sk, &rig, 2, 13, 600);
    assert!(swung > 0.02, "chains barely moved ({swung} m)");
}

#[test]
fn chain_crowd_is_the_same_on_one_and_two_threads_and_without_avx2() {
    let (sk, settings) = builtin::bench_character(8, 6, 8);
    let rig = Arc::new(ChainRig::new(&sk, &settings).unwrap());
    let sk = Arc::new(sk);
    let n = 37;
    let run = |threads: usize, simd: SimdUse| -> Vec<u32> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut crowd = ChainCrowd::new(sk.clone(), rig.clone()).unwrap();
        crowd.set_simd(simd);
        for _ in 0..n {
            crowd.add();
        }
        let mut inputs = vec![(Transform::IDENTITY, sk.rest().to_vec()); n];
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
        (0..n)
            .flat_map(|i| (0..rig.point_count()).map(move |p| (i, p)))
            .flat_map(|(i, p)| crowd.point(i, p).unwrap().to_array())
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
/// the next good frame goes on.
#[test]
fn chain_crowd_rejects_bad_input_by_character() {
    let (sk, settings) = builtin::bench_character(4, 5, 2);
    let rig = Arc::new(ChainRig::new(&sk, &settings).unwrap());
    let sk = Arc::new(sk);
    let mut crowd = ChainCrowd::new(sk.clone(), rig.clone()).unwrap();
    for _ in 0..20 {
        crowd.add();
    }
    let rest = sk.rest().to_vec();
    let mut bad = rest.clone();
    bad[3].translation.x = f32::NAN;
    let at =
        |f: usize, i: usize| Transform::from_translation(Vec3::X * (f as f32 * 0.05 + i as f32));
    for f in 0..2 {
        crowd
            .frame(1.0 / 60.0, |i| CrowdPose {
                transform: at(f, i),
                locals: &rest,
            })
            .unwrap();
    }
    // The same crowd given good input: the reference for everyone but 17.
    let mut good = crowd.clone();
    let points = rig.point_count();
    let bits = |c: &ChainCrowd, i: usize| -> Vec<[u32; 3]> {
        (0..points)
            .map(|k| c.point(i, k).unwrap().to_array().map(f32::to_bits))
            .collect()
    };
    let before: Vec<_> = (0..20).map(|i| bits(&crowd, i)).collect();
    let err = crowd
        .frame(1.0 / 60.0, |i| CrowdPose {
            transform: at(2, i),
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
        transform: at(2, i),
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
    let tip = points - 1;
    let short = &rest[..3];
    let err = crowd
        .frame(1.0 / 60.0, |i| CrowdPose {
            transform: at(3, i),
            locals: if i == 4 { short } else { &rest },
        })
        .unwrap_err();
    assert!(err.to_string().contains("expected"), "{err}");
    let far = Transform::from_translation(Vec3::splat(f32::INFINITY));
    let err = crowd
        .frame(1.0 / 60.0, |i| CrowdPose {
            transform: if i == 9 { far } else { at(4, i) },
            locals: &rest,
        })
        .unwrap_err();
    assert!(err.to_string().contains("crowd character 9"), "{err}");
    for dt in [f32::NAN, -1.0, f32::INFINITY] {
        assert!(crowd
            .frame(dt, |_| CrowdPose {
                transform: Transform::IDENTITY,
                locals: &rest,
            })
            .is_err());
    }
    crowd
        .frame(1.0 / 60.0, |i| CrowdPose {
            transform: at(5, i),
            locals: &rest,
        })
        .unwrap();
    for i in 0..20 {
        assert!(crowd.point(i, tip).unwrap().is_finite());
    }
    assert!(crowd.point(20, 0).is_none() && crowd.reset(20).is_err());
    assert!(crowd.point(0, rig.point_count()).is_none());
    let mut short_locals = rest[..2].to_vec();
    let mut models = rest.clone();
    assert!(crowd.write_pose(0, &mut short_locals, &mut models).is_err());
}

/// Characters swapped mid-run (`swap`: across lane groups and within one), removed
/// (`swap_remove`, the last taking the index) and added again: everyone left carries on
/// with the bits of their own `CharacterSim`, and a character added into a freed lane
/// starts afresh.
#[test]
fn chain_crowd_removes_and_adds_characters() {
    let (sk, mut settings) = builtin::bench_character(6, 5, 8);
    settings.chains[1].wind = Wind {
        direction: Vec3::X,
        speed: 0.01,
        gust: 0.5,
        seed: 11,
        ..Default::default()
    };
    settings.chains[2].target_framerate = 90.0;
    let rig = Arc::new(ChainRig::new(&sk, &settings).unwrap());
    let mut crowd = ChainCrowd::new(Arc::new(sk.clone()), rig.clone()).unwrap();
    // Who is where: the crowd index of each live single-character reference.
    let mut sims: Vec<(usize, CharacterSim)> = Vec::new();
    for k in 0..21 {
        crowd.add();
        sims.push((k, CharacterSim::new(sk.clone(), &settings).unwrap()));
    }
    let mut locals = sk.rest().to_vec();
    let mut models = sk.rest().to_vec();
    let mut inputs = vec![(Transform::IDENTITY, sk.rest().to_vec()); 40];
    for f in 0..240 {
        if f == 30 {
            // Across lane groups, within one, and a character with itself.
            for (a, b) in [(1, 17), (4, 6), (2, 2)] {
                crowd.swap(a, b).unwrap();
                sims.swap(a, b);
            }
        }
        if f == 60 {
            // Remove character 3 (the last takes its index), then the new last one.
            for gone in [3usize, 19] {
                crowd.swap_remove(gone).unwrap();
                let last = sims.len() - 1;
                sims.swap(gone, last);
                sims.pop();
            }
        }
        if f == 120 {
            for _ in 0..4 {
                let k = sims.len() + 100;
                crowd.add();
                sims.push((k, CharacterSim::new(sk.clone(), &settings).unwrap()));
            }
        }
        // Each character's motion follows its identity, not its index.
        for (i, (who, _)) in sims.iter().enumerate() {
            let (t, l) = &mut inputs[i];
            *t = motion(&sk, 1, *who, f, l);
        }
        crowd
            .frame(1.0 / 60.0, |i| CrowdPose {
                transform: inputs[i].0,
                locals: &inputs[i].1,
            })
            .unwrap();
        assert_eq!(crowd.len(), sims.len());
        for (i, (who, sim)) in sims.iter_mut().enumerate() {
            let pose = sim.frame(&inputs[i].1, inputs[i].0, 1.0 / 60.0).unwrap();
            locals.copy_from_slice(&inputs[i].1);
            crowd.write_pose(i, &mut locals, &mut models).unwrap();
            for j in 0..sk.len() {
                assert_eq!(
                    common::transform_bits(&locals[j]),
                    common::transform_bits(&pose.locals[j]),
                    "frame {f}, index {i} (character {who}), joint {j}"
                );
            }
        }
    }
    assert!(crowd.swap(0, crowd.len()).is_err() && crowd.swap(crowd.len(), 0).is_err());
}

/// A pose whose every joint is within the input limits but whose model pose overflows
/// (scales of 1e6 compounding down a chain) names the first joint, in skeleton order,
/// whose model transform is not finite, found here by the scalar model-pose job; the
/// other lane groups step.
#[test]
fn chain_crowd_names_the_joint_whose_model_pose_overflows() {
    use tassel::LocalToModelJob;
    let (sk, settings) = builtin::bench_character(2, 9, 2);
    let rig = Arc::new(ChainRig::new(&sk, &settings).unwrap());
    let sk = Arc::new(sk);
    let mut crowd = ChainCrowd::new(sk.clone(), rig).unwrap();
    // Character 3 in the first lane group, `LANES + 2` in the second.
    let other = LANES + 2;
    for _ in 0..LANES + 4 {
        crowd.add();
    }
    let rest = sk.rest().to_vec();
    let mut huge = rest.clone();
    for t in &mut huge {
        t.scale = Vec3::splat(1.0e6);
    }
    assert!(huge.iter().all(|t| t.within_limits()));
    let mut models = rest.clone();
    LocalToModelJob {
        skeleton: &sk,
        root: Transform::IDENTITY,
        locals: &huge,
        models: &mut models,
    }
    .run()
    .unwrap();
    let first = models
        .iter()
        .position(|t| !t.is_finite())
        .expect("the pose overflows");
    let tip = crowd.rig().point_count() - 1;
    let before = crowd.point(other, tip).unwrap();
    let err = crowd
        .frame(1.0 / 60.0, |i| CrowdPose {
            transform: Transform::from_translation(Vec3::X * i as f32),
            locals: if i == 3 { &huge } else { &rest },
        })
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("crowd character 3") && err.contains(&format!("'{}'", sk.name(first))),
        "{err} (expected joint {})",
        sk.name(first)
    );
    assert_ne!(
        crowd.point(other, tip).unwrap(),
        before,
        "the second lane group stepped"
    );
}

/// The crowd accepts and rejects an animated pose exactly where the single-character
/// path does (`CharacterSim::frame`, `Transform::within_limits`): rotations whose squared
/// norm lies just inside and just outside the accepted band, coordinates and scales at
/// the limit and one step of `f32` beyond it, NaN and infinity; a rejected pose names
/// the same joint. Two bad characters in one lane group: the first one is named, whatever
/// is wrong with either.
#[test]
fn chain_crowd_checks_the_input_limits_as_the_single_path() {
    let (sk, settings) = builtin::bench_character(3, 4, 2);
    let rig = Arc::new(ChainRig::new(&sk, &settings).unwrap());
    let arc = Arc::new(sk.clone());
    let mut crowd = ChainCrowd::new(arc, rig).unwrap();
    for _ in 0..12 {
        crowd.add();
    }
    let rest = sk.rest().to_vec();
    let max = tassel::limits::MAX_COORDINATE;
    let beyond = f32::from_bits(max.to_bits() + 1);
    let j = 5;
    let mut variants: Vec<Transform> = Vec::new();
    for norm2 in [0.79f32, 1.21] {
        for d in [-2e-4f32, -1e-6, 1e-6, 2e-4] {
            let mut t = rest[j];
            let unit = glam::Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.3);
            t.rotation = glam::Quat::from_array(unit.to_array().map(|c| c * (norm2 + d).sqrt()));
            variants.push(t);
        }
    }
    for v in [max, -max, beyond, -beyond, f32::INFINITY, f32::NAN] {
        let mut t = rest[j];
        t.translation.y = v;
        variants.push(t);
        let mut t = rest[j];
        t.scale.z = v;
        variants.push(t);
    }
    let mut t = rest[j];
    t.rotation.w = f32::NAN;
    variants.push(t);
    let (mut accepted, mut rejected) = (0, 0);
    for (k, v) in variants.iter().enumerate() {
        let mut pose = rest.clone();
        pose[j] = *v;
        let mut sim = CharacterSim::new(sk.clone(), &settings).unwrap();
        let single = sim.frame(&pose, Transform::IDENTITY, 1.0 / 60.0);
        let crowd_says = crowd.frame(1.0 / 60.0, |i| CrowdPose {
            transform: Transform::IDENTITY,
            locals: if i == 5 { &pose } else { &rest },
        });
        match (single, crowd_says) {
            (Ok(_), Ok(())) => accepted += 1,
            (Err(_), Err(e)) => {
                let e = e.to_string();
                assert!(
                    e.contains("crowd character 5") && e.contains(&format!("'{}'", sk.name(j))),
                    "variant {k} ({v:?}): {e}"
                );
                rejected += 1;
            }
            (single, crowd) => panic!("variant {k} ({v:?}): single {single:?}, crowd {crowd:?}"),
        }
    }
    // Counted by hand: inside the band (2 of 4 near each end) and at ± the limit (2 × 2)
    // accepted; outside the band, one step beyond the limit, infinity and NaN rejected.
    assert_eq!((accepted, rejected), (8, 13));
    // Two bad characters in lane group 0: a bad local at 2 and a bad transform at 6, and
    // the other way round; the first is named.
    let mut bad = rest.clone();
    bad[j].translation.x = f32::NAN;
    let far = Transform::from_translation(Vec3::splat(f32::INFINITY));
    for (local_at, transform_at) in [(2, 6), (6, 2)] {
        let e = crowd
            .frame(1.0 / 60.0, |i| CrowdPose {
                transform: if i == transform_at {
                    far
                } else {
                    Transform::IDENTITY
                },
                locals: if i == local_at { &bad } else { &rest },
            })
            .unwrap_err()
            .to_string();
        let first = local_at.min(transform_at);
        assert!(e.contains(&format!("crowd character {first}:")), "{e}");
    }
}

/// `frame_parts` (the lane groups cut into shares the caller runs, as a game engine's
/// task pool does) gives `frame`'s bits whatever the number of parts and the order or
/// threads they run in, and runs no part on a bad time step.
#[test]
fn chain_crowd_parts_give_the_frame_bits() {
    let (sk, settings) = builtin::bench_character(8, 6, 8);
    let rig = Arc::new(ChainRig::new(&sk, &settings).unwrap());
    let sk = Arc::new(sk);
    let n = 37;
    let run = |parts: usize, threads: bool| -> (Vec<u32>, f32) {
        let mut crowd = ChainCrowd::new(sk.clone(), rig.clone()).unwrap();
        for _ in 0..n {
            crowd.add();
        }
        let mut inputs = vec![(Transform::IDENTITY, sk.rest().to_vec()); n];
        let mut first = Vec::new();
        for f in 0..200 {
            for (i, (t, l)) in inputs.iter_mut().enumerate() {
                *t = motion(&sk, 1, i, f, l);
            }
            let input = |i: usize| CrowdPose {
                transform: inputs[i].0,
                locals: &inputs[i].1,
            };
            if parts == 0 {
                crowd.frame(1.0 / 60.0, input)
            } else {
                crowd.frame_parts(1.0 / 60.0, input, parts, |jobs| {
                    common::run_parts(jobs, threads, |job| job.run())
                })
            }
            .unwrap();
            if f == 0 {
                first = (0..rig.point_count())
                    .map(|p| crowd.point(0, p).unwrap())
                    .collect();
            }
        }
        let moved = (0..rig.point_count())
            .map(|p| crowd.point(0, p).unwrap().distance(first[p]))
            .fold(0.0f32, f32::max);
        let bits = (0..n)
            .flat_map(|i| (0..rig.point_count()).map(move |p| (i, p)))
            .flat_map(|(i, p)| crowd.point(i, p).unwrap().to_array())
            .map(f32::to_bits)
            .collect();
        (bits, moved)
    };
    let (frame, moved) = run(0, false);
    assert!(moved > 0.05, "the chains move ({moved} m)");
    for parts in [1, 2, 3, 5] {
        for threads in [false, true] {
            assert_eq!(
                frame,
                run(parts, threads).0,
                "{parts} parts, threads {threads}"
            );
        }
    }
    let mut crowd = ChainCrowd::new(sk.clone(), rig.clone()).unwrap();
    crowd.add();
    let rest = sk.rest().to_vec();
    let mut ran = 0;
    let e = crowd.frame_parts(
        f32::NAN,
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
