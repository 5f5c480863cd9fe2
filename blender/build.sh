#!/usr/bin/env bash
# Builds Tassel for Blender: blender/dist/tassel-<version>-<platform>.zip, an extension
# (Blender 4.2+) holding the Python package blender/tassel/ and the native library.
#
#   bash blender/build.sh
#
# Here (Linux x86-64) the library is target/release/libtassel_ffi.so. For another
# platform build the library with that platform's Rust target and name it as
# native.py expects, then set TASSEL_PLATFORM to the manifest's platform name:
#   macOS arm64:  cargo build --release -p tassel-ffi --target aarch64-apple-darwin
#                 TASSEL_LIBRARY=target/aarch64-apple-darwin/release/libtassel_ffi.dylib \
#                 TASSEL_PLATFORM=macos-arm64 bash blender/build.sh
#   Windows x64:  cargo build --release -p tassel-ffi --target x86_64-pc-windows-msvc
#                 TASSEL_LIBRARY=target/x86_64-pc-windows-msvc/release/tassel_ffi.dll \
#                 TASSEL_PLATFORM=windows-x64 bash blender/build.sh
set -euo pipefail
cd "$(dirname "$0")/.."
platform="${TASSEL_PLATFORM:-linux-x64}"
library="${TASSEL_LIBRARY:-}"
if [ -z "$library" ]; then
  cargo build --release -p tassel-ffi
  library=target/release/libtassel_ffi.so
fi
version=$(sed -n 's/^version = "\(.*\)"/\1/p' blender/tassel/blender_manifest.toml)
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/tassel" blender/dist
cp blender/tassel/*.py "$stage/tassel/"
sed "s/^platforms = .*/platforms = [\"$platform\"]/" blender/tassel/blender_manifest.toml \
  >"$stage/tassel/blender_manifest.toml"
cp "$library" "$stage/tassel/"
out="blender/dist/tassel-$version-$platform.zip"
rm -f "$out"
(cd "$stage/tassel" && python3 -c '
import os, sys, zipfile
with zipfile.ZipFile(sys.argv[1], "w", zipfile.ZIP_DEFLATED) as z:
    for name in sorted(os.listdir(".")):
        z.write(name, name)
' "$OLDPWD/$out")
echo "$out"
