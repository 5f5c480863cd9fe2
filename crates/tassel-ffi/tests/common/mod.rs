//! What the tests of the C ABI and the crowd share (each test binary uses part of it).
#![allow(dead_code)]

use std::path::PathBuf;

/// The VRM files of `../shared/testdata/vrm`, sorted (at least five); empty, with a line
/// saying it was skipped, when the folder is missing outside CI.
pub fn vrm_files() -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/testdata/vrm");
    if !dir.is_dir() {
        assert!(
            std::env::var_os("TASSEL_REQUIRE_TESTDATA").is_none(),
            "../shared/testdata is missing and TASSEL_REQUIRE_TESTDATA is set"
        );
        println!("SKIPPED: ../shared/testdata/vrm is missing (CI has shared/ beside the clone)");
        return Vec::new();
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "vrm"))
        .collect();
    files.sort();
    assert!(
        files.len() >= 5,
        "{} VRM files in {}",
        files.len(),
        dir.display()
    );
    files
}

/// The built-in character's skeleton as a GLB (no mesh): the file its rig files run on.
pub fn builtin_glb() -> Vec<u8> {
    let c = tassel::builtin::character();
    let source = tassel_gltf::ExportSource::from_skeleton(&c.skeleton, tassel_gltf::BoneMesh::None);
    tassel_gltf::export_glb(&source, &[]).unwrap()
}

/// Turns joint `j`'s local rotation in `locals` (10 floats a joint) by `angle` about x
/// (applied after it), normalised.
pub fn turn_about_x(locals: &mut [f32], j: usize, angle: f32) {
    let f = tassel_ffi::FLOATS_PER_JOINT;
    let r = &mut locals[j * f + 3..j * f + 7];
    let q = tassel::glam::Quat::from_rotation_x(angle)
        * tassel::glam::Quat::from_xyzw(r[0], r[1], r[2], r[3]);
    r.copy_from_slice(&q.normalize().to_array());
}

/// `tassel_last_error()`'s message (this thread's last error).
pub fn last_error() -> String {
    let p = tassel_ffi::abi::tassel_last_error();
    assert!(!p.is_null());
    // SAFETY: this thread's NUL-terminated error, not NULL (checked).
    unsafe { std::ffi::CStr::from_ptr(p) }
        .to_string_lossy()
        .into_owned()
}

/// A character's root (10 floats) at frame `f` of 60 Hz: swaying along x and y and turning
/// about y.
pub fn swaying_root(f: usize) -> [f32; tassel_ffi::FLOATS_PER_JOINT] {
    let t = f as f32 / 60.0;
    let (s, co) = ((0.4 * (3.0 * t).sin()) / 2.0).sin_cos();
    [
        0.3 * (2.0 * t).sin(),
        0.1 * (5.0 * t).cos(),
        0.0,
        0.0,
        s,
        0.0,
        co,
        1.0,
        1.0,
        1.0,
    ]
}
