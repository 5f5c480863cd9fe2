//! Reading the files a glTF file points to (buffers, images): data URIs, or relative
//! paths inside the file's folder, read with a byte limit.

use base64::Engine;
use std::path::Path;

/// Reads at most `limit` bytes of a regular file. A device or a pipe (`/dev/zero`) is
/// refused rather than read without end.
pub(crate) fn read_at_most(path: &Path, limit: usize) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file",
        ));
    }
    let mut bytes = Vec::with_capacity((meta.len() as usize).min(limit));
    file.take(limit as u64).read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// A buffer's bytes from its URI: a base64 data URI, or a file beside the glTF file
/// (relative, inside its folder: no absolute path, no `..`, no other scheme), of which at
/// most `length` bytes (the buffer's `byteLength`) are read. Without a folder
/// (`base_dir` `None`: bytes from memory) no file is read: an external URI is an error
/// that names it.
pub(crate) fn read_uri(
    uri: &str,
    base_dir: Option<&Path>,
    length: usize,
) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, payload) = rest
            .split_once(";base64,")
            .ok_or_else(|| format!("data URI without base64: {}", head(uri, 40)))?;
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| format!("bad base64 in data URI: {e}"));
    }
    let decoded = percent_decode(uri);
    let relative = Path::new(&decoded);
    let escapes = relative.components().any(|c| {
        !matches!(
            c,
            std::path::Component::Normal(_) | std::path::Component::CurDir
        )
    });
    if decoded.is_empty() || escapes || decoded.contains(':') {
        return Err(format!(
            "buffer URI '{}' is not a relative path inside the file's folder",
            head(uri, 80)
        ));
    }
    let Some(base_dir) = base_dir else {
        return Err(format!(
            "buffer URI '{}' is an external file, and bytes loaded from memory read no \
             files: embed the buffer (a GLB, or a data: URI) or load the file from its path",
            head(uri, 80)
        ));
    };
    let path = base_dir.join(relative);
    // At most the declared bytes: a longer file keeps its tail (it may be padded).
    read_at_most(&path, length).map_err(|e| format!("buffer '{}': {e}", path.display()))
}

/// At most `n` characters of `s` (whole characters, never cut inside one).
fn head(s: &str, n: usize) -> &str {
    s.char_indices().nth(n).map_or(s, |(i, _)| &s[..i])
}

/// `%XX` escapes decoded byte by byte (the rest kept as it is), then read as UTF-8.
fn percent_decode(s: &str) -> String {
    let hex = |c: u8| (c as char).to_digit(16).map(|d| d as u8);
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push(h * 16 + l);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_decoding_never_splits_a_character() {
        // '%a' followed by a two-byte 'é': not an escape, kept as written.
        assert_eq!(percent_decode("%aé.bin"), "%aé.bin");
        assert_eq!(percent_decode("a%20b.bin"), "a b.bin");
        assert_eq!(percent_decode("%C3%A9.bin"), "é.bin");
        assert_eq!(percent_decode("x%4"), "x%4");
        assert_eq!(percent_decode("%"), "%");
    }

    #[test]
    fn messages_cut_at_character_boundaries() {
        let uri = format!("data:{}", "é".repeat(50));
        let e = read_uri(&uri, None, 10).unwrap_err();
        assert!(e.starts_with("data URI without base64: data:ééé"), "{e}");
        assert_eq!(head("aé", 2), "aé");
        assert_eq!(head("aéb", 2), "aé");
    }

    #[test]
    fn uris_stay_inside_the_folder() {
        for uri in [
            "../x.bin",
            "/etc/passwd",
            "a/../../x.bin",
            "file:///dev/zero",
            "C:x",
            "",
        ] {
            let e = read_uri(uri, Some(Path::new("/tmp")), 10).unwrap_err();
            assert!(e.contains("relative path inside"), "{uri}: {e}");
        }
    }

    #[test]
    fn bytes_from_memory_read_no_file() {
        // A file that exists where a relative path would find it (the crate's folder is
        // the test's working directory): still refused, named.
        let e = read_uri("Cargo.toml", None, 10).unwrap_err();
        assert!(e.contains("'Cargo.toml' is an external file"), "{e}");
        let data = read_uri("data:application/octet-stream;base64,AAEC", None, 3).unwrap();
        assert_eq!(data, vec![0, 1, 2]);
    }

    #[test]
    fn reads_at_most_the_declared_length() {
        let dir = std::env::temp_dir().join(format!("tassel-uri-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("b.bin"), [7u8; 100]).unwrap();
        assert_eq!(read_uri("b.bin", Some(&dir), 10).unwrap(), vec![7u8; 10]);
        std::fs::remove_dir_all(&dir).unwrap();
        let e = read_at_most(Path::new("/dev/zero"), 10).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
    }
}
