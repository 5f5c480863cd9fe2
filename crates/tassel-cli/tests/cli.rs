//! The `tassel` binary end to end: demo output validity and determinism, the simulate
//! contract, and bad input (clear error, non-zero exit, no output file).

mod common;

use common::{tassel, testdata, tmp, validate};
use std::path::Path;

#[test]
fn demo_writes_valid_files_and_is_deterministic() {
    let (a, b) = (tmp("demo-a"), tmp("demo-b"));
    for d in [&a, &b] {
        let out = tassel().args(["demo", "--out"]).arg(d).output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains("joints simulated"), "{text}");
        // The run's idle, walk, run, running jump, walk and stop, as the seed's graph
        // sees them.
        assert!(
            text.contains("states: idle > walk_run > jump_start_from_walk_run > jump_loop_from_walk_run > jump_end_from_walk_run > walk_run > idle"),
            "{text}"
        );
        // The door and the platform move the character: the platform carries it for
        // its 3 s ride (180 frames at 60 Hz) and more while it stands on it at rest.
        let carried: usize = text
            .split("carried by the platform on ")
            .nth(1)
            .and_then(|r| r.split(',').next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{text}"));
        assert!(carried >= 180, "{text}");
    }
    let glb = std::fs::read(a.join("demo.glb")).unwrap();
    assert_eq!(
        glb,
        std::fs::read(b.join("demo.glb")).unwrap(),
        "demo.glb differs between runs"
    );
    assert_eq!(
        std::fs::read(a.join("demo.png")).unwrap(),
        std::fs::read(b.join("demo.png")).unwrap()
    );
    assert_eq!(&std::fs::read(a.join("demo.png")).unwrap()[1..4], b"PNG");
    // The rig written beside demo.glb reads back as the built-in character's own.
    let rig = std::fs::read_to_string(a.join("demo.rig.toml")).unwrap();
    assert_eq!(
        tassel::dynamics::RigSettings::from_toml_str(&rig).unwrap(),
        tassel::builtin::character().rig
    );
    if let Some(report) = validate(&a.join("demo.glb")) {
        assert!(report.contains("\"errors\":0"), "{report}");
    }
    // The character as a VRM 1.0 avatar beside it: the importer reads its springs.
    let vrm = tassel_gltf::load(&a.join("demo.vrm")).unwrap();
    let springs = &vrm.vrm.as_ref().expect("demo.vrm has spring bones").springs;
    assert_eq!(springs.springs.len(), 13);
    // The baked clip has one key per frame: 18.5 s at 60 Hz = 1 111 keys.
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let doc: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let input = doc["animations"][0]["samplers"][0]["input"]
        .as_u64()
        .unwrap() as usize;
    assert_eq!(doc["accessors"][input]["count"], 1111);
    assert!((doc["accessors"][input]["max"][0].as_f64().unwrap() - 18.5).abs() < 1e-4);
}

