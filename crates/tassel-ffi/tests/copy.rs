//! `tassel_character_copy` / `FlatCharacter::fresh_copy`: a copy of a character is the
//! character a new load of the same file, rig and mode makes, whatever the original did
//! before (it stepped, it was freed), and it shares the original's compiled rig. Checked
//! against new loads, bit for bit over a swaying, animated motion, on the built-in VRM
//! avatar in every VRM mode and on the built-in character's whole rig (chains, springs,
//! cloth, rope) in every mode that takes it.

mod common;

use std::sync::Arc;
use tassel_ffi::abi::{
    tassel_character_copy, tassel_character_free, tassel_character_load, tassel_frame,
};
use tassel_ffi::{FlatCharacter, FLOATS_PER_JOINT};

const F: usize = FLOATS_PER_JOINT;

/// The character's root at frame `f` (swaying, turning) and its animated locals: the rest
/// pose with every third joint turned about x.
fn input(c: &FlatCharacter, f: usize) -> ([f32; F], Vec<f32>) {
    let t = f as f32 / 60.0;
    let root = common::swaying_root(f);
    let mut locals = vec![0.0; c.joint_count() * F];
    c.rest_locals(&mut locals).unwrap();
    for j in (0..c.joint_count()).step_by(3) {
        common::turn_about_x(&mut locals, j, 0.3 * (4.0 * t + j as f32).sin());
    }
    (root, locals)
}

/// `frames` frames of the motion from frame `from` at `dt`: every frame's output locals.
fn run(c: &mut FlatCharacter, from: usize, frames: usize, dt: f32) -> Vec<Vec<f32>> {
    (from..from + frames)
        .map(|f| {
            let (root, mut locals) = input(c, f);
            c.frame(&root, &mut locals, dt).unwrap();
            locals
        })
        .collect()
}

/// A file to copy characters of: its name, bytes, rig file (or its VRM springs) and the
/// modes it runs in.
type Case = (String, Vec<u8>, Option<String>, &'static [&'static str]);

fn cases() -> Vec<Case> {
    let avatar = tassel_gltf::builtin_avatar().unwrap();
    let rig = tassel::builtin::character().rig.to_toml_string().unwrap();
    vec![
        (
            "the built-in avatar (VRM springs)".into(),
            avatar,
            None,
            &["fixed", "spec", "three-vrm"],
        ),
        (
            "the built-in character's rig".into(),
            common::builtin_glb(),
            Some(rig),
            &["fixed", "classic", "kawaii", "spcr"],
        ),
    ]
}

#[test]
fn a_copy_steps_as_a_new_load_of_the_same_file() {
    for (name, bytes, rig, modes) in cases() {
        for &mode in modes {
            let load = || FlatCharacter::load(&bytes, rig.as_deref(), Some(mode)).unwrap();
            // The original steps 40 frames first: its state must not reach the copy.
            let mut original = load();
            let stepped = run(&mut original, 0, 40, 1.0 / 60.0);
            let mut copy = original.fresh_copy().unwrap();
            assert!(
                Arc::ptr_eq(original_rig(&original), original_rig(&copy)),
                "{name} {mode}: the copy compiled a rig of its own"
            );
            assert_eq!(copy.mode(), original.mode());
            assert_eq!(copy.read_joints(), original.read_joints());
            assert_eq!(copy.simulated_joints(), original.simulated_joints());
            drop(original);
            let mut fresh = load();
            // 60 Hz, then 144 Hz frames, then a hitch: the fixed clock and the modes' own.
            for (from, frames, dt) in [(0, 50, 1.0 / 60.0), (50, 50, 1.0 / 144.0), (100, 3, 0.2)] {
                let a = run(&mut copy, from, frames, dt);
                let b = run(&mut fresh, from, frames, dt);
                for (f, (a, b)) in a.iter().zip(&b).enumerate() {
                    let same = a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
                    assert!(
                        same,
                        "{name} {mode}: frame {} differs from a new load",
                        from + f
                    );
                }
            }
            // And the motion moves the simulated joints (the comparison compares motion):
            // the original's first frames differ from its 40th.
            assert_ne!(stepped[1], stepped[39], "{name} {mode}: nothing moved");
        }
    }
}

fn original_rig(c: &FlatCharacter) -> &Arc<tassel::CharacterRig> {
    c.sim().rig()
}

#[test]
fn the_c_copy_outlives_its_original_and_a_null_is_refused() {
    let bytes = tassel_gltf::builtin_avatar().unwrap();
    let mode = c"fixed";
    // SAFETY: valid bytes and strings; every character freed once.
    unsafe {
        let a = tassel_character_load(bytes.as_ptr(), bytes.len(), std::ptr::null(), mode.as_ptr());
        assert!(!a.is_null(), "{}", common::last_error());
        let b = tassel_character_copy(a);
        assert!(!b.is_null(), "{}", common::last_error());
        tassel_character_free(a);
        let reference = FlatCharacter::load(&bytes, None, Some("fixed")).unwrap();
        let mut fresh = FlatCharacter::load(&bytes, None, Some("fixed")).unwrap();
        for f in 0..30 {
            let (root, locals) = input(&reference, f);
            let mut out = vec![0.0f32; locals.len()];
            let code = tassel_frame(
                b,
                root.as_ptr(),
                locals.as_ptr(),
                out.as_mut_ptr(),
                locals.len(),
                1.0 / 60.0,
            );
            assert_eq!(code, 0, "{}", common::last_error());
            let mut want = locals.clone();
            fresh.frame(&root, &mut want, 1.0 / 60.0).unwrap();
            assert!(
                out.iter()
                    .zip(&want)
                    .all(|(x, y)| x.to_bits() == y.to_bits()),
                "frame {f}"
            );
        }
        tassel_character_free(b);
        assert!(tassel_character_copy(std::ptr::null()).is_null());
        assert!(
            common::last_error().contains("NULL"),
            "{}",
            common::last_error()
        );
    }
}
