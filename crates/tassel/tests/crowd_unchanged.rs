//! `VrmCrowd::mark_pose_unchanged`: a mark that tells the truth changes no bit of any
//! character, through resets, teleports, held characters, moved characters and uneven
//! frames; a mark that lies steps a lane group on last frame's pose where the group kept
//! that pose as it came, and changes nothing elsewhere (so the marks are really used).

use glam::{Quat, Vec3};
use std::sync::Arc;
use tassel::builtin;
use tassel::crowd::{CrowdPose, VrmCrowd};
use tassel::dynamics::vrm::{VrmMode, VrmOptions, VrmRig};
use tassel::{Skeleton, Transform};

/// Character `id`'s animated pose in its version `v`: the root and the first joint below
/// it turned by an amount of both.
fn pose(sk: &Skeleton, id: usize, v: u32) -> Vec<Transform> {
    let mut l = sk.rest().to_vec();
    let a = 0.4 * (id as f32 * 0.7 + v as f32 * 1.3).sin();
    l[0].rotation = sk.rest()[0].rotation * Quat::from_rotation_z(a);
    l[1].rotation = sk.rest()[1].rotation * Quat::from_rotation_x(0.5 * a);
    l
}

/// Character `id`'s world transform at frame `f`: a sway on its own phase; character 33
/// jumps 10 m at frame 50 (past the teleport distance).
fn at(f: usize, id: usize) -> Transform {
    let t = f as f32 / 60.0 + 0.37 * id as f32;
    let jump = if id == 33 && f >= 50 { 10.0 } else { 0.0 };
    Transform::from_translation_rotation(
        Vec3::new(0.4 * (3.0 * t).sin() + jump, 0.1 * (5.0 * t).sin(), 0.0),
        Quat::from_rotation_y(0.5 * (2.0 * t).sin()),
    )
}

/// Frame `f`'s time step: 60 Hz with a hitch, a paused frame, a spell at 45 Hz and one at
/// 144 Hz.
fn dt_at(f: usize) -> f32 {
    match f {
        60 => 0.25,
        61 => 0.0,
        80..90 => 1.0 / 45.0,
        100..106 => 1.0 / 144.0,
        _ => 1.0 / 60.0,
    }
}

fn crowd(options: VrmOptions, n: usize) -> (Arc<Skeleton>, VrmCrowd) {
    let (sk, bones) = builtin::bench_vrm(4, 5, 2);
    let rig = Arc::new(VrmRig::new(&sk, &bones, options).unwrap());
    let sk = Arc::new(sk);
    let mut c = VrmCrowd::new(sk.clone(), rig).unwrap();
    for _ in 0..n {
        c.add();
    }
    (sk, c)
}

fn rotation_bits(c: &VrmCrowd, i: usize) -> Vec<[u32; 4]> {
    (0..c.rig().links.len())
        .map(|k| c.rotation(i, k).unwrap().to_array().map(f32::to_bits))
        .collect()
}

fn fixed(step_rate: f32) -> VrmOptions {
    VrmOptions {
        mode: VrmMode::Fixed,
        step_rate,
        teleport_distance: 2.0,
        ..Default::default()
    }
}

