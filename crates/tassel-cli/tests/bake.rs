//! `tassel bake` end to end: Fox.glb with the shipped tail rig, a VRM without clips, and
//! bad input. The files are read back by hand (GLB chunks, accessors), not with the
//! loader that wrote them.

mod common;

use common::{accessor_bytes, glb_chunks, read_floats, run_ok, tassel, testdata, tmp, validate};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn fox_rig() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/rigs/fox.toml")
}

/// (node, path) → (times, values) of every channel of animation `a`.
type Channels = BTreeMap<(u64, String), (Vec<f32>, Vec<f32>)>;

fn channels(json: &Value, bin: &[u8], a: usize) -> Channels {
    let anim = &json["animations"][a];
    let mut out = BTreeMap::new();
    for ch in anim["channels"].as_array().unwrap() {
        let s = &anim["samplers"][ch["sampler"].as_u64().unwrap() as usize];
        let key = (
            ch["target"]["node"].as_u64().unwrap(),
            ch["target"]["path"].as_str().unwrap().to_string(),
        );
        let times = read_floats(json, bin, s["input"].as_u64().unwrap() as usize);
        let values = read_floats(json, bin, s["output"].as_u64().unwrap() as usize);
        assert!(
            out.insert(key, (times, values)).is_none(),
            "two channels on one target"
        );
    }
    out
}

/// The input's LINEAR rotation at `t` (normalised lerp in one hemisphere: within 0.1° of
/// slerp for the few-degree steps between Fox keys).
fn rotation_at(times: &[f32], values: &[f32], t: f32) -> [f32; 4] {
    let q = |i: usize| {
        [
            values[4 * i],
            values[4 * i + 1],
            values[4 * i + 2],
            values[4 * i + 3],
        ]
    };
    let k = times.iter().position(|&x| x > t).unwrap_or(times.len());
    if k == 0 {
        return q(0);
    }
    if k == times.len() {
        return q(times.len() - 1);
    }
    let (a, mut b) = (q(k - 1), q(k));
    let s = (t - times[k - 1]) / (times[k] - times[k - 1]);
    if a.iter().zip(&b).map(|(x, y)| x * y).sum::<f32>() < 0.0 {
        b = b.map(|x| -x);
    }
    let r: Vec<f32> = (0..4).map(|i| a[i] + (b[i] - a[i]) * s).collect();
    let n = r.iter().map(|x| x * x).sum::<f32>().sqrt();
    [r[0] / n, r[1] / n, r[2] / n, r[3] / n]
}

fn angle_deg(a: [f32; 4], b: [f32; 4]) -> f32 {
    let d: f32 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
    2.0 * d.abs().min(1.0).acos().to_degrees()
}

