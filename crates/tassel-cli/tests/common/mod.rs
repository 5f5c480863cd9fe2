//! Helpers shared by the CLI tests: the binary, scratch folders, test data, the Khronos
//! validator.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

pub fn tassel() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tassel"))
}

/// A test's scratch folder (`<temp>/tassel-cli-<pid>-<name>`), made empty on creation and
/// removed when the test is done with it; kept when the test panics, so that a failure's
/// files can be looked at.
pub struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for Scratch {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

pub fn tmp(name: &str) -> Scratch {
    let d = std::env::temp_dir().join(format!("tassel-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    Scratch(d)
}

pub fn testdata(rel: &str) -> Option<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/testdata");
    if root.is_dir() {
        return Some(root.join(rel));
    }
    if std::env::var_os("TASSEL_REQUIRE_TESTDATA").is_some() {
        panic!("../shared/testdata is missing (TASSEL_REQUIRE_TESTDATA is set)");
    }
    eprintln!("SKIPPED: ../shared/testdata is missing; {rel} not tested");
    None
}

pub fn validate(file: &Path) -> Option<String> {
    let tools = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools");
    if !tools.join("node_modules/gltf-validator").is_dir() {
        if std::env::var_os("TASSEL_REQUIRE_VALIDATOR").is_some() {
            panic!("gltf-validator is not installed: run `npm ci` in tools/");
        }
        eprintln!(
            "SKIPPED: gltf-validator not installed; {} not validated",
            file.display()
        );
        return None;
    }
    let out = Command::new("node")
        .arg(tools.join("validate.mjs"))
        .arg(file)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "validator found errors in {}: {text}",
        file.display()
    );
    Some(text)
}

/// The JSON and BIN chunks of a GLB file, read by hand from the container layout
/// (glTF 2.0 §4.4), independent of the loaders under test.
pub fn glb_chunks(bytes: &[u8]) -> (serde_json::Value, Vec<u8>) {
    assert_eq!(&bytes[0..4], b"glTF", "not a GLB");
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as usize;
    assert_eq!(u32_at(8), bytes.len(), "GLB length field");
    let json_len = u32_at(12);
    assert_eq!(&bytes[16..20], b"JSON");
    let json = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let rest = 20 + json_len;
    let bin = if rest < bytes.len() {
        let bin_len = u32_at(rest);
        assert_eq!(&bytes[rest + 4..rest + 8], b"BIN\0");
        bytes[rest + 8..rest + 8 + bin_len].to_vec()
    } else {
        Vec::new()
    };
    (json, bin)
}

/// The float components of accessor `a` (FLOAT, tightly packed or strided), read by hand.
pub fn read_floats(json: &serde_json::Value, bin: &[u8], a: usize) -> Vec<f32> {
    read_components(json, bin, a, (5126, "FLOAT"), |b: [u8; 4]| {
        f32::from_le_bytes(b)
    })
}

/// The components of accessor `a` (UNSIGNED_SHORT, e.g. JOINTS_0; tightly packed or
/// strided), read by hand.
pub fn read_u16s(json: &serde_json::Value, bin: &[u8], a: usize) -> Vec<u16> {
    read_components(json, bin, a, (5123, "UNSIGNED_SHORT"), |b: [u8; 2]| {
        u16::from_le_bytes(b)
    })
}

/// The components of accessor `a`, each `N` little-endian bytes of glTF component type
/// `kind` (code, name), decoded by `decode`; tightly packed or strided.
fn read_components<T, const N: usize>(
    json: &serde_json::Value,
    bin: &[u8],
    a: usize,
    kind: (u64, &str),
    decode: impl Fn([u8; N]) -> T,
) -> Vec<T> {
    let acc = &json["accessors"][a];
    assert_eq!(
        acc["componentType"], kind.0,
        "accessor {a} is not {}",
        kind.1
    );
    let comps = match acc["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" => 4,
        "MAT4" => 16,
        t => panic!("accessor type {t}"),
    };
    let count = acc["count"].as_u64().unwrap() as usize;
    let view = &json["bufferViews"][acc["bufferView"].as_u64().unwrap() as usize];
    let start = view.get("byteOffset").and_then(|v| v.as_u64()).unwrap_or(0) as usize
        + acc.get("byteOffset").and_then(|v| v.as_u64()).unwrap_or(0) as usize;
    let stride = view
        .get("byteStride")
        .and_then(|v| v.as_u64())
        .map(|s| s as usize)
        .unwrap_or(comps * N);
    let mut out = Vec::with_capacity(count * comps);
    for i in 0..count {
        for c in 0..comps {
            let o = start + i * stride + c * N;
            out.push(decode(bin[o..o + N].try_into().unwrap()));
        }
    }
    out
}

/// Runs `cmd` and asserts it succeeded (the message shows its standard error).
pub fn run_ok(cmd: &mut Command) -> std::process::Output {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{cmd:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The raw bytes of accessor `a`'s buffer view range (for byte-for-byte comparisons).
pub fn accessor_bytes<'a>(json: &serde_json::Value, bin: &'a [u8], a: usize) -> &'a [u8] {
    let acc = &json["accessors"][a];
    let view = &json["bufferViews"][acc["bufferView"].as_u64().unwrap() as usize];
    let start = view.get("byteOffset").and_then(|v| v.as_u64()).unwrap_or(0) as usize;
    let len = view["byteLength"].as_u64().unwrap() as usize;
    &bin[start..start + len]
}

/// An RGB PNG as (width, height, row-major RGB bytes).
pub fn read_png(path: &Path) -> (usize, usize, Vec<u8>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width as usize, info.height as usize, buf)
}
