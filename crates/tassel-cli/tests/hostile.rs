//! Hostile input, each case built here: the CLI answers with exit 1 and a message naming
//! the problem, quickly, within bounded memory, and leaves no file behind (issue 14).

mod common;
use common::{glb_chunks, tassel, tmp};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// A data URI for `bytes` (base64, by hand: the test does not use the crate under test).
fn data_uri(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::from("data:application/octet-stream;base64,");
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

fn floats(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// A three-node chain (root, a, b) with whatever else `extra` adds.
fn chain_doc(extra: Value) -> Value {
    let mut d = json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [
            {"name": "root", "children": [1]},
            {"name": "a", "translation": [0.0, -0.1, 0.0], "children": [2]},
            {"name": "b", "translation": [0.0, -0.1, 0.0]}
        ]
    });
    for (k, v) in extra.as_object().unwrap() {
        d[k] = v.clone();
    }
    d
}

/// The chain with one clip, `name`: node `node` translated along X from 0 to `x` over
/// two keys at 0 and `end` seconds (LINEAR).
fn ramp_clip(name: &str, node: usize, end: f32, x: f32) -> Value {
    let bytes = [floats(&[0.0, end]), floats(&[0.0, 0.0, 0.0, x, 0.0, 0.0])].concat();
    chain_doc(json!({
        "buffers": [{"uri": data_uri(&bytes), "byteLength": 32}],
        "bufferViews": [{"buffer": 0, "byteLength": 8}, {"buffer": 0, "byteOffset": 8, "byteLength": 24}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0.0], "max": [end]},
            {"bufferView": 1, "componentType": 5126, "count": 2, "type": "VEC3"}
        ],
        "animations": [{"name": name, "channels": [{"sampler": 0, "target": {"node": node, "path": "translation"}}],
                        "samplers": [{"input": 0, "output": 1}]}]
    }))
}

fn write_json(dir: &Path, name: &str, doc: &Value) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, serde_json::to_vec(doc).unwrap()).unwrap();
    p
}

fn chain_rig(dir: &Path, extra: &str) -> PathBuf {
    let p = dir.join("rig.toml");
    std::fs::write(
        &p,
        format!("[[chain]]\nname = \"c\"\nroot = \"a\"\ndummy_bone_length = 0.1\n{extra}"),
    )
    .unwrap();
    p
}

