//! The C ABI as C and Python programs use it: `tests/c/frame.c` compiled with the
//! system's C compiler against `libtassel_ffi.a` and `include/tassel.h`, and
//! `tests/python/frame.py` loading `libtassel_ffi.so` through ctypes, each running the VRM
//! files of `../shared/testdata/vrm` on a swaying root. Each prints every joint's world
//! position per frame, composed in C or Python from the locals the ABI gives back; they
//! must match `tassel simulate`'s world positions for the same file and motion to 1e-6 m.
//! Both programs also check the ABI's promises on bad input (NULL, wrong lengths, NaN,
//! overlapping buffers: errors with messages that change nothing). The Python program also
//! runs the crowd functions (`tassel_crowd_*`): three members against three characters of
//! their own, bit for bit, and a member's NaN held. `tests/c/skeleton.c` and
//! `tests/python/skeleton.py` make a character with `tassel_character_new` from what a
//! loaded one reports (joints, parents, rest pose) and the file's springs JSON, and
//! require the loaded one's frames byte for byte.

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::vrm_files;

const FRAMES: usize = 90;
const DT: &str = "0.0166666667";
const AMP: &str = "0.3";
const FREQ: &str = "1.5";

fn manifest() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The folder of this build's artifacts (`target/<profile>`): the test binary is in its
/// `deps/`.
fn build_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    exe.parent().unwrap().parent().unwrap().to_path_buf()
}

/// The C library file `name` of this build: `target/<profile>/` after `cargo build`,
/// `deps/` beside this test otherwise (cargo copies the library up only for builds).
fn library(name: &str) -> PathBuf {
    let dir = build_dir();
    [dir.join(name), dir.join("deps").join(name)]
        .into_iter()
        .filter(|p| p.is_file())
        .max_by_key(|p| p.metadata().and_then(|m| m.modified()).ok())
        .unwrap_or_else(|| panic!("{name} was not built in {} or its deps/", dir.display()))
}

/// The `tassel` CLI of this build; built if this run did not build it (`cargo test -p
/// tassel-ffi` alone).
fn tassel_cli() -> PathBuf {
    let dir = build_dir();
    let exe = dir.join(format!("tassel{}", std::env::consts::EXE_SUFFIX));
    if !exe.is_file() {
        let mut cargo = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
        cargo.args(["build", "-p", "tassel-cli", "--bin", "tassel"]);
        if dir.file_name().is_some_and(|n| n == "release") {
            cargo.arg("--release");
        }
        let target = dir.parent().unwrap();
        let status = cargo.arg("--target-dir").arg(target).status().unwrap();
        assert!(status.success(), "building the tassel CLI failed");
    }
    exe
}

/// `tassel simulate FILE --mode MODE --motion sin`: per frame, the listed joints' nodes
/// and world positions.
fn simulate(file: &Path, mode: &str) -> Vec<Vec<(usize, [f64; 3])>> {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "ffi-sim-{}-{mode}.json",
        file.file_stem().unwrap().to_string_lossy()
    ));
    let status = Command::new(tassel_cli())
        .arg("simulate")
        .arg(file)
        .args(["--mode", mode, "--motion", "sin", "--axis", "x"])
        .args(["--amp", AMP, "--freq", FREQ, "--dt", DT])
        .args(["--frames", &FRAMES.to_string()])
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success(), "tassel simulate {}", file.display());
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let nodes: Vec<usize> = doc["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["node"].as_u64().unwrap() as usize)
        .collect();
    doc["samples"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            let pos = s["world_pos"].as_array().unwrap();
            nodes
                .iter()
                .zip(pos)
                .map(|(&n, p)| (n, [0, 1, 2].map(|i| p[i].as_f64().unwrap())))
                .collect()
        })
        .collect()
}

