//! Replays, through the fuzz targets' own functions: every input in
//! `fuzz/regressions/<target>/` (the inputs that once found a bug, and hand-made hostile
//! ones), every file the local corpus `fuzz/corpus/<target>/` holds if a fuzz run left
//! one, and the seed files the corpus script starts from (`../shared/testdata`, the
//! example rigs, the built-in state machine). A panic here is a bug the fuzzers found.

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

/// Every file directly in `dir` (none if it does not exist), sorted.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    out.retain(|p| p.is_file());
    out.sort();
    out
}

fn replay(target: &str, run: fn(&[u8]), seeds: &[PathBuf]) -> usize {
    let mut inputs = files(&root().join("regressions").join(target));
    inputs.extend(files(&root().join("corpus").join(target)));
    inputs.extend(seeds.iter().cloned());
    for path in &inputs {
        // (A running fuzzer may remove corpus files as it reduces them.)
        let Ok(data) = std::fs::read(path) else {
            continue;
        };
        let name = path.display().to_string();
        let result = std::panic::catch_unwind(|| run(&data));
        assert!(result.is_ok(), "{target}: {name} panicked");
    }
    println!("{target}: {} inputs replayed", inputs.len());
    inputs.len()
}

fn testdata() -> Option<PathBuf> {
    let dir = root().join("../../shared/testdata");
    if dir.is_dir() {
        return Some(dir);
    }
    assert!(
        std::env::var_os("TASSEL_REQUIRE_TESTDATA").is_none(),
        "../shared/testdata is missing and TASSEL_REQUIRE_TESTDATA is set"
    );
    println!("SKIPPED the testdata seeds: ../shared/testdata is missing");
    None
}

#[test]
fn gltf_import_replays() {
    let mut seeds = Vec::new();
    if let Some(dir) = testdata() {
        seeds.extend(files(&dir.join("gltf")));
        seeds.extend(files(&dir.join("vrm")));
    }
    let n = replay("gltf_import", tassel_fuzz::gltf_import, &seeds);
    assert!(
        n >= 8,
        "only {n} inputs: the regression folder should hold the hostile files"
    );
}

/// The C ABI's load on the glTF importer's inputs (its regressions and the test files).
#[test]
fn ffi_load_replays() {
    let mut seeds = files(&root().join("regressions").join("gltf_import"));
    if let Some(dir) = testdata() {
        seeds.extend(files(&dir.join("gltf")));
        seeds.extend(files(&dir.join("vrm")));
    }
    let n = replay("ffi_load", tassel_fuzz::ffi_load, &seeds);
    assert!(n >= 8, "only {n} inputs");
}

/// `tassel_character_new` on its regressions (hand-made: a valid chain with VRM 1.0 and
/// VRM 0.x springs, a cycle, a NaN rest, a rig) and a fixed sweep of byte patterns.
#[test]
fn ffi_skeleton_replays() {
    let n = replay("ffi_skeleton", tassel_fuzz::ffi_skeleton, &[]);
    // The hand-made inputs do what they say: the VRM chains make a character in both
    // modes, the chain rig in `fixed` only (`spec` is a VRM mode), the cycle, the NaN and
    // the repeated names none.
    let dir = root().join("regressions/ffi_skeleton");
    for (file, want) in [
        ("chain_vrm1.bin", 2),
        ("chain_vrm0.bin", 2),
        ("rig.bin", 1),
        ("cycle.bin", 0),
        ("nan_rest.bin", 0),
        ("repeated_names.bin", 0),
    ] {
        let data = std::fs::read(dir.join(file)).unwrap();
        assert_eq!(tassel_fuzz::ffi_skeleton_made(&data), want, "{file}");
    }
    for seed in 0u64..200 {
        let mut rng = tassel::rng::SplitMix64::new(seed);
        let len = 1 + (rng.next_u64() % 600) as usize;
        let mut data: Vec<u8> = (0..len).map(|_| rng.next_u64() as u8).collect();
        data[0] %= 8;
        tassel_fuzz::ffi_skeleton(&data);
    }
    assert!(n >= 4, "only {n} inputs");
}

#[test]
fn rig_toml_replays() {
    let seeds = files(&root().join("../examples/rigs"));
    let n = replay("rig_toml", tassel_fuzz::rig_toml, &seeds);
    assert!(n >= 2, "only {n} inputs");
}

#[test]
fn state_machine_toml_replays() {
    let n = replay("state_machine_toml", tassel_fuzz::state_machine_toml, &[]);
    tassel_fuzz::state_machine_toml(tassel::anim::StateMachine::LOCOMOTION.as_bytes());
    assert!(n >= 1, "only {n} inputs");
}

#[test]
fn simulation_replays() {
    let n = replay("simulation", tassel_fuzz::simulation, &[]);
    // Plus a fixed sweep of byte patterns, so the target runs even on a fresh clone.
    for seed in 0u64..200 {
        let mut rng = tassel::rng::SplitMix64::new(seed);
        let data: Vec<u8> = (0..512).map(|_| rng.next_u64() as u8).collect();
        tassel_fuzz::simulation(&data);
    }
    assert!(n >= 1, "only {n} inputs");
}
