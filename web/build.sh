#!/usr/bin/env bash
# Builds tassel-three into web/dist/: Tassel's C ABI (crates/tassel-ffi) compiled to
# wasm32-unknown-unknown on stable Rust (portable lanes: no x86 intrinsics), and the ES
# module that loads it (web/src/index.js). Needs `rustup target add wasm32-unknown-unknown`.
set -euo pipefail
cd "$(dirname "$0")/.."
# A target folder of its own: the wasm build never waits on, or evicts, the native one.
# simd128 (WebAssembly's 128-bit SIMD: Chrome 91+, Firefox 89+, Safari 16.4+, Node 16.4+)
# lets the compiler turn the portable 8-lane types into vector code, as AVX2 does natively;
# without it every lane is a scalar operation (5-9x slower, measured). Symbols are
# stripped: the module is smaller to fetch.
export CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUSTFLAGS="-C target-feature=+simd128"
export CARGO_PROFILE_RELEASE_STRIP=symbols
cargo build --release --target wasm32-unknown-unknown -p tassel-ffi --lib \
  --target-dir target/wasm
rm -rf web/dist && mkdir -p web/dist
cp target/wasm/wasm32-unknown-unknown/release/tassel_ffi.wasm web/dist/tassel.wasm
cp web/src/index.js web/dist/index.js
cp web/src/index.d.ts web/dist/index.d.ts
echo "web/dist: $(wc -c < web/dist/tassel.wasm) bytes of wasm"