fn simulate(args: &[&str], out: &Path) -> std::process::Output {
    tassel()
        .arg("simulate")
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn simulate_builtin_follows_the_contract() {
    let d = tmp("sim");
    let out_file = d.join("s.json");
    let out = simulate(
        &[
            "--builtin",
            "--motion",
            "sin",
            "--frames",
            "30",
            "--mode",
            "fixed",
        ],
        &out_file,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&out_file).unwrap()).unwrap();
    assert_eq!(doc["frames"], 30);
    assert_eq!(doc["mode"], "fixed");
    let samples = doc["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 30);
    let joints = doc["joints"].as_array().unwrap();
    assert!(joints.iter().any(|j| j["name"] == "ponytail_0"));
    // root_pos follows amp·sin(2π·freq·t) on x, computed here by hand.
    for s in samples {
        let t = s["t"].as_f64().unwrap();
        let x = s["root_pos"][0].as_f64().unwrap();
        assert!((x - 0.5 * (std::f64::consts::TAU * t).sin()).abs() < 1e-5);
        assert_eq!(s["world_pos"].as_array().unwrap().len(), joints.len());
    }
    // Bone length joint → tail equals the rest length at every frame.
    let len = |a: &serde_json::Value, b: &serde_json::Value| -> f64 {
        (0..3)
            .map(|k| (a[k].as_f64().unwrap() - b[k].as_f64().unwrap()).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    for (i, _) in joints.iter().enumerate() {
        let rest = len(
            &doc["initial"]["world_pos"][i],
            &doc["initial"]["tail_world_pos"][i],
        );
        for s in samples {
            let l = len(&s["world_pos"][i], &s["tail_world_pos"][i]);
            assert!((l - rest).abs() < 1e-4, "joint {i}: {l} vs {rest}");
        }
    }
}

#[test]
fn simulate_builtin_with_the_skirt_of_chains_and_constraints() {
    let d = tmp("skirt-chains");
    let out_file = d.join("s.json");
    let rig = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/rigs/skirt-chains.toml");
    let out = simulate(
        &[
            "--builtin",
            "--rig",
            rig.to_str().unwrap(),
            "--motion",
            "sin",
            "--frames",
            "60",
        ],
        &out_file,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&out_file).unwrap()).unwrap();
    let joints = doc["joints"].as_array().unwrap();
    // Every skirt bone but the columns' roots (and their rotating roots) is simulated.
    let skirt = joints
        .iter()
        .filter(|j| j["name"].as_str().unwrap().starts_with("skirt_"))
        .count();
    assert_eq!(skirt, 32, "{joints:?}");
    let last = doc["samples"].as_array().unwrap().last().unwrap();
    let finite = last["world_pos"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|p| p.as_array().unwrap())
        .all(|v| v.as_f64().is_some_and(f64::is_finite));
    assert!(finite);
}

#[test]
fn simulate_gltf_with_rig() {
    let Some(fox) = testdata("gltf/Fox.glb") else {
        return;
    };
    let d = tmp("fox");
    let rig = d.join("fox.toml");
    std::fs::write(&rig, "[[chain]]\nname = \"tail\"\nroot = \"b_Tail01_012\"\nradius = 1.0\ngravity = [0.0, -981.0, 0.0]\nteleport_distance = 0.0\n").unwrap();
    let out_file = d.join("fox.json");
    let out = simulate(
        &[
            fox.to_str().unwrap(),
            "--rig",
            rig.to_str().unwrap(),
            "--motion",
            "sin",
            "--amp",
            "30",
        ],
        &out_file,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&out_file).unwrap()).unwrap();
    let names: Vec<&str> = doc["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["name"].as_str().unwrap())
        .collect();
    assert!(names.contains(&"b_Tail01_012"), "{names:?}");
    // The tail swings: its tip leaves the rigidly carried rest position.
    let s = &doc["samples"][59];
    let last = names.len() - 1;
    let tip_x = s["tail_world_pos"][last][0].as_f64().unwrap();
    let rigid_x = doc["initial"]["tail_world_pos"][last][0].as_f64().unwrap()
        + s["root_pos"][0].as_f64().unwrap();
    assert!(
        (tip_x - rigid_x).abs() > 0.1,
        "tail did not swing: {tip_x} vs {rigid_x}"
    );
}

fn assert_fails(args: &[&str], out: &Path, needle: &str) {
    let o = simulate(args, out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{args:?} succeeded");
    assert!(
        err.contains(needle),
        "{args:?}: error '{err}' does not mention '{needle}'"
    );
    assert!(!out.exists(), "{args:?} left {}", out.display());
}

#[test]
fn bad_input_fails_cleanly() {
    let d = tmp("bad");
    let out = d.join("never.json");
    let rig = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let missing = rig(
        "missing.toml",
        "[[chain]]\nname = \"x\"\nroot = \"no_such_bone\"\n",
    );
    assert_fails(&["--builtin", "--rig", &missing], &out, "no_such_bone");
    let negative = rig(
        "neg.toml",
        "[[chain]]\nname = \"p\"\nroot = \"ponytail_0\"\n[[collider]]\nname = \"h\"\nbone = \"head\"\nshape = \"sphere\"\nradius = -0.1\n",
    );
    assert_fails(&["--builtin", "--rig", &negative], &out, "radius");
    let nan = rig(
        "nan.toml",
        "[[chain]]\nname = \"p\"\nroot = \"ponytail_0\"\nstiffness = nan\n",
    );
    assert_fails(&["--builtin", "--rig", &nan], &out, "stiffness");
    let itself = rig(
        "itself.toml",
        "[[chain]]\nname = \"p\"\nroot = \"ponytail_0\"\n[[bone_constraint]]\nbone1 = \"ponytail_2\"\nbone2 = \"ponytail_2\"\n",
    );
    assert_fails(&["--builtin", "--rig", &itself], &out, "bone_constraint #1");
    assert_fails(&["--builtin", "--dt", "1000"], &out, "--dt");
    assert_fails(&["--builtin", "--dt", "NaN"], &out, "--dt");
    if let Some(fox) = testdata("gltf/Fox.glb") {
        let bytes = std::fs::read(fox).unwrap();
        let cut = d.join("cut.glb");
        std::fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
        let ok_rig = rig(
            "ok.toml",
            "[[chain]]\nname = \"t\"\nroot = \"b_Tail01_012\"\n",
        );
        assert_fails(&[cut.to_str().unwrap(), "--rig", &ok_rig], &out, "cut.glb");
    }
    let cycle = d.join("cycle.gltf");
    std::fs::write(&cycle, r#"{"asset":{"version":"2.0"},"nodes":[{"name":"a","children":[1]},{"name":"b","children":[0]}],"skins":[{"joints":[0,1]}]}"#).unwrap();
    let r = rig("ab.toml", "[[chain]]\nname = \"t\"\nroot = \"a\"\n");
    assert_fails(&[cycle.to_str().unwrap(), "--rig", &r], &out, "cycle");
    // An output folder that does not exist: error, nothing written.
    let o = tassel()
        .args(["simulate", "--builtin", "--out", "/no/such/dir/x.json"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("/no/such/dir"));
}

#[test]
fn sample_prints_hand_checkable_values() {
    let Some(fox) = testdata("gltf/Fox.glb") else {
        return;
    };
    let d = tmp("sample");
    let out_file = d.join("s.json");
    let t = (1.0f64 / 48.0).to_string();
    let o = tassel()
        .args([
            "sample",
            fox.to_str().unwrap(),
            "--clip",
            "Survey",
            "--times",
            &format!("0,{t}"),
            "--out",
        ])
        .arg(&out_file)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&out_file).unwrap()).unwrap();
    // b_Head_05 (node 8): half way between its first two keys, read off the file, is
    // their normalised sum.
    let k0 = [-0.100_036_45f64, -0.313_690_57, -0.407_602_5, 0.851_734_2];
    let k1 = [-0.100_419_14f64, -0.310_795_37, -0.410_886_97, 0.851_172_2];
    let sum: Vec<f64> = (0..4).map(|i| k0[i] + k1[i]).collect();
    let norm = sum.iter().map(|x| x * x).sum::<f64>().sqrt();
    let r = &doc["samples"][1]["local_r"][8];
    let dot: f64 = (0..4).map(|i| r[i].as_f64().unwrap() * sum[i] / norm).sum();
    assert!(dot.abs() > 1.0 - 1e-6, "{r}");
    // A node without parent has world position = local translation.
    let s = &doc["samples"][0];
    let root = doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .position(|n| n["name"] == "root")
        .unwrap();
    for k in 0..3 {
        let (w, l) = (
            s["world_pos"][root][k].as_f64().unwrap(),
            s["local_t"][root][k].as_f64().unwrap(),
        );
        assert!((w - l).abs() < 1e-6);
    }
    // A missing clip: a clear error, non-zero exit, no file.
    let bad = d.join("bad.json");
    let o = tassel()
        .args([
            "sample",
            fox.to_str().unwrap(),
            "--clip",
            "Dance",
            "--times",
            "0",
            "--out",
        ])
        .arg(&bad)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("Dance"));
    assert!(!bad.exists());
}

#[test]
fn a_closed_stdout_is_not_a_panic() {
    // `tassel demo | head -0`: the reader is gone before the summary is printed.
    let dir = std::env::temp_dir().join(format!("tassel-pipe-{}", std::process::id()));
    let mut child = tassel()
        .args(["demo", "--out"])
        .arg(&dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "exit {:?}: {err}", out.status);
    assert!(!err.contains("panicked"), "{err}");
    assert!(dir.join("demo.glb").exists() && dir.join("demo.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn simulate_vrm_follows_the_contract() {
    let Some(file) = testdata("vrm/smoke_spring.vrm") else {
        return;
    };
    let d = tmp("vrm");
    let out_file = d.join("s.json");
    let out = simulate(
        &[
            file.to_str().unwrap(),
            "--motion",
            "step",
            "--amp",
            "0.2",
            "--axis",
            "z",
            "--frames",
            "90",
        ],
        &out_file,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&out_file).unwrap()).unwrap();
    // A VRM runs in fixed mode by default (the one default of every stepping switch); the
    // joints are the spring's joints without its last (tail-only) joint: nodes 19, 20, 21
    // with tails 20, 21, 22 (from the file).
    assert_eq!(doc["mode"], "fixed");
    let joints = doc["joints"].as_array().unwrap();
    let nodes: Vec<u64> = joints.iter().map(|j| j["node"].as_u64().unwrap()).collect();
    let tails: Vec<u64> = joints
        .iter()
        .map(|j| j["tail_node"].as_u64().unwrap())
        .collect();
    assert_eq!(nodes, vec![19, 20, 21]);
    assert_eq!(tails, vec![20, 21, 22]);
    assert_eq!(joints[0]["name"], "spring_joint_0");
    // Initial world positions from the file's translations, added up by hand:
    // hips 0.86 + spine 0.1 + chest 0.1 + neck 0.2 + head 0.1 − 0.05 per spring joint.
    let initial = &doc["initial"];
    for (k, y) in [1.31, 1.26, 1.21].iter().enumerate() {
        let p = &initial["world_pos"][k];
        assert!((p[1].as_f64().unwrap() - y).abs() < 1e-5, "{p}");
        let t = &initial["tail_world_pos"][k];
        assert!((t[1].as_f64().unwrap() - (y - 0.05)).abs() < 1e-5, "{t}");
    }
    // The step moved the root 0.2 m along z; the chain swings behind and comes back.
    let samples = doc["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 90);
    assert!((samples[0]["root_pos"][2].as_f64().unwrap() - 0.2).abs() < 1e-6);
    let tip_z = |s: &serde_json::Value| s["tail_world_pos"][2][2].as_f64().unwrap();
    let lag = samples.iter().map(|s| 0.2 - tip_z(s)).fold(0.0, f64::max);
    assert!(lag > 0.01, "the tip did not lag behind the step: {lag}");
    assert!((tip_z(&samples[89]) - 0.2).abs() < 0.01, "not settled back");
    // Fixed mode on request.
    let out = simulate(&[file.to_str().unwrap(), "--mode", "fixed"], &out_file);
    assert!(out.status.success());
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&out_file).unwrap()).unwrap();
    assert_eq!(doc["mode"], "fixed");
}

#[test]
fn inspect_lists_vrm_springs_and_clips() {
    let (Some(vrm), Some(fox)) = (
        testdata("vrm/springbone_extended_plane_pmed.vrm"),
        testdata("gltf/Fox.glb"),
    ) else {
        return;
    };
    let out = tassel().arg("inspect").arg(&vrm).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "(VRMC_springBone 1.0): 1 spring(s), 3 swinging joint(s), 1 collider(s)",
        "'spring_joint_0' (node 19) → 'spring_joint_1' (node 20)",
        "collider 0 on 'head' (node 4): plane through (0.000, -0.080, 0.000) normal (0.000, 1.000, 0.000)",
        "no specVersion",
    ] {
        assert!(text.contains(needle), "missing '{needle}' in:\n{text}");
    }
    let out = tassel().arg("inspect").arg(&fox).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    // Fox.glb: 3 clips; Survey is 3.417 s long (its last key time).
    assert!(text.contains("'Survey': 3.417 s"), "{text}");
    assert!(text.contains("'Walk'") && text.contains("'Run'"), "{text}");
    // A truncated file: a clear error and a non-zero exit.
    let d = tmp("inspect");
    let cut = d.join("cut.glb");
    let bytes = std::fs::read(&fox).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
    let out = tassel().arg("inspect").arg(&cut).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("cut.glb"));
}

