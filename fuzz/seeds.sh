#!/usr/bin/env bash
# Builds the fuzzers' seed corpus in fuzz/corpus/ (not committed) from files already on
# disk: the glTF and VRM files of ../shared/testdata (for gltf_import and ffi_load), the example rigs, the built-in
# state machine. Existing corpus files are kept.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p fuzz/corpus/{gltf_import,ffi_load,ffi_skeleton,rig_toml,state_machine_toml,simulation}
if [ -d ../shared/testdata ]; then
  for f in ../shared/testdata/gltf/* ../shared/testdata/vrm/*; do
    case "$f" in *.glb|*.gltf|*.vrm) cp -n "$f" fuzz/corpus/gltf_import/ ;; esac
    # The C ABI's load starts from the same files (the gltf_import corpus).
    case "$f" in *.glb|*.gltf|*.vrm) cp -n "$f" fuzz/corpus/ffi_load/ ;; esac
  done
else
  echo "seeds: ../shared/testdata is missing; the glTF corpus starts from fuzz/regressions only" >&2
fi
cp -n examples/rigs/*.toml fuzz/corpus/rig_toml/
cp -n crates/tassel/src/anim/locomotion.toml fuzz/corpus/state_machine_toml/
