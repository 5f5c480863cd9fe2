#!/usr/bin/env bash
# Builds tassel-three into web/dist/: Tassel's C ABI (crates/tassel-ffi) compiled to
# wasm32-unknown-unknown on stable Rust (portable lanes: no x86 intrinsics), and the ES
# module that loads it (web/src/index.js). Needs `rustup target add wasm32-unknown-unknown`.
set -euo pipefail
cd "$(dirname "$0")/.."
# A target folder of its own: the wasm build never waits on, or evicts, the native one.
cargo build --release --target wasm32-unknown-unknown -p tassel-ffi --lib \
  --target-dir target/wasm
rm -rf web/dist && mkdir -p web/dist
cp target/wasm/wasm32-unknown-unknown/release/tassel_ffi.wasm web/dist/tassel.wasm
cp web/src/index.js web/dist/index.js
cp web/src/index.d.ts web/dist/index.d.ts
echo "web/dist: $(wc -c < web/dist/tassel.wasm) bytes of wasm"
