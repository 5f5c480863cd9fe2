//! The flat crowd against the flat character, its reference: each member of a
//! [`FlatCrowd`] gives, bit for bit, what its own [`FlatCharacter`] (reset before its first
//! frame) gives on the same input — for the VRM files of `../shared/testdata/vrm` in every
//! VRM mode (the core's VRM crowd), a chains-only rig (the chain crowd) and the built-in
//! character (springs, cloth, rope: one simulation a character) — through hitches, a
//! member's reset, a removal and a member's bad frame (held, the others unchanged).

mod common;

use common::vrm_files;
use tassel_ffi::{FlatCharacter, FlatCrowd, FLOATS_PER_JOINT};

const F: usize = FLOATS_PER_JOINT;

/// The built-in character as a GLB and its rig file, with only the solvers `keep` lists.
fn builtin(keep: &[&str]) -> (Vec<u8>, String) {
    let glb = common::builtin_glb();
    let mut rig = tassel::builtin::character().rig;
    if !keep.contains(&"chains") {
        rig.chains.clear();
    }
    if !keep.contains(&"springs") {
        rig.springs.clear();
    }
    if !keep.contains(&"cloths") {
        rig.cloths.clear();
    }
    if !keep.contains(&"ropes") {
        rig.ropes.clear();
    }
    (glb, rig.to_toml_string().unwrap())
}

/// Character `i`'s input at frame `f`: its root (swaying, each character its own phase;
/// a jump at frame 40 for character 1) and every joint's animated local (the rest pose,
/// the first read joints turned a little, the turn changing every eighth frame: the
/// frames between repeat the pose, and the crowd is told so).
fn input(kind: &FlatCharacter, read: &[usize], i: usize, f: usize) -> ([f32; F], Vec<f32>) {
    let t = f as f32 / 60.0;
    let phase = i as f32 * 0.7;
    let jump = if i == 1 && f >= 40 { 5.0 } else { 0.0 };
    let (s, c) = ((0.4 * (3.0 * t + phase).sin()) / 2.0).sin_cos();
    let root = [
        i as f32 + 0.3 * (2.0 * t + phase).sin() + jump,
        0.1 * (5.0 * t).cos(),
        0.0,
        0.0,
        s,
        0.0,
        c,
        1.0,
        1.0,
        1.0,
    ];
    let mut locals = vec![0.0; kind.joint_count() * F];
    kind.rest_locals(&mut locals).unwrap();
    // Turn the first two read joints (a hips and a head, say) about x.
    let held = (f / 8 * 8) as f32 / 60.0;
    for (k, &j) in read.iter().take(2).enumerate() {
        common::turn_about_x(&mut locals, j, 0.3 * (4.0 * held + phase + k as f32).sin());
    }
    (root, locals)
}

/// The frame times: 60 Hz with a hitch (0.25 s) and a zero frame.
fn dt(f: usize) -> f32 {
    match f {
        25 => 0.25,
        30 => 0.0,
        _ => 1.0 / 60.0,
    }
}

/// Runs `count` characters of `bytes` + `rig` in `mode` through a crowd and through one
/// flat character each, 80 frames, and checks the written joints bit for bit. Character 2
/// is reset at frame 50; at frame 60 character 0 is removed (the last takes its place);
/// at frame 35 character 3 gets a NaN (held: not stepped, out not written). A member whose
/// read joints have the bits of its last frame's is marked unchanged
/// (`mark_pose_unchanged`, as a caller that knows its clip did not move would).
fn crowd_matches_characters(bytes: &[u8], rig: Option<&str>, mode: Option<&str>, want_kind: &str) {
    let kind = FlatCharacter::load(bytes, rig, mode).unwrap();
    let mut crowd = FlatCrowd::new(&kind);
    assert_eq!(crowd.kind(), want_kind);
    assert_eq!(crowd.mode(), kind.mode());
    assert_eq!(crowd.written_joints(), kind.simulated_joints());
    let count = 5;
    // Each member's reference: its own character, reset (a crowd member starts from its
    // pose on its first frame).
    let mut refs: Vec<(usize, FlatCharacter)> = (0..count)
        .map(|i| {
            assert_eq!(crowd.add(), i);
            let mut c = kind.clone();
            c.reset();
            (i, c)
        })
        .collect();
    let read = crowd.read_joints().to_vec();
    let written = crowd.written_joints().to_vec();
    let mut out = vec![f32::NAN; count * written.len() * F];
    // Each member's (by id) read joints' bits in the last frame.
    let mut last: Vec<Option<Vec<u32>>> = vec![None; count];
    let mut marks = 0;
    for f in 0..80 {
        if f == 50 {
            crowd.reset(2).unwrap();
            refs[2].1.reset();
        }
        if f == 60 {
            crowd.swap_remove(0).unwrap();
            refs.swap_remove(0);
            out.truncate(crowd.len() * written.len() * F);
        }
        let mut roots = Vec::new();
        let mut locals = Vec::new();
        let mut full = Vec::new();
        for (id, _) in &refs {
            let (root, mut l) = input(&kind, &read, *id, f);
            if f == 35 && *id == 3 {
                l[read[read.len() - 1] * F + 3] = f32::NAN;
            }
            roots.extend_from_slice(&root);
            let start = locals.len();
            for &j in &read {
                locals.extend_from_slice(&l[j * F..(j + 1) * F]);
            }
            let bits: Vec<u32> = locals[start..].iter().map(|x| x.to_bits()).collect();
            if last[*id].as_ref() == Some(&bits) {
                crowd.mark_pose_unchanged(full.len()).unwrap();
                marks += 1;
            }
            last[*id] = Some(bits);
            full.push((root, l));
        }
        let before = out.clone();
        let all = crowd.frame(&roots, &locals, &mut out, dt(f)).unwrap();
        assert_eq!(all, f != 35, "frame {f}: held {:?}", crowd.held());
        for (m, ((id, reference), (root, l))) in refs.iter_mut().zip(full).enumerate() {
            let mut want = l.clone();
            let stepped = reference.frame(&root, &mut want, dt(f)).is_ok();
            let slot = &out[m * written.len() * F..(m + 1) * written.len() * F];
            if !stepped {
                assert_eq!((f, *id), (35, 3), "only the NaN frame fails");
                assert_eq!(crowd.held().len(), 1);
                assert_eq!(crowd.held()[0].0, m);
                assert!(
                    crowd.held()[0].1.contains("non-finite"),
                    "{}",
                    crowd.held()[0].1
                );
                let old = &before[m * written.len() * F..(m + 1) * written.len() * F];
                assert!(
                    slot.iter()
                        .zip(old)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "a held character's output is not written"
                );
                continue;
            }
            for (k, &j) in written.iter().enumerate() {
                let got = &slot[k * F..(k + 1) * F];
                let w = &want[j * F..(j + 1) * F];
                assert!(
                    got.iter().zip(w).all(|(a, b)| a.to_bits() == b.to_bits()),
                    "frame {f}, character {id}, joint {j} ({:?}): crowd {got:?}, character {w:?}",
                    kind.joint_name(j)
                );
            }
        }
    }
    assert!(marks > 200, "{marks} marks");
    assert!(crowd.mark_pose_unchanged(crowd.len()).is_err());
}