/// Two crowds of 40 characters (three lane groups) given the same input, one marked
/// wherever a character's pose did not change since the last frame that ran: the same
/// bits after every frame. Group 0 never changes its pose, group 1 changes a character
/// now and then, group 2 has a teleport, a reset and a held character; then characters
/// are swapped, removed and added, and at last everyone changes at once.
#[test]
fn true_marks_keep_every_bit() {
    for step_rate in [60.0, 90.0] {
        let (sk, mut plain) = crowd(fixed(step_rate), 40);
        let mut marked = plain.clone();
        // Per crowd index: the character (its phase) and its pose's version.
        let mut ids: Vec<usize> = (0..40).collect();
        let mut versions = vec![0u32; 40];
        let mut ran: Vec<Option<u32>> = vec![None; 40];
        let mut marks = 0;
        for f in 0..160 {
            match f {
                70 => {
                    plain.reset(35).unwrap();
                    marked.reset(35).unwrap();
                }
                110 => {
                    plain.swap(1, 33).unwrap();
                    marked.swap(1, 33).unwrap();
                    ids.swap(1, 33);
                    versions.swap(1, 33);
                    ran.swap(1, 33);
                }
                120 => {
                    plain.swap_remove(5).unwrap();
                    marked.swap_remove(5).unwrap();
                    ids.swap_remove(5);
                    versions.swap_remove(5);
                    ran.swap_remove(5);
                }
                130 => {
                    plain.add();
                    marked.add();
                    ids.push(100);
                    versions.push(0);
                    ran.push(None);
                }
                _ => {}
            }
            for (i, v) in versions.iter_mut().enumerate() {
                if (16..32).contains(&i) && (f + i) % 10 == 0 || f == 150 {
                    *v += 1;
                }
            }
            for (i, v) in versions.iter().enumerate() {
                if ran[i] == Some(*v) {
                    marked.mark_pose_unchanged(i).unwrap();
                    marks += 1;
                }
            }
            let poses: Vec<Vec<Transform>> = (0..ids.len())
                .map(|i| pose(&sk, ids[i], versions[i]))
                .collect();
            let input = |i: usize| CrowdPose {
                transform: if f == 90 && i == 36 {
                    Transform::from_translation(Vec3::NAN)
                } else {
                    at(f, ids[i])
                },
                locals: &poses[i],
            };
            let dt = dt_at(f);
            let a = plain.frame(dt, input);
            let b = marked.frame(dt, input);
            assert_eq!(a.is_err(), f == 90, "frame {f}: {a:?}");
            assert_eq!(b.is_err(), f == 90, "frame {f}: {b:?}");
            for (i, v) in versions.iter().enumerate() {
                ran[i] = Some(*v);
                assert_eq!(
                    rotation_bits(&plain, i),
                    rotation_bits(&marked, i),
                    "{step_rate} Hz steps: frame {f}, character {i}"
                );
            }
        }
        assert!(marks > 4000, "{marks} marks");
        // The teleport and the reset were seen.
        assert_eq!(
            plain.reset_count(ids.iter().position(|&d| d == 33).unwrap()),
            Some(2)
        );
    }
}

/// A mark that lies: a group that kept its last input as it came steps on that pose (the
/// same bits as a crowd given last frame's pose), a group reset in its last frame reads
/// the new pose (the same bits as a crowd not marked), and so does `spec` mode.
#[test]
fn false_marks_step_on_the_kept_pose_only_where_it_was_kept() {
    for options in [fixed(60.0), VrmOptions::spec()] {
        let fixed = options.mode == VrmMode::Fixed;
        let (sk, mut c) = crowd(options, 20);
        let old: Vec<_> = (0..20).map(|i| pose(&sk, i, 0)).collect();
        let new: Vec<_> = (0..20).map(|i| pose(&sk, i, 1)).collect();
        let input = |f: usize, p: &Vec<Vec<Transform>>| {
            let p = p.clone();
            move |i: usize| (at(f, i), p[i].clone())
        };
        let frame = |c: &mut VrmCrowd, f: usize, p: &Vec<Vec<Transform>>| {
            let inp = input(f, p);
            let all: Vec<_> = (0..20).map(inp).collect();
            c.frame(1.0 / 60.0, |i| CrowdPose {
                transform: all[i].0,
                locals: &all[i].1,
            })
            .unwrap();
        };
        for f in 0..10 {
            if f > 0 {
                for i in 0..20 {
                    c.mark_pose_unchanged(i).unwrap();
                }
            }
            if f == 9 {
                // Group 0 (characters 0-15) resets in its last frame before the lie.
                c.reset(3).unwrap();
            }
            frame(&mut c, f, &old);
        }
        let (mut lied, mut honest, mut kept) = (c.clone(), c.clone(), c);
        for i in 0..20 {
            lied.mark_pose_unchanged(i).unwrap();
        }
        frame(&mut lied, 10, &new);
        frame(&mut honest, 10, &new);
        frame(&mut kept, 10, &old);
        for i in 0..20 {
            let l = rotation_bits(&lied, i);
            if fixed && i >= 16 {
                assert_eq!(l, rotation_bits(&kept, i), "character {i}: the kept pose");
                assert_ne!(
                    l,
                    rotation_bits(&honest, i),
                    "character {i}: not the new pose"
                );
            } else {
                assert_eq!(l, rotation_bits(&honest, i), "{options:?}: character {i}");
                assert_ne!(l, rotation_bits(&kept, i), "character {i}: the new pose");
            }
        }
    }
    // The marks are for the next frame only, and only for characters that exist.
    let (_, mut c) = crowd(fixed(60.0), 3);
    assert!(c.mark_pose_unchanged(3).is_err());
}
