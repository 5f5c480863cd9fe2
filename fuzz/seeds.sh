#!/usr/bin/env bash
# Builds the fuzzers' seed corpus in fuzz/corpus/ (not committed) from files already on
# disk: the glTF and VRM files of ../shared/testdata, the example rigs, the built-in
# state machine. Existing corpus files are kept.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p fuzz/corpus/{gltf_import,rig_toml,state_machine_toml,simulation}
if [ -d ../shared/testdata ]; then
  for f in ../shared/testdata/gltf/* ../shared/testdata/vrm/*; do
    case "$f" in *.glb|*.gltf|*.vrm) cp -n "$f" fuzz/corpus/gltf_import/ ;; esac
  done
else
  echo "seeds: ../shared/testdata is missing; the glTF corpus starts from fuzz/regressions only" >&2
fi
cp -n examples/rigs/*.toml fuzz/corpus/rig_toml/
cp -n crates/tassel/src/anim/locomotion.toml fuzz/corpus/state_machine_toml/
