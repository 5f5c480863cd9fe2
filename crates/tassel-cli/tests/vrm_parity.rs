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
    // One folder per test: two tests run `spec` side by side (one with the hook), and a
    // shared folder emptied by one while the other read it failed once.
    let hooked = if hooks.is_some() { "hooked" } else { "plain" };
    let out = tmp(&format!("vrm-parity-{mode}-{hooked}"));
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

/// VRMC_node_constraint 1.0 against `@pixiv/three-vrm-node-constraint` (issue 15): the
/// shared `sphere-collider.gltf` with its springs taken out, rest rotations given to three
/// nodes and three constraints added that depend on one another (the collider node takes
/// node B's rotation at weight 0.7; node D rolls about Y with the collider node at 0.9;
/// node E aims its +X at the collider node at 0.8), while nodes A and B turn (swing and
/// twist, `tests/oracles/node_constraint_oracle.mjs` has the same motion). Every node's
/// world position within 1e-4 m and world rotation within 1e-4 rad of three-vrm's, 120
/// frames.
#[test]
fn node_constraints_match_three_vrm() {
    use base64::Engine;
    use glam::{Quat, Vec3};
    let Some(oracle) = oracle_dir() else { return };
    let Some(src) = testdata("vrm/sphere-collider.gltf") else {
        return;
    };
    // The edited file, its buffer inlined.
    let mut json: Value = serde_json::from_slice(&std::fs::read(&src).unwrap()).unwrap();
    let bin = std::fs::read(src.parent().unwrap().join("sphere_mesh.bin")).unwrap();
    json["buffers"][0]["uri"] = Value::from(format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    ));
    json["extensions"]
        .as_object_mut()
        .unwrap()
        .remove("VRMC_springBone");
    json["extensionsUsed"] = serde_json::json!(["VRMC_node_constraint"]);
    let rot = |axis: [f32; 3], angle: f32| {
        let q = Quat::from_axis_angle(Vec3::from(axis).normalize(), angle);
        serde_json::json!([q.x, q.y, q.z, q.w])
    };
    json["nodes"][1]["rotation"] = rot([0.0, 0.0, 1.0], 0.4);
    json["nodes"][3]["rotation"] = rot([1.0, 0.0, 0.0], -0.5);
    json["nodes"][5]["rotation"] = rot([0.0, 1.0, 1.0], 0.7);
    let constraint = |c: Value| serde_json::json!({"VRMC_node_constraint": {"specVersion": "1.0", "constraint": c}});
    json["nodes"][5]["extensions"] =
        constraint(serde_json::json!({"rotation": {"source": 1, "weight": 0.7}}));
    json["nodes"][3]["extensions"] =
        constraint(serde_json::json!({"roll": {"source": 5, "rollAxis": "Y", "weight": 0.9}}));
    json["nodes"][4]["extensions"] = constraint(
        serde_json::json!({"aim": {"source": 5, "aimAxis": "PositiveX", "weight": 0.8}}),
    );
    let dir = tmp("node-constraints");
    let file = dir.join("constrained.gltf");
    std::fs::write(&file, serde_json::to_vec(&json).unwrap()).unwrap();

    // The oracle.
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/oracles/node_constraint_oracle.mjs"),
        oracle.join("node_constraint_oracle.mjs"),
    )
    .unwrap();
    let (frames, dt) = (120usize, 1.0f64 / 60.0);
    let out = dir.join("oracle.json");
    let run = Command::new("node")
        .current_dir(&oracle)
        .arg("node_constraint_oracle.mjs")
        .arg(&file)
        .args([
            "--frames",
            &frames.to_string(),
            "--dt",
            &format!("{dt:.12}"),
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "oracle: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let reference: Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(reference["constraints"], 3);

    // Tassel: the same file, the same motion.
    let model = tassel_gltf::load(&file).unwrap();
    let vrm = model.vrm.clone().expect("the constraints are read");
    assert_eq!(vrm.springs.node_constraints.len(), 3);
    let sk = &model.skeleton;
    let joint_of = |node: usize| model.joint_to_node.iter().position(|&n| n == node).unwrap();
    let mut sim = tassel::CharacterSim::with_vrm(
        sk.clone(),
        &tassel::dynamics::RigSettings::default(),
        &vrm.springs,
        tassel::dynamics::vrm::VrmOptions::spec(),
    )
    .unwrap();
    let axis = Vec3::new(1.0, 2.0, 3.0).normalize();
    let tau = std::f64::consts::TAU;
    let (mut worst_pos, mut worst_angle) = (0.0f64, 0.0f64);
    // How far each destination (nodes 5, 3, 4) turns from its rest: the constraints act.
    let mut turned = [0.0f32; 3];
    for f in 1..=frames {
        let t = f as f64 * dt;
        let motion1 = Quat::from_axis_angle(axis, (0.8 * (tau * 0.7 * t).sin()) as f32)
            * Quat::from_rotation_y((0.5 * (tau * 1.3 * t).sin()) as f32);
        let motion0 = Quat::from_rotation_z((0.3 * (tau * 0.5 * t).sin()) as f32);
        let mut locals = sk.rest().to_vec();
        let (j0, j1) = (joint_of(0), joint_of(1));
        locals[j1].rotation = sk.rest()[j1].rotation * motion1;
        locals[j0].rotation = sk.rest()[j0].rotation * motion0;
        let pose = sim
            .frame(&locals, tassel::Transform::IDENTITY, dt as f32)
            .unwrap();
        for (k, node) in [5, 3, 4].into_iter().enumerate() {
            let j = joint_of(node);
            turned[k] = turned[k].max(pose.locals[j].rotation.angle_between(sk.rest()[j].rotation));
        }
        let sample = &reference["samples"][f - 1];
        for node in 0..6 {
            let m = pose.models[joint_of(node)];
            let p = &sample["world_pos"][node];
            let q = &sample["world_quat"][node];
            let want_p = Vec3::from([0, 1, 2].map(|k| p[k].as_f64().unwrap() as f32));
            let want_q = Quat::from_array([0, 1, 2, 3].map(|k| q[k].as_f64().unwrap() as f32));
            worst_pos = worst_pos.max((m.translation - want_p).length() as f64);
            // The angle between them from the vector part (robust for small angles).
            let d = (m.rotation.inverse() * want_q).normalize();
            let angle = 2.0 * Vec3::new(d.x, d.y, d.z).length().min(1.0).asin() as f64;
            worst_angle = worst_angle.max(angle);
        }
    }
    println!(
        "node constraints vs three-vrm: worst position {worst_pos:.2e} m, worst rotation {worst_angle:.2e} rad over {frames} frames"
    );
    println!("destinations turned up to {turned:?} rad from their rest");
    assert!(
        turned.iter().all(|&a| a > 0.1),
        "a constraint did not act: {turned:?}"
    );
    assert!(worst_pos <= 1e-4, "{worst_pos} m");
    assert!(worst_angle <= 1e-4, "{worst_angle} rad");
}
