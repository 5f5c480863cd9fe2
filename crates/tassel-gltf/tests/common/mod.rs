//! Helpers shared by the glTF tests: test data and the Khronos validator.
#![allow(dead_code)]

use glam::{Quat, Vec3};
use std::path::{Path, PathBuf};
use tassel::{Skeleton, Transform};

/// `../shared/testdata/<rel>` from the repository root, or `None` (with a message) when the
/// folder is missing and `TASSEL_REQUIRE_TESTDATA` is not set.
pub fn testdata(rel: &str) -> Option<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/testdata");
    if root.is_dir() {
        return Some(root.join(rel));
    }
    if std::env::var_os("TASSEL_REQUIRE_TESTDATA").is_some() {
        panic!("../shared/testdata is missing (TASSEL_REQUIRE_TESTDATA is set)");
    }
    eprintln!("SKIPPED: ../shared/testdata is missing beside the repository; {rel} not tested");
    None
}

/// The VRM fixtures of `../shared/testdata/vrm` (`.vrm` and `.gltf`), sorted; empty when
/// the test data is missing (see [`testdata`]).
pub fn vrm_files() -> Vec<PathBuf> {
    let Some(dir) = testdata("vrm") else {
        return vec![];
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("vrm" | "gltf")))
        .collect();
    files.sort();
    assert!(
        files.len() >= 8,
        "expected the 8 VRM fixtures, found {files:?}"
    );
    files
}

/// Runs the Khronos validator on `file`; returns (errors, report text), or `None` when the
/// validator is not installed (`npm ci` in tools/) and `TASSEL_REQUIRE_VALIDATOR` is unset.
pub fn validate(file: &Path) -> Option<(u64, String)> {
    let tools = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools");
    if !tools.join("node_modules/gltf-validator").is_dir() {
        if std::env::var_os("TASSEL_REQUIRE_VALIDATOR").is_some() {
            panic!("gltf-validator is not installed: run `npm ci` in tools/");
        }
        eprintln!(
            "SKIPPED: gltf-validator not installed (npm ci in tools/); {} not validated",
            file.display()
        );
        return None;
    }
    let out = std::process::Command::new("node")
        .arg(tools.join("validate.mjs"))
        .arg(file)
        .output()
        .expect("node runs");
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let errors = text
        .split("\"errors\":")
        .nth(1)
        .and_then(|s| s.split(|c: char| !c.is_ascii_digit()).next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| {
            panic!(
                "validator output not understood: {text} {}",
                String::from_utf8_lossy(&out.stderr)
            )
        });
    Some((errors, text))
}

/// Character `i` at frame `f`: its own phase of a sway that rolls it over (so that gravity
/// throws the springs against the colliders), joint 0 and the first spring joint's parent
/// swinging in the animated pose.
pub fn input(
    sk: &Skeleton,
    swing: usize,
    i: usize,
    f: usize,
    locals: &mut [Transform],
) -> Transform {
    let t = f as f32 / 60.0 + 0.29 * i as f32;
    let w = std::f32::consts::TAU * t;
    locals.copy_from_slice(sk.rest());
    locals[swing].rotation =
        sk.rest()[swing].rotation * Quat::from_rotation_x(0.4 * (2.0 * w).sin());
    let roll = std::f32::consts::FRAC_PI_2 * (1.0 - (0.5 * w).cos());
    Transform::from_translation_rotation(
        Vec3::new(
            0.15 * w.sin(),
            0.05 * (1.7 * w).sin(),
            0.1 * (0.6 * w).cos(),
        ),
        Quat::from_rotation_y(0.6 * (0.8 * w).sin()) * Quat::from_rotation_z(roll),
    )
}

/// A transform's 10 floats as bits (for exact comparisons).
pub fn bits(t: &Transform) -> Vec<u32> {
    t.translation
        .to_array()
        .into_iter()
        .chain(t.rotation.to_array())
        .chain(t.scale.to_array())
        .map(f32::to_bits)
        .collect()
}