#[test]
fn vrm_files_in_a_crowd_match_their_characters_bit_for_bit() {
    let files = vrm_files();
    for file in &files {
        let bytes = std::fs::read(file).unwrap();
        for mode in ["fixed", "spec", "three-vrm"] {
            println!("{} {mode}", file.display());
            crowd_matches_characters(&bytes, None, Some(mode), "vrm");
        }
    }
}

#[test]
fn a_chains_only_rig_runs_on_the_chain_crowd_bit_for_bit() {
    let (glb, rig) = builtin(&["chains"]);
    for mode in ["fixed", "classic"] {
        crowd_matches_characters(&glb, Some(&rig), Some(mode), "chains");
    }
}

#[test]
fn the_builtin_character_runs_one_simulation_a_character_bit_for_bit() {
    let (glb, rig) = builtin(&["chains", "springs", "cloths", "ropes"]);
    crowd_matches_characters(&glb, Some(&rig), None, "characters");
}

#[test]
fn wrong_lengths_and_bad_time_steps_change_nothing() {
    let (glb, rig) = builtin(&["chains"]);
    let kind = FlatCharacter::load(&glb, Some(&rig), None).unwrap();
    let mut crowd = FlatCrowd::new(&kind);
    crowd.add();
    crowd.add();
    let [r, l, o] = crowd.buffer_lengths();
    assert_eq!(r, 2 * F);
    assert_eq!(l, 2 * crowd.read_joints().len() * F);
    assert_eq!(o, 2 * crowd.written_joints().len() * F);
    let (root, full) = input(&kind, crowd.read_joints(), 0, 0);
    let roots = [root, root].concat();
    let mut locals = Vec::new();
    for _ in 0..2 {
        for &j in crowd.read_joints() {
            locals.extend_from_slice(&full[j * F..(j + 1) * F]);
        }
    }
    let mut out = vec![7.0; o];
    let e = crowd
        .frame(&roots[..F], &locals, &mut out, 0.01)
        .unwrap_err();
    assert!(e.contains("roots holds 10 floats"), "{e}");
    let e = crowd
        .frame(&roots, &locals[1..], &mut out, 0.01)
        .unwrap_err();
    assert!(e.contains("locals holds"), "{e}");
    let e = crowd
        .frame(&roots, &locals, &mut out[1..], 0.01)
        .unwrap_err();
    assert!(e.contains("out holds"), "{e}");
    for bad in [-1.0, f32::NAN, f32::INFINITY] {
        let e = crowd.frame(&roots, &locals, &mut out, bad).unwrap_err();
        assert!(e.contains("time step"), "{e}");
    }
    assert!(out.iter().all(|&v| v == 7.0), "nothing written");
    assert!(crowd.reset(2).unwrap_err().contains("does not exist"));
    assert!(crowd.swap_remove(2).unwrap_err().contains("does not exist"));
    // The failed frames changed nothing: the next frame is each character's first.
    assert!(crowd.frame(&roots, &locals, &mut out, 0.01).unwrap());
    let mut reference = kind.clone();
    reference.reset();
    let mut want = full.clone();
    reference.frame(&root, &mut want, 0.01).unwrap();
    for (k, &j) in crowd.written_joints().iter().enumerate() {
        assert_eq!(&out[k * F..(k + 1) * F], &want[j * F..(j + 1) * F]);
    }
}
