//! VRM spring bones, `spec` mode, against the web reference: three-vrm 3.5.5 run headless
//! in Node by `../shared/oracles/springbone_oracle.mjs` with the hook that keeps the
//! specification's fixed bone length (`hooks/fixed_bone_length.mjs`; without it three-vrm
//! re-measures the bone against last frame's matrices, which the specification does not).
//! Every VRM file of `../shared/testdata/vrm`, motions `sin`, `step` and `rotate`, 120
//! frames: every tail within 1e-4 m of three-vrm's on every frame (issue 15).
//!
//! The oracle is installed by `.ci/run` (`npm ci` in a copy at `target/oracles`); where it
//! is missing the test says SKIPPED, unless `TASSEL_REQUIRE_ORACLE` is set (CI).

mod common;
use common::{tassel, testdata, tmp};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn oracle_dir() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/oracles");
    if dir.join("node_modules/@pixiv").is_dir() {
        return Some(dir);
    }
    assert!(
        std::env::var_os("TASSEL_REQUIRE_ORACLE").is_none(),
        "the three-vrm oracle is not installed in target/oracles (see .ci/run)"
    );
    eprintln!("SKIPPED: the three-vrm oracle is not installed in target/oracles (run .ci/run)");
    None
}

/// Largest distance between the two runs' tails, joints matched by glTF node, frames by
/// number; also how many joints were compared.
fn max_tail_distance(oracle: &Value, ours: &Value) -> (f64, usize) {
    let nodes = |v: &Value| -> Vec<u64> {
        v["joints"]
            .as_array()
            .unwrap()
            .iter()
            .map(|j| j["node"].as_u64().unwrap())
            .collect()
    };
    let (na, nb) = (nodes(oracle), nodes(ours));
    let pairs: Vec<(usize, usize)> = na
        .iter()
        .enumerate()
        .filter_map(|(i, n)| nb.iter().position(|m| m == n).map(|k| (i, k)))
        .collect();
    let samples = |v: &Value| v["samples"].as_array().unwrap().clone();
    let (sa, sb) = (samples(oracle), samples(ours));
    let mut worst = 0.0f64;
    for a in &sa {
        let f = a["frame"].as_u64().unwrap();
        let b = sb
            .iter()
            .find(|s| s["frame"].as_u64() == Some(f))
            .unwrap_or_else(|| panic!("frame {f} missing"));
        for &(i, k) in &pairs {
            let p = &a["tail_world_pos"][i];
            let q = &b["tail_world_pos"][k];
            let d: f64 = (0..3)
                .map(|c| (p[c].as_f64().unwrap() - q[c].as_f64().unwrap()).powi(2))
                .sum::<f64>()
                .sqrt();
            worst = worst.max(d);
        }
    }
    (worst, pairs.len())
}

/// Every VRM and glTF file of the test data.
fn files() -> Vec<PathBuf> {
    let Some(vrm_dir) = testdata("vrm") else {
        return vec![];
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(&vrm_dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "vrm" || e == "gltf"))
        .collect();
    files.sort();
    assert!(files.len() >= 8, "{} VRM and glTF files", files.len());
    files
}

/// Runs the oracle (with `hooks`, if any) and `tassel simulate --mode mode` on every file
/// with motions `sin`, `step` and `rotate`, 120 frames; with `limit`, asserts every tail
/// within it on every frame; returns the worst distance.
fn parity(oracle: &Path, hooks: Option<&str>, mode: &str, what: &str, limit: Option<f64>) -> f64 {
    let out = tmp(&format!("vrm-parity-{mode}"));
    let mut worst_all = 0.0f64;
    for file in &files() {
        for motion in ["sin", "step", "rotate"] {
            let (o, t) = (out.join("oracle.json"), out.join("tassel.json"));
            let args = ["--frames", "120", "--motion", motion, "--amp", "0.3"];
            let mut node = Command::new("node");
            node.current_dir(oracle);
            if let Some(h) = hooks {
                node.env("HOOKS", h);
            }
            let run = node
                .arg("springbone_oracle.mjs")
                .arg(file)
                .args(args)
                .arg("--fix-ext-spec")
                .arg("--out")
                .arg(&o)
                .output()
                .unwrap();
            assert!(
                run.status.success(),
                "oracle on {}: {}",
                file.display(),
                String::from_utf8_lossy(&run.stderr)
            );
            let run = tassel()
                .arg("simulate")
                .arg(file)
                .args(["--mode", mode])
                .args(args)
                .arg("--out")
                .arg(&t)
                .output()
                .unwrap();
            assert!(
                run.status.success(),
                "tassel on {}: {}",
                file.display(),
                String::from_utf8_lossy(&run.stderr)
            );
            let read =
                |p: &Path| -> Value { serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap() };
            let (worst, joints) = max_tail_distance(&read(&o), &read(&t));
            let name = file.file_name().unwrap().to_string_lossy();
            println!("{what}: {name} {motion}: {joints} joints, max tail distance {worst:.2e} m");
            assert!(joints > 0, "{name}: no joint in common");
            if let Some(limit) = limit {
                assert!(
                    worst <= limit,
                    "{what}: {name} {motion}: {worst} m from three-vrm"
                );
            }
            worst_all = worst_all.max(worst);
        }
    }
    println!("{what}: worst over every file and motion: {worst_all:.2e} m");
    worst_all
}

#[test]
fn spec_mode_matches_three_vrm_with_the_specifications_bone_length() {
    let Some(oracle) = oracle_dir() else { return };
    if files().is_empty() {
        return;
    }
    parity(
        &oracle,
        Some("hooks/fixed_bone_length.mjs"),
        "spec",
        "spec vs three-vrm with the spec's bone length",
        Some(1e-4),
    );
}

/// `--mode three-vrm` against three-vrm exactly as an app runs it (no hook: the bone
/// length re-measured against last frame's tail). And the difference is real: the same
/// runs in `spec` mode are farther than 1e-4 m from the plain oracle on some file.
#[test]
fn three_vrm_mode_matches_three_vrm_as_an_app_runs_it() {
    let Some(oracle) = oracle_dir() else { return };
    if files().is_empty() {
        return;
    }
    parity(
        &oracle,
        None,
        "three-vrm",
        "three-vrm vs three-vrm",
        Some(1e-4),
    );
    let spec = parity(
        &oracle,
        None,
        "spec",
        "spec vs three-vrm as an app runs it",
        None,
    );
    assert!(
        spec > 1e-3,
        "spec mode should differ from three-vrm's stale bone length: {spec} m"
    );
}
