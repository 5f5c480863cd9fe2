//! Writing output files whole or not at all: write to a temporary file beside the target,
//! then rename.

use std::io::{BufWriter, Write};
use std::path::Path;

/// Fails early (before any long work) when `path` cannot be an output file: its folder
/// does not exist, or it is a folder. Returns the folder.
pub fn check_output_dir(path: &Path) -> Result<&Path, String> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !dir.is_dir() {
        return Err(format!(
            "{}: the folder {} does not exist",
            path.display(),
            dir.display()
        ));
    }
    if path.is_dir() {
        return Err(format!("{}: is a folder, not a file", path.display()));
    }
    Ok(dir)
}

/// Writes `bytes` to `path` atomically; on any error no file is left at `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), String> {
    write_atomic_with(path, |w| {
        w.write_all(bytes)
            .map_err(|e| format!("{}: {e}", path.display()))
    })
}

/// Streams the output through `write` into a temporary file beside `path`, renamed to
/// `path` only when `write` returns `Ok`: nothing is held whole in memory, and on any
/// error (the writer's own, or an I/O error) no file is left at `path` nor beside it.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> Result<(), String>,
) -> Result<(), String> {
    let dir = check_output_dir(path)?;
    let name = path
        .file_name()
        .ok_or_else(|| format!("{}: not a file path", path.display()))?;
    let tmp = dir.join(format!(
        ".{}.tmp{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let io = |e: std::io::Error| format!("{}: {e}", path.display());
    let result = std::fs::File::create(&tmp).map_err(io).and_then(|file| {
        let mut out = BufWriter::new(file);
        write(&mut out)?;
        out.flush().map_err(io)?;
        drop(out);
        std::fs::rename(&tmp, path).map_err(io)
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// A JSON object written piece by piece: the fields of `head`, then one array field whose
/// elements are pushed one at a time (a long run is never held whole in memory).
pub struct JsonStream<'w> {
    out: &'w mut dyn Write,
    first: bool,
}

impl<'w> JsonStream<'w> {
    /// Writes `{`, every field of `head` (an object), and `"<array>":[`.
    pub fn begin(
        out: &'w mut dyn Write,
        head: &serde_json::Value,
        array: &str,
    ) -> Result<Self, String> {
        let mut text = serde_json::to_string(head).map_err(|e| e.to_string())?;
        // `{...}` → `{...,"array":[` (or `{"array":[` for an empty head).
        text.pop();
        if text.len() > 1 {
            text.push(',');
        }
        text.push_str(&serde_json::to_string(array).map_err(|e| e.to_string())?);
        text.push_str(":[");
        out.write_all(text.as_bytes()).map_err(|e| e.to_string())?;
        Ok(Self { out, first: true })
    }

    /// Appends one element. A value holding `null` (what serde writes for NaN or
    /// infinity) is refused: no output file carries a number that is not one.
    pub fn push(&mut self, value: &serde_json::Value, what: &str) -> Result<(), String> {
        if has_null(value) {
            return Err(format!("{what}: a value is not a finite number"));
        }
        if !self.first {
            self.out.write_all(b",").map_err(|e| e.to_string())?;
        }
        self.first = false;
        serde_json::to_writer(&mut *self.out, value).map_err(|e| e.to_string())
    }

    /// Closes the array and the object.
    pub fn end(self) -> Result<(), String> {
        self.out.write_all(b"]}").map_err(|e| e.to_string())
    }
}

fn has_null(v: &serde_json::Value) -> bool {
    match v {
        serde_json::Value::Null => true,
        serde_json::Value::Array(a) => a.iter().any(has_null),
        serde_json::Value::Object(o) => o.values().any(has_null),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stream_refuses_non_numbers_and_writes_valid_json() {
        let mut buf = Vec::new();
        let head = serde_json::json!({"dt": 0.5, "joints": [1, 2]});
        let mut doc = JsonStream::begin(&mut buf, &head, "samples").unwrap();
        doc.push(&serde_json::json!({"x": [1.0, 2.0]}), "frame 1")
            .unwrap();
        let e = doc
            .push(&serde_json::json!({"x": [f32::NAN]}), "frame 2")
            .unwrap_err();
        assert!(
            e.contains("frame 2") && e.contains("not a finite number"),
            "{e}"
        );
        doc.push(&serde_json::json!({"x": [3.0]}), "frame 3")
            .unwrap();
        doc.end().unwrap();
        let v: serde_json::Value = serde_json::from_slice(&buf).unwrap();
        assert_eq!(v["dt"], 0.5);
        assert_eq!(v["samples"].as_array().unwrap().len(), 2);
        assert_eq!(v["samples"][1]["x"][0], 3.0);
    }

    #[test]
    fn a_failed_write_leaves_no_file() {
        let dir = std::env::temp_dir().join(format!("tassel-output-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("out.json");
        let e = write_atomic_with(&path, |w| {
            w.write_all(b"{\"partial\":").unwrap();
            Err("frame 7: boom".into())
        })
        .unwrap_err();
        assert_eq!(e, "frame 7: boom");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
