//! Helpers shared by the glTF tests: test data and the Khronos validator.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

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
