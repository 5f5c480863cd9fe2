//! `include/tassel.h` is what cbindgen generates from `src/abi.rs` and `src/abi/crowd.rs`
//! with `cbindgen.toml`:
//! a change to the ABI that is not in the checked-in header fails here.
//! `TASSEL_BLESS=1 cargo test -p tassel-ffi --test header` writes the new header.

use std::path::PathBuf;

#[test]
fn the_checked_in_header_is_the_generated_one() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).unwrap();
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(dir.join("src/abi.rs"))
        .with_src(dir.join("src/abi/crowd.rs"))
        .generate()
        .expect("cbindgen could not read src/abi.rs and src/abi/crowd.rs");
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let generated = String::from_utf8(generated).unwrap();
    let path = dir.join("include/tassel.h");
    if std::env::var("TASSEL_BLESS").is_ok_and(|v| !v.is_empty()) {
        std::fs::write(&path, &generated).unwrap();
    }
    let checked_in = std::fs::read_to_string(&path).unwrap_or_default();
    // The declarations the C ABI promises, by name and signature.
    for decl in [
        "typedef struct TasselCharacter TasselCharacter;",
        "size_t tassel_joint_count(const TasselCharacter *c);",
        "const char *tassel_last_error(void);",
        "typedef struct TasselCrowd TasselCrowd;",
        "TasselCrowd *tassel_crowd_new(const TasselCharacter *kind);",
    ] {
        assert!(
            generated.contains(decl),
            "the header lacks `{decl}`:\n{generated}"
        );
    }
    assert!(
        checked_in == generated,
        "include/tassel.h differs from what cbindgen generates from src/abi.rs and src/abi/crowd.rs; run \
         TASSEL_BLESS=1 cargo test -p tassel-ffi --test header and commit it"
    );
}