/// Runs the CLI; asserts exit code 1, a message containing every `needles` entry, a run
/// shorter than `seconds`, and no file (nor temporary file) in `dir` beyond `keep`.
fn fails(args: &[&str], dir: &Path, keep: &[&str], needles: &[&str], seconds: u64) {
    let start = Instant::now();
    let out = tassel().args(args).output().unwrap();
    let took = start.elapsed();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: message lacks '{n}': {err}");
    }
    assert!(
        took < Duration::from_secs(seconds),
        "{args:?} took {took:?}: {err}"
    );
    let left: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| !keep.contains(&n.as_str()))
        .collect();
    assert!(left.is_empty(), "{args:?} left {left:?}");
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn loader_problems_are_errors_not_panics() {
    let d = tmp("hostile-loader");
    let pos = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let mesh = |stride: Option<u32>, index_type: Option<u32>| {
        let mut views = vec![json!({"buffer": 0, "byteLength": 36})];
        if let Some(st) = stride {
            views[0]["byteStride"] = json!(st);
        }
        let mut accessors = vec![json!({"bufferView": 0, "componentType": 5126, "count": 3,
            "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]})];
        let mut prim = json!({"attributes": {"POSITION": 0}});
        let mut bytes = pos.clone();
        if let Some(ct) = index_type {
            views.push(json!({"buffer": 0, "byteOffset": 36, "byteLength": 12}));
            accessors
                .push(json!({"bufferView": 1, "componentType": ct, "count": 3, "type": "SCALAR"}));
            prim["indices"] = json!(1);
            bytes.extend([0u8; 12]);
        }
        let mut doc = chain_doc(json!({
            "buffers": [{"uri": data_uri(&bytes), "byteLength": bytes.len()}],
            "bufferViews": views, "accessors": accessors,
            "meshes": [{"primitives": [prim]}]
        }));
        doc["nodes"][2]["mesh"] = json!(0);
        doc
    };
    let cases: Vec<(&str, Value, Vec<&str>)> = vec![
        (
            "percent.gltf",
            chain_doc(json!({"buffers": [{"uri": "%aé.bin", "byteLength": 4}]})),
            vec!["%aé.bin"],
        ),
        (
            "datauri.gltf",
            chain_doc(
                json!({"buffers": [{"uri": format!("data:{}", "é".repeat(50)), "byteLength": 4}]}),
            ),
            vec!["data URI without base64"],
        ),
        (
            "stride.gltf",
            mesh(Some(4), None),
            vec!["byteStride of 4", "12-byte element"],
        ),
        (
            "byte_index.gltf",
            mesh(None, Some(5120)),
            vec!["indices", "I8"],
        ),
        (
            "float_index.gltf",
            mesh(None, Some(5126)),
            vec!["indices", "F32"],
        ),
        (
            "devzero.gltf",
            chain_doc(json!({"buffers": [{"uri": "/dev/zero", "byteLength": 4}]})),
            vec!["not a relative path inside the file's folder"],
        ),
        (
            "escape.gltf",
            chain_doc(json!({"buffers": [{"uri": "../../../../../../dev/zero", "byteLength": 4}]})),
            vec!["not a relative path inside the file's folder"],
        ),
        (
            "far.gltf",
            {
                let mut doc = chain_doc(json!({}));
                doc["nodes"][0]["translation"] = json!([1e20, 0.0, 0.0]);
                doc
            },
            vec!["'root'", "limit of 1e6"],
        ),
        (
            "skin.gltf",
            chain_doc(json!({"skins": [{"joints": vec![1; 600_000]}]})),
            vec!["lists joint 'a' twice"],
        ),
    ];
    for (name, doc, needles) in cases {
        let f = write_json(&d, name, &doc);
        let o = d.join("o.json");
        for cmd in ["inspect", "simulate"] {
            let mut args = vec![cmd, s(&f)];
            if cmd == "simulate" {
                args.extend(["--rig", "/nonexistent.toml", "--out", s(&o)]);
            }
            fails(&args, &d, &[name], &needles, 20);
        }
        std::fs::remove_file(&f).unwrap();
    }
}

#[test]
fn a_clip_of_a_billion_seconds_is_refused_by_every_command() {
    let d = tmp("hostile-clip");
    let doc = ramp_clip("long", 1, 1e9, 1.0);
    let f = write_json(&d, "long.gltf", &doc);
    let rig = chain_rig(&d, "");
    let keep = ["long.gltf", "rig.toml"];
    let needles = ["key time 1000000000 s", "3600"];
    let (o, png) = (d.join("o.glb"), d.join("o.png"));
    fails(&["inspect", s(&f)], &d, &keep, &needles, 10);
    fails(
        &["bake", s(&f), "--rig", s(&rig), "-o", s(&o)],
        &d,
        &keep,
        &needles,
        10,
    );
    fails(
        &["render", s(&f), "--rig", s(&rig), "-o", s(&png)],
        &d,
        &keep,
        &needles,
        10,
    );
    fails(
        &["plot", s(&f), "--rig", s(&rig), "-o", s(&png)],
        &d,
        &keep,
        &needles,
        10,
    );
    fails(
        &[
            "sample",
            s(&f),
            "--clip",
            "long",
            "--times",
            "0",
            "--out",
            s(&o),
        ],
        &d,
        &keep,
        &needles,
        10,
    );
}

#[test]
fn rigs_that_ask_for_unbounded_work_are_refused() {
    let d = tmp("hostile-rig");
    let f = write_json(&d, "m.gltf", &chain_doc(json!({})));
    let o = d.join("o.json");
    let run = |rig_text: &str, needles: &[&str]| {
        std::fs::write(d.join("rig.toml"), rig_text).unwrap();
        let rig = d.join("rig.toml");
        fails(
            &["simulate", s(&f), "--rig", s(&rig), "--out", s(&o)],
            &d,
            &["m.gltf", "rig.toml"],
            needles,
            10,
        );
    };
    let mut many = String::from("[[chain]]\nname = \"c\"\nroot = \"a\"\n");
    for i in 0..80_000 {
        many.push_str(&format!(
            "[[collider]]\nname = \"c{i}\"\nbone = \"a\"\nshape = \"sphere\"\nradius = 0.1\n"
        ));
    }
    run(&many, &["80000 colliders", "limit of 4096"]);
    run(
        "[[chain]]\nname = \"c\"\nroot = \"a\"\nwarmup_steps = 100000000\n",
        &["chain 'c'", "warmup_steps", "10000"],
    );
    run(
        "[[chain]]\nname = \"c\"\nroot = \"a\"\nmax_steps_per_frame = 4294967295\n",
        &["chain 'c'", "max_steps_per_frame", "1..=64"],
    );
    run(
        "[[spring]]\nname = \"s\"\nbone = \"b\"\nfixed_time_step = 1e-9\nmax_steps_per_frame = 4294967295\n",
        &["spring 's'", "fixed_time_step"],
    );
    run(
        "[[spring]]\nname = \"s\"\nbone = \"b\"\nmax_steps_per_frame = 4294967295\n",
        &["spring 's'", "max_steps_per_frame", "1..=64"],
    );
    run(
        "[[rope]]\nname = \"r\"\nroot = \"root\"\nend = \"b\"\nworld.time_step = 1e-9\n",
        &["rope 'r'", "time_step"],
    );
    run(
        "[[rope]]\nname = \"r\"\nroot = \"root\"\nend = \"b\"\nworld.max_steps_per_frame = 4294967295\n",
        &["rope 'r'", "max_steps_per_frame"],
    );
    // A spring on a bone a chain already moves: one solver per bone.
    run(
        "[[chain]]\nname = \"c\"\nroot = \"a\"\n[[spring]]\nname = \"s\"\nbone = \"b\"\n",
        &["'b'", "chain", "spring", "one solver"],
    );
}

#[test]
fn arguments_past_the_limits_are_refused() {
    let d = tmp("hostile-args");
    let f = write_json(&d, "m.gltf", &chain_doc(json!({})));
    let rig = chain_rig(&d, "");
    let o = d.join("o.json");
    let keep = ["m.gltf", "rig.toml"];
    fails(
        &[
            "simulate",
            s(&f),
            "--rig",
            s(&rig),
            "--frames",
            "1000001",
            "--out",
            s(&o),
        ],
        &d,
        &keep,
        &["--frames", "1000000"],
        10,
    );
    fails(
        &[
            "simulate",
            s(&f),
            "--rig",
            s(&rig),
            "--dt",
            "1e9",
            "--out",
            s(&o),
        ],
        &d,
        &keep,
        &["--dt"],
        10,
    );
    // A motion that carries the character beyond the coordinate limit mid-run: an error
    // naming the frame, no file.
    fails(
        &[
            "simulate",
            s(&f),
            "--rig",
            s(&rig),
            "--motion",
            "linear",
            "--amp",
            "1e30",
            "--out",
            s(&o),
        ],
        &d,
        &keep,
        &["frame 1", "character transform"],
        10,
    );
}

/// Long runs are streamed: under a 200 MB address-space limit (bash's `ulimit -v`), a
/// 200 000-frame `simulate` (≈ 80 MB of JSON; 850 MB resident when it was held whole)
/// and a 200 001-time `sample` complete, and their files parse with the expected counts.
#[test]
fn long_runs_stream_within_bounded_memory() {
    let d = tmp("hostile-stream");
    let doc = ramp_clip("move", 0, 1.0, 0.5);
    let f = write_json(&d, "m.gltf", &doc);
    let rig = chain_rig(&d, "");
    let bin = env!("CARGO_BIN_EXE_tassel");
    let limited = |args: String| {
        let out = std::process::Command::new("bash")
            .arg("-c")
            .arg(format!("ulimit -v 200000 && exec '{bin}' {args}"))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{args}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    let sim = d.join("sim.json");
    limited(format!(
        "simulate '{}' --rig '{}' --frames 200000 --motion sin --amp 0.1 --out '{}'",
        f.display(),
        rig.display(),
        sim.display()
    ));
    let v: Value = serde_json::from_slice(&std::fs::read(&sim).unwrap()).unwrap();
    let samples = v["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 200_000);
    assert_eq!(samples[199_999]["frame"], 200_000);
    assert_eq!(v["joints"].as_array().unwrap().len(), 2);
    std::fs::remove_file(&sim).unwrap();
    let smp = d.join("sample.json");
    limited(format!(
        "sample '{}' --clip move --fps 10000 --duration 20 --out '{}'",
        f.display(),
        smp.display()
    ));
    let v: Value = serde_json::from_slice(&std::fs::read(&smp).unwrap()).unwrap();
    let samples = v["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 200_001);
    // Root x at t = 0.5 s of a 0 → 0.5 m ramp over 1 s: 0.25 m (the clip clamps after 1 s).
    assert!((samples[5000]["world_pos"][0][0].as_f64().unwrap() - 0.25).abs() < 1e-6);
    assert!((samples[200_000]["world_pos"][0][0].as_f64().unwrap() - 0.5).abs() < 1e-6);
}

/// Every number of the input's JSON comes out of `bake` with the same value. The numbers
/// are compared as the text of both files parsed by Rust's exactly-rounding `f64` parser,
/// not through the JSON library the tool uses.
#[test]
fn bake_keeps_the_inputs_numbers_exactly() {
    let d = tmp("hostile-numbers");
    // Decimal strings whose nearest f64 a non-exact parser misses (the first is the
    // issue's VRM accessor minimum), plus extremes.
    let tricky = [
        "-0.18815206736326218",
        "0.30000000000000004",
        "2.2250738585072014e-308",
        "1.7976931348623157e308",
        "9007199254740993",
        "0.1",
        "-1.0000000000000002",
        "3.0517578125e-05",
    ];
    let text = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"name":"root","children":[1]}},{{"name":"a","translation":[0.0,-0.1,0.0],"children":[2]}},{{"name":"b","translation":[0.0,-0.1,0.0]}}],
"extras":{{"tricky":[{}]}}}}"#,
        tricky.join(",")
    );
    let f = d.join("m.gltf");
    std::fs::write(&f, &text).unwrap();
    let rig = chain_rig(&d, "");
    let o = d.join("o.glb");
    let out = tassel()
        .args([
            "bake",
            s(&f),
            "--rig",
            s(&rig),
            "--sway",
            "0.1,0,0",
            "-o",
            s(&o),
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&o).unwrap();
    let (json, _) = glb_chunks(&bytes);
    let json_text = serde_json::to_string(&json["extras"]["tricky"]).unwrap();
    // The raw text of the output's array, from the GLB's JSON chunk.
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let raw = std::str::from_utf8(&bytes[20..20 + len]).unwrap();
    let at = raw.find("\"tricky\":[").expect("extras kept") + "\"tricky\":[".len();
    let end = at + raw[at..].find(']').unwrap();
    let got: Vec<&str> = raw[at..end].split(',').collect();
    assert_eq!(got.len(), tricky.len(), "{json_text}");
    for (g, want) in got.iter().zip(tricky) {
        let (g, w) = (g.parse::<f64>().unwrap(), want.parse::<f64>().unwrap());
        assert_eq!(g.to_bits(), w.to_bits(), "{want} came out as {g:e}");
    }
}