#[test]
fn bake_fox_keys_the_tail_and_keeps_everything_else() {
    let Some(fox) = testdata("gltf/Fox.glb") else {
        return;
    };
    let dir = tmp("bake-fox");
    let out = dir.join("fox_baked.glb");
    let run = tassel()
        .arg("bake")
        .arg(&fox)
        .arg("--rig")
        .arg(fox_rig())
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    // Not a terminal: no progress bar in the captured error stream.
    assert!(!String::from_utf8_lossy(&run.stderr).contains('#'));
    validate(&out);
    let (ij, ib) = glb_chunks(&std::fs::read(&fox).unwrap());
    let (oj, ob) = glb_chunks(&std::fs::read(&out).unwrap());
    // Three clips, same names, same order.
    let names = |j: &Value| -> Vec<String> {
        j["animations"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a["name"].as_str().unwrap().to_string())
            .collect()
    };
    assert_eq!(names(&oj), vec!["Survey", "Walk", "Run"]);
    assert_eq!(names(&oj), names(&ij));
    // Nodes, meshes, skins, materials, textures, images: the same JSON, and the mesh and
    // skin data the same bytes.
    for key in [
        "nodes",
        "scenes",
        "meshes",
        "skins",
        "materials",
        "textures",
        "images",
    ] {
        assert_eq!(oj.get(key), ij.get(key), "{key} changed");
    }
    let prim = &ij["meshes"][0]["primitives"][0];
    let mut accessors: Vec<u64> = prim["attributes"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .collect();
    accessors.push(ij["skins"][0]["inverseBindMatrices"].as_u64().unwrap());
    if let Some(i) = prim.get("indices").and_then(Value::as_u64) {
        accessors.push(i);
    }
    for a in accessors {
        assert_eq!(oj["accessors"][a as usize], ij["accessors"][a as usize]);
        assert_eq!(
            accessor_bytes(&oj, &ob, a as usize),
            accessor_bytes(&ij, &ib, a as usize),
            "accessor {a}'s data changed"
        );
    }
    // The tail nodes, found by name in the input.
    let tail: Vec<u64> = ij["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .filter(|(_, n)| n["name"].as_str().unwrap_or("").starts_with("b_Tail0"))
        .map(|(i, _)| i as u64)
        .collect();
    assert_eq!(tail.len(), 3);
    for a in 0..3 {
        let (before, after) = (channels(&ij, &ib, a), channels(&oj, &ob, a));
        // No sampler left without a channel (the replaced ones are dropped).
        let anim = &oj["animations"][a];
        let used: std::collections::BTreeSet<u64> = anim["channels"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c["sampler"].as_u64().unwrap())
            .collect();
        assert_eq!(used.len(), anim["samplers"].as_array().unwrap().len());
        // Every other channel: the same keys, bit for bit.
        for (key, chan) in &before {
            if !tail.contains(&key.0) {
                assert_eq!(
                    after.get(key),
                    Some(chan),
                    "clip {a} channel {key:?} changed"
                );
            }
        }
        for key in after.keys() {
            assert!(
                tail.contains(&key.0) || before.contains_key(key),
                "clip {a} gained a channel {key:?} off the tail"
            );
        }
        // Each tail joint's rotation is re-keyed at 60 fps over the clip and leaves the
        // input's animation somewhere.
        let duration = before
            .values()
            .map(|(t, _)| *t.last().unwrap())
            .fold(0.0, f32::max);
        for &node in &tail {
            let (times, values) = &after[&(node, "rotation".to_string())];
            assert_eq!(times[0], 0.0);
            assert!((times.last().unwrap() - duration).abs() < 1e-6);
            assert!(times.windows(2).all(|w| w[1] - w[0] <= 1.0 / 60.0 + 1e-4));
            let (it, iv) = &before[&(node, "rotation".to_string())];
            let largest = times
                .iter()
                .enumerate()
                .map(|(k, &t)| {
                    let baked = [
                        values[4 * k],
                        values[4 * k + 1],
                        values[4 * k + 2],
                        values[4 * k + 3],
                    ];
                    angle_deg(baked, rotation_at(it, iv, t))
                })
                .fold(0.0, f32::max);
            // 1°: ten times the nlerp-vs-slerp error of `rotation_at`; the walking and
            // running tail's tip swings far more.
            let least = if a > 0 && node == tail[2] { 10.0 } else { 1.0 };
            assert!(
                largest > least,
                "clip {a} node {node}: baked tail within {largest}° of the input"
            );
        }
    }
}

#[test]
fn bake_vrm_keeps_its_extensions() {
    let Some(vrm) = testdata("vrm/smoke_spring.vrm") else {
        return;
    };
    let dir = tmp("bake-vrm");
    let out = dir.join("baked.vrm");
    let run = tassel()
        .arg("bake")
        .arg(&vrm)
        .args([
            "--mode", "fixed", "--warmup", "0", "--sway", "0.1,0,0", "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    validate(&out);
    let (ij, _) = glb_chunks(&std::fs::read(&vrm).unwrap());
    let (oj, ob) = glb_chunks(&std::fs::read(&out).unwrap());
    for key in [
        "extensions",
        "extensionsUsed",
        "extensionsRequired",
        "nodes",
        "meshes",
        "skins",
        "materials",
    ] {
        assert_eq!(oj.get(key), ij.get(key), "{key} changed");
    }
    assert!(oj["extensions"]["VRMC_springBone"].is_object());
    assert!(oj["extensions"]["VRMC_vrm"].is_object());
    // The file has no clips: one `sway` clip moves the root 0.1 m along X at 1 Hz and keys
    // the three swinging joints (named by the springBone extension), which start at rest
    // and swing away from it.
    assert_eq!(oj["animations"].as_array().unwrap().len(), 1);
    assert_eq!(oj["animations"][0]["name"], "sway");
    let root = ij["scenes"][0]["nodes"][0].as_u64().unwrap();
    let root_t: Vec<f32> = ij["nodes"][root as usize]["translation"]
        .as_array()
        .map(|a| a.iter().map(|x| x.as_f64().unwrap() as f32).collect())
        .unwrap_or(vec![0.0; 3]);
    let chans_root = channels(&oj, &ob, 0);
    let (rt, rv) = &chans_root[&(root, "translation".to_string())];
    for (k, &t) in rt.iter().enumerate() {
        let x = root_t[0] + 0.1 * (std::f32::consts::TAU * t).sin();
        assert!(
            (rv[3 * k] - x).abs() < 1e-5,
            "root x at {t}: {} vs {x}",
            rv[3 * k]
        );
        assert!((rv[3 * k + 1] - root_t[1]).abs() < 1e-6);
    }
    let springs: Vec<u64> = ij["extensions"]["VRMC_springBone"]["springs"][0]["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["node"].as_u64().unwrap())
        .collect();
    let chans = channels(&oj, &ob, 0);
    for &node in &springs[..springs.len() - 1] {
        let (times, values) = &chans[&(node, "rotation".to_string())];
        assert_eq!(times.len(), 121, "2 s at 60 fps");
        let rest = ij["nodes"][node as usize]
            .get("rotation")
            .map(|r| {
                let v: Vec<f32> = r
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap() as f32)
                    .collect();
                [v[0], v[1], v[2], v[3]]
            })
            .unwrap_or([0.0, 0.0, 0.0, 1.0]);
        let first = [values[0], values[1], values[2], values[3]];
        let n = times.len() - 1;
        let last = [
            values[4 * n],
            values[4 * n + 1],
            values[4 * n + 2],
            values[4 * n + 3],
        ];
        assert!(
            angle_deg(first, rest) < 0.5,
            "node {node} does not start at rest"
        );
        assert!(angle_deg(last, rest) > 1.0, "node {node} never moved");
    }
}

/// A GLB from a JSON and a BIN chunk (glTF 2.0 §4.4), padded as the container requires.
fn glb_bytes(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&b);
    out
}

/// `VRMC_springBone_limit`: a file whose first spring joint has a 3° cone keeps the
/// extension through `bake`, and every baked key of that joint stays in the cone (the chain
/// hangs along −Y, the draft's special case of the limit's frame), while the same sway
/// without the limit swings it much further.
#[test]
fn bake_vrm_keeps_and_respects_spring_bone_limits() {
    let Some(vrm) = testdata("vrm/smoke_spring.vrm") else {
        return;
    };
    let dir = tmp("bake-vrm-limit");
    let (mut json, bin) = glb_chunks(&std::fs::read(&vrm).unwrap());
    let cone = 0.05f32;
    let joint0 = &mut json["extensions"]["VRMC_springBone"]["springs"][0]["joints"][0];
    joint0["extensions"] = serde_json::json!({
        "VRMC_springBone_limit": {"specVersion": "1.0-draft", "limit": {"cone": {"angle": cone}}}
    });
    let node = joint0["node"].as_u64().unwrap();
    json["extensionsUsed"]
        .as_array_mut()
        .unwrap()
        .push("VRMC_springBone_limit".into());
    let limited = dir.join("limited.vrm");
    std::fs::write(&limited, glb_bytes(&json, &bin)).unwrap();
    // The bone axis: the next joint's rest translation, in the joint's space.
    let next = json["extensions"]["VRMC_springBone"]["springs"][0]["joints"][1]["node"]
        .as_u64()
        .unwrap();
    let t: Vec<f32> = json["nodes"][next as usize]["translation"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap() as f32)
        .collect();
    let axis = glam::Vec3::new(t[0], t[1], t[2]).normalize();
    assert!(json["nodes"][node as usize].get("rotation").is_none());
    let largest_swing = |file: &Path, out: &Path| -> f32 {
        run_ok(
            tassel()
                .arg("bake")
                .arg(file)
                .args([
                    "--mode",
                    "fixed",
                    "--warmup",
                    "0",
                    "--sway",
                    "0.3,0,0.2",
                    "-o",
                ])
                .arg(out),
        );
        let (oj, ob) = glb_chunks(&std::fs::read(out).unwrap());
        let (ij, _) = glb_chunks(&std::fs::read(file).unwrap());
        assert_eq!(oj["extensions"], ij["extensions"], "extensions changed");
        assert_eq!(oj["extensionsUsed"], ij["extensionsUsed"]);
        let chans = channels(&oj, &ob, 0);
        let (_, values) = &chans[&(node, "rotation".to_string())];
        values
            .chunks(4)
            .map(|q| {
                let q = glam::Quat::from_xyzw(q[0], q[1], q[2], q[3]).normalize();
                // The rest rotation is the identity: the angle from the rest bone.
                (q * axis).angle_between(axis)
            })
            .fold(0.0f32, f32::max)
    };
    let with = largest_swing(&limited, &dir.join("baked-limited.vrm"));
    let without = largest_swing(&vrm, &dir.join("baked-free.vrm"));
    assert!(
        with <= cone + 1e-4,
        "a baked key {with} rad from rest, past the {cone} rad cone"
    );
    assert!(
        with > 0.8 * cone,
        "the joint never reached its cone ({with} rad)"
    );
    assert!(
        without > 3.0 * cone,
        "without the limit it swings only {without} rad"
    );
}

fn assert_bake_fails(args: &[&std::ffi::OsStr], out: &Path, needle: &str) {
    let run = tassel()
        .arg("bake")
        .args(args)
        .arg("-o")
        .arg(out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success(), "bake {args:?} succeeded");
    assert!(
        err.contains(needle),
        "error {err:?} does not say {needle:?}"
    );
    assert!(!out.exists(), "{} was written", out.display());
    if let Some(dir) = out.parent().filter(|d| d.is_dir()) {
        let left: Vec<_> = std::fs::read_dir(dir).unwrap().collect();
        assert!(left.is_empty(), "files left behind: {left:?}");
    }
}

#[test]
fn bake_bad_input_fails_cleanly() {
    let Some(fox) = testdata("gltf/Fox.glb") else {
        return;
    };
    let dir = tmp("bake-bad");
    let scratch = tmp("bake-bad-in");
    let out = dir.join("out.glb");
    let rig = fox_rig();
    // A truncated file.
    let bytes = std::fs::read(&fox).unwrap();
    let cut = scratch.join("truncated.glb");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    assert_bake_fails(
        &[cut.as_os_str(), "--rig".as_ref(), rig.as_os_str()],
        &out,
        "truncated.glb",
    );
    // A clip that is not there: the message names it and lists the file's clips.
    assert_bake_fails(
        &[
            fox.as_os_str(),
            "--rig".as_ref(),
            rig.as_os_str(),
            "--clip".as_ref(),
            "Gallop".as_ref(),
        ],
        &out,
        "no clip named 'Gallop'; the file has 'Survey', 'Walk', 'Run'",
    );
    // An output folder that does not exist, and an output path that is a folder.
    let nowhere = dir.join("missing").join("out.glb");
    assert_bake_fails(
        &[fox.as_os_str(), "--rig".as_ref(), rig.as_os_str()],
        &nowhere,
        "does not exist",
    );
    let run = tassel()
        .arg("bake")
        .arg(&fox)
        .arg("--rig")
        .arg(&rig)
        .arg("-o")
        .arg(&dir)
        .output()
        .unwrap();
    assert!(!run.status.success());
    assert!(String::from_utf8_lossy(&run.stderr).contains("is a folder"));
    // A rig naming a bone the fox does not have; no rig and no VRM springs; bad options.
    let bad_rig = scratch.join("bad.toml");
    std::fs::write(&bad_rig, "[[chain]]\nroot = \"b_Ear_L\"\n").unwrap();
    assert_bake_fails(
        &[fox.as_os_str(), "--rig".as_ref(), bad_rig.as_os_str()],
        &out,
        "b_Ear_L",
    );
    assert_bake_fails(&[fox.as_os_str()], &out, "give --rig");
    assert_bake_fails(
        &[
            fox.as_os_str(),
            "--rig".as_ref(),
            rig.as_os_str(),
            "--fps".as_ref(),
            "0".as_ref(),
        ],
        &out,
        "fps 0",
    );
    assert_bake_fails(
        &[
            fox.as_os_str(),
            "--rig".as_ref(),
            rig.as_os_str(),
            "--mode".as_ref(),
            "spec".as_ref(),
        ],
        &out,
        "no VRM springs",
    );
    assert_bake_fails(
        &[
            fox.as_os_str(),
            "--rig".as_ref(),
            rig.as_os_str(),
            "--mode".as_ref(),
            "three-vrm".as_ref(),
        ],
        &out,
        "mode three-vrm is a VRM spring-bone mode",
    );
}