/// A client's output: `P frame joint x y z` lines into `[frame - 1][joint]`; the client's
/// own checks must all have passed.
fn parse(program: &str, stdout: &[u8]) -> Vec<Vec<[f64; 3]>> {
    let text = String::from_utf8_lossy(stdout);
    let fails: Vec<&str> = text.lines().filter(|l| l.starts_with("FAIL")).collect();
    assert!(fails.is_empty(), "{program}: {fails:#?}");
    assert!(text.contains("DONE 0"), "{program} did not finish:\n{text}");
    let mut frames: Vec<Vec<[f64; 3]>> = vec![Vec::new(); FRAMES];
    for line in text.lines().filter(|l| l.starts_with("P ")) {
        let v: Vec<f64> = line[2..].split(' ').map(|x| x.parse().unwrap()).collect();
        let (f, j) = (v[0] as usize, v[1] as usize);
        assert_eq!(frames[f - 1].len(), j, "{program}: joints out of order");
        frames[f - 1].push([v[2], v[3], v[4]]);
    }
    frames
}

/// The largest distance between the simulated joints' world positions.
fn deviation(sim: &[Vec<(usize, [f64; 3])>], client: &[Vec<[f64; 3]>]) -> f64 {
    let mut worst = 0.0f64;
    let mut compared = 0;
    for (s, c) in sim.iter().zip(client) {
        for &(node, p) in s {
            let q = c[node];
            let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            worst = worst.max(d);
            compared += 1;
        }
    }
    assert!(compared >= FRAMES, "only {compared} positions compared");
    worst
}

fn run(cmd: &mut Command, what: &str) -> Vec<u8> {
    let out = cmd.output().unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        out.status.success(),
        "{what} failed ({}):\n{}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter(|l| !l.starts_with("P "))
            .collect::<Vec<_>>()
            .join("\n"),
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// The shared library Python loads (`libtassel_ffi.so` and the like).
fn shared_library() -> PathBuf {
    library(&format!(
        "{}tassel_ffi{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    ))
}

/// `source` compiled with the system's C compiler (`$CC`, else `cc`; warnings are errors)
/// against `include/tassel.h` and the static library, into the test's scratch folder.
fn compile_c(source: &Path, name: &str) -> PathBuf {
    let exe = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    run(
        Command::new(&cc)
            .args(["-std=c11", "-O1", "-Wall", "-Wextra", "-Werror", "-I"])
            .arg(manifest().join("include"))
            .arg(source)
            .arg(library("libtassel_ffi.a"))
            // What Rust's standard library needs from the system (rustc's
            // --print native-static-libs on Linux).
            .args([
                "-lgcc_s",
                "-lutil",
                "-lrt",
                "-lpthread",
                "-lm",
                "-ldl",
                "-lc",
            ])
            .arg("-o")
            .arg(&exe),
        &format!("compiling {}", source.display()),
    );
    exe
}

#[test]
fn a_c_program_matches_tassel_simulate() {
    let files = vrm_files();
    if files.is_empty() {
        return;
    }
    let exe = compile_c(&manifest().join("tests/c/frame.c"), "tassel-ffi-frame");
    for file in &files {
        for mode in ["fixed", "spec"] {
            let out = run(
                Command::new(&exe)
                    .arg(file)
                    .args([mode, &FRAMES.to_string(), DT, AMP, FREQ]),
                &format!("frame {} {mode}", file.display()),
            );
            let d = deviation(&simulate(file, mode), &parse("frame.c", &out));
            println!("{} {mode}: C deviates {d:.2e} m", file.display());
            assert!(d <= 1e-6, "{} {mode}: {d} m", file.display());
        }
    }
}

#[test]
fn a_python_program_matches_tassel_simulate() {
    let files = vrm_files();
    if files.is_empty() {
        return;
    }
    let lib = shared_library();
    let python = std::env::var("PYTHON").unwrap_or_else(|_| "python3".into());
    for file in &files {
        let mode = "three-vrm";
        let out = run(
            Command::new(&python)
                .arg(manifest().join("tests/python/frame.py"))
                .arg(&lib)
                .arg(file)
                .args([mode, &FRAMES.to_string(), DT, AMP, FREQ]),
            &format!("frame.py {} {mode}", file.display()),
        );
        let d = deviation(&simulate(file, mode), &parse("frame.py", &out));
        println!("{} {mode}: Python deviates {d:.2e} m", file.display());
        let text = String::from_utf8_lossy(&out);
        let crowd = text.lines().find_map(|l| l.strip_prefix("CROWD "));
        assert!(
            crowd.is_some_and(|n| n.parse::<usize>().is_ok_and(|n| n > 0)),
            "frame.py compared no crowd output"
        );
        assert!(d <= 1e-6, "{} {mode}: {d} m", file.display());
    }
}

/// The file's spring bones as JSON text (its `VRMC_springBone`, else VRM 0.x's
/// `secondaryAnimation`), written beside the test's other outputs.
fn springs_json_file(file: &Path) -> PathBuf {
    let bytes = std::fs::read(file).unwrap();
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + len]).unwrap();
    let ext = &json["extensions"];
    let springs = ext
        .get("VRMC_springBone")
        .or_else(|| ext.get("VRM").and_then(|v| v.get("secondaryAnimation")))
        .expect("a VRM file has spring bones");
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "{}.springs.json",
        file.file_name().unwrap().to_string_lossy()
    ));
    std::fs::write(&out, springs.to_string()).unwrap();
    out
}