/// `tassel bench ARGS`, which must succeed: its standard output.
fn bench_ok(args: &[&str]) -> String {
    let out = tassel().arg("bench").args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// `tassel bench ARGS` must fail, saying `says` on its standard error.
fn bench_refused(args: &[&str], says: &str) {
    let out = tassel().arg("bench").args(args).output().unwrap();
    assert!(!out.status.success(), "{args:?}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains(says), "{args:?}: {stderr}");
}

/// `--crowd N --threads T` ends with the line the crowd figures are read from; `--cloth`
/// times the built-in skirt's 32 free points; bad counts and phase steps are refused;
/// `--cold` runs the crowd path and says so, and is refused where it would not; so is
/// `--still` outside a VRM crowd.
#[test]
fn bench_crowd_and_cloth() {
    let stdout = bench_ok(&[
        "--crowd",
        "3",
        "--threads",
        "2",
        "--frames",
        "5",
        "--runs",
        "1",
    ]);
    // Chains go through the chain crowd path.
    assert!(
        stdout.lines().next().unwrap().contains("crowd path"),
        "{stdout}"
    );
    let last = stdout.lines().last().unwrap();
    assert!(
        last.starts_with("crowd: 3 characters x 112 joints, 2 threads: ")
            && last.contains(" ms per frame, ")
            && last.ends_with(" ns per joint-step"),
        "{last}"
    );
    // So do VRM springs; --compare times the single-character path
    // in the same run and says the ratio before the last line.
    let stdout = bench_ok(&[
        "--vrm",
        "fixed",
        "--crowd",
        "9",
        "--compare",
        "--frames",
        "5",
        "--runs",
        "1",
    ]);
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(lines[0].contains("crowd path"), "{stdout}");
    assert!(
        lines[lines.len() - 2].contains("the crowd path is"),
        "{stdout}"
    );
    assert!(
        lines[lines.len() - 1].starts_with("crowd: 9 characters x 112 joints, 1 threads: "),
        "{stdout}"
    );
    let out = tassel()
        .args(["bench", "--cloth", "--frames", "5", "--runs", "1"])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("32 simulated joints"));
    for bad in [
        &["--crowd", "0"][..],
        &["--crowd", "2", "--threads", "0"][..],
        &["--crowd", "2", "--phase-step", "nan"][..],
        &["--crowd", "2", "--phase-step", "1e9"][..],
    ] {
        bench_refused(bad, "must be");
    }
    // `--cold`: the crowd path with a pose per character and the caches swept, said in
    // the header; refused where it would time something else.
    let stdout = bench_ok(&[
        "--vrm", "spec", "--crowd", "20", "--cold", "--frames", "3", "--runs", "1",
    ]);
    assert!(
        stdout.lines().next().unwrap().contains("; cold: "),
        "{stdout}"
    );
    assert!(stdout
        .lines()
        .last()
        .unwrap()
        .starts_with("crowd: 20 characters x 112 joints, 1 threads: "));
    for bad in [
        &["--crowd", "2", "--cold", "--compare"][..],
        &["--crowd", "2", "--cold", "--cloth"][..],
    ] {
        bench_refused(bad, "--cold times the crowd path only");
    }
    // `--still`: a VRM crowd told its poses do not change, said in the header; refused
    // for the chains, which have no such mark.
    let stdout = bench_ok(&[
        "--vrm", "fixed", "--crowd", "20", "--still", "--frames", "3", "--runs", "1",
    ]);
    assert!(
        stdout.lines().next().unwrap().contains("; still: "),
        "{stdout}"
    );
    bench_refused(&["--crowd", "2", "--still"], "--still marks a VRM crowd");
}

#[test]
fn bench_runs_chains_and_vrm_springs() {
    for extra in [
        &[][..],
        &["--vrm", "spec"][..],
        &["--vrm", "fixed"][..],
        &["--vrm", "three-vrm"][..],
    ] {
        let out = tassel()
            .args(["bench", "--frames", "20", "--runs", "1"])
            .args(extra)
            .output()
            .unwrap();
        assert!(out.status.success(), "{extra:?}");
        // 16 chains of 8 joints below their roots: 16 × 7 simulated joints.
        assert!(
            String::from_utf8_lossy(&out.stdout).contains("112 simulated joints"),
            "{extra:?}"
        );
    }
}

/// `tassel bench FILE`: the user's own character, one and a crowd; the joint count read
/// from the file by hand (`smoke_spring.vrm`: one spring of three joints); a glTF with a
/// rig steps one `CharacterSim` per member; a file that does not exist or a glTF without
/// springs or rig is refused with its name.
#[test]
fn bench_of_a_users_file() {
    let Some(vrm) = testdata("vrm/smoke_spring.vrm") else {
        return;
    };
    // `tassel bench FILE ARGS…`: whether it succeeded, its stdout and its stderr.
    let bench = |file: &std::path::Path, args: &[&str]| {
        let out = tassel().arg("bench").arg(file).args(args).output().unwrap();
        let text = |b: &[u8]| String::from_utf8_lossy(b).to_string();
        (out.status.success(), text(&out.stdout), text(&out.stderr))
    };
    for mode in ["spec", "fixed", "three-vrm"] {
        let (ok, stdout, stderr) = bench(&vrm, &["--vrm", mode, "--frames", "20", "--runs", "1"]);
        assert!(ok, "{mode}: {stderr}");
        assert!(
            stdout.contains("smoke_spring.vrm (25 nodes; 3 VRM spring joints)"),
            "{stdout}"
        );
        assert!(
            stdout.contains("3 simulated joints") && stdout.contains(" us)"),
            "{stdout}"
        );
        let crowd = [
            "--vrm", mode, "--crowd", "20", "--frames", "5", "--runs", "1",
        ];
        let (ok, stdout, _) = bench(&vrm, &crowd);
        assert!(ok, "{mode} crowd");
        assert!(
            stdout.lines().next().unwrap().contains("crowd path"),
            "{stdout}"
        );
        assert!(stdout
            .lines()
            .last()
            .unwrap()
            .starts_with("crowd: 20 characters x 3 joints"));
    }
    if let Some(fox) = testdata("gltf/Fox.glb") {
        let rig =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/rigs/fox.toml");
        let rig = rig.to_str().unwrap();
        let (ok, stdout, stderr) = bench(
            &fox,
            &["--rig", rig, "--crowd", "4", "--frames", "5", "--runs", "1"],
        );
        assert!(ok, "{stderr}");
        assert!(
            stdout.contains("one CharacterSim per character"),
            "{stdout}"
        );
        let (ok, _, stderr) = bench(&fox, &[]);
        assert!(!ok);
        assert!(stderr.contains("--rig"));
    }
    let (ok, _, stderr) = bench(std::path::Path::new("no-such-file.vrm"), &[]);
    assert!(!ok);
    assert!(stderr.contains("no-such-file.vrm"));
}

/// World positions of a sample's tails.
type Points = Vec<[f64; 3]>;

/// Issue 15: `simulate --builtin` lists the joints of every solver (chains, springs, cloth,
/// rope) and, in fixed mode under the issue's sway (`--motion sin --amp 0.3 --freq 1
/// --axis x`), its tails at 30 and 60 Hz stay within 1 % of the 144 Hz run (RMS difference
/// at the instants the runs share, every 1/6 s for 6 s, relative to the tails' RMS
/// dynamic deviation from the character carried rigidly, computed here from the file).
#[test]
fn simulate_builtin_lists_every_solver_and_is_frame_rate_independent() {
    let d = tmp("simrate");
    let run = |hz: u32| {
        let out_file = d.join(format!("s{hz}.json"));
        let frames = (6 * hz).to_string();
        let dt = format!("{:.12}", 1.0 / hz as f64);
        let out = simulate(
            &[
                "--builtin",
                "--mode",
                "fixed",
                "--motion",
                "sin",
                "--amp",
                "0.3",
                "--freq",
                "1",
                "--axis",
                "x",
                "--dt",
                &dt,
                "--frames",
                &frames,
            ],
            &out_file,
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let doc: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&out_file).unwrap()).unwrap();
        let v3 = |v: &serde_json::Value| -> [f64; 3] { [0, 1, 2].map(|i| v[i].as_f64().unwrap()) };
        let names: Vec<String> = doc["joints"]
            .as_array()
            .unwrap()
            .iter()
            .map(|j| j["name"].as_str().unwrap().to_string())
            .collect();
        let initial: Vec<[f64; 3]> = doc["initial"]["tail_world_pos"]
            .as_array()
            .unwrap()
            .iter()
            .map(v3)
            .collect();
        // (tails, rigid tails) at frames f = k·hz/6.
        let samples: Vec<(Points, Points)> = doc["samples"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|s| (s["frame"].as_u64().unwrap() as u32 * 6).is_multiple_of(hz))
            .map(|s| {
                let root = v3(&s["root_pos"]);
                let tails = s["tail_world_pos"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(v3)
                    .collect();
                let rigid = initial
                    .iter()
                    .map(|p| [p[0] + root[0], p[1] + root[1], p[2] + root[2]])
                    .collect();
                (tails, rigid)
            })
            .collect();
        (names, samples)
    };
    let dist2 = |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>();
    let (names, reference) = run(144);
    assert!(names.len() >= 40, "only {} joints listed", names.len());
    for solver in ["ponytail_0", "tail_0", "chest_l", "skirt_0_1", "charm_1"] {
        assert!(names.iter().any(|n| n == solver), "{solver} is not listed");
    }
    let (mut dev2, mut n) = (0.0, 0usize);
    for (tails, rigid) in &reference {
        for (a, b) in tails.iter().zip(rigid) {
            dev2 += dist2(a, b);
            n += 1;
        }
    }
    let dev = (dev2 / n as f64).sqrt();
    for hz in [30, 60] {
        let (other_names, other) = run(hz);
        assert_eq!(other_names, names);
        assert_eq!(other.len(), reference.len());
        let mut d2 = 0.0;
        for ((a, _), (b, _)) in other.iter().zip(&reference) {
            for (p, q) in a.iter().zip(b) {
                d2 += dist2(p, q);
            }
        }
        let rel = (d2 / n as f64).sqrt() / dev;
        println!(
            "simulate --builtin, {} joints: {hz} Hz vs 144 Hz {:.3} % of the RMS dynamic deviation ({:.1} mm)",
            names.len(),
            100.0 * rel,
            dev * 1e3
        );
        assert!(rel <= 0.01, "{hz} Hz: {:.2} %", 100.0 * rel);
    }
}