/// `tassel_character_new` from C and from Python: for every VRM test file, the joints,
/// parents and rest pose its loaded character reports plus its own springs JSON step the
/// same frames, byte for byte, as the loaded character (C in every VRM mode, Python in
/// `fixed`); a cycle (C) and a repeated name (Python) are refused with a message.
#[test]
fn c_and_python_make_a_character_from_a_skeleton() {
    let files = vrm_files();
    if files.is_empty() {
        return;
    }
    let exe = compile_c(
        &manifest().join("tests/c/skeleton.c"),
        "tassel-ffi-skeleton",
    );
    let lib = shared_library();
    let python = std::env::var("PYTHON").unwrap_or_else(|_| "python3".into());
    for file in &files {
        let json = springs_json_file(file);
        for mode in ["fixed", "spec", "three-vrm"] {
            let out = run(
                Command::new(&exe).arg(file).arg(&json).args([mode, "120"]),
                &format!("skeleton {} {mode}", file.display()),
            );
            assert!(
                String::from_utf8_lossy(&out).contains("SAME 120"),
                "{}",
                file.display()
            );
        }
        let out = run(
            Command::new(&python)
                .arg(manifest().join("tests/python/skeleton.py"))
                .arg(&lib)
                .arg(file)
                .arg(&json)
                .args(["fixed", "120"]),
            &format!("skeleton.py {}", file.display()),
        );
        assert!(
            String::from_utf8_lossy(&out).contains("SAME 120"),
            "{}",
            file.display()
        );
    }
}

/// The C example of README.md (its one ```c block, a function `swing(bytes, len)`)
/// compiles without a warning and runs on a test VRM: every frame steps.
#[test]
fn the_readme_c_example_runs() {
    let files = vrm_files();
    if files.is_empty() {
        return;
    }
    let readme = std::fs::read_to_string(manifest().join("../../README.md")).unwrap();
    let start = readme.find("```c\n").expect("README.md has a ```c block") + 5;
    let end = start + readme[start..].find("```").unwrap();
    let example = &readme[start..end];
    assert!(
        example.lines().count() <= 25,
        "the README's C example is long"
    );
    let tmp = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let source = tmp.join("readme_example.c");
    std::fs::write(
        &source,
        format!(
            "{example}\n#include <string.h>\nint main(int argc, char **argv) {{\n  \
             (void)argc;\n  FILE *f = fopen(argv[1], \"rb\");\n  static uint8_t buf[1 << 24];\n  \
             size_t len = fread(buf, 1, sizeof buf, f);\n  fclose(f);\n  \
             return swing(buf, len) == 0 && tassel_last_error() == NULL ? 0 : 1;\n}}\n"
        ),
    )
    .unwrap();
    let exe = compile_c(&source, "readme_example");
    run(Command::new(&exe).arg(&files[0]), "README.md's C example");
}
