#!/usr/bin/env bash
# Coverage-guided fuzzing on stable Rust: libFuzzer (from the libfuzzer-sys crate, built
# with the machine's C++ compiler) driven by LLVM's SanitizerCoverage, which stable rustc
# enables with `-C passes=sancov-module` and `-C llvm-args=-sanitizer-coverage-*` (what
# cargo-fuzz passes, minus the nightly-only address sanitizer). Debug assertions and
# overflow checks stay on, so an arithmetic overflow is a finding too.
#
#   fuzz/run.sh TARGET [SECONDS] [-- libFuzzer options...]
#   fuzz/run.sh all [SECONDS]          # each target in turn
#
# Targets: gltf_import, ffi_load (the C ABI's load and frame), ffi_skeleton (tassel_character_new), rig_toml, state_machine_toml, simulation. The corpus lives in
# fuzz/corpus/TARGET (not committed; seeded by fuzz/seeds.sh from ../shared/testdata, the
# example rigs and fuzz/regressions); crashes land in fuzz/artifacts/TARGET. A crash input
# belongs in fuzz/regressions/TARGET/ with its fix: `cargo test -p tassel-fuzz` replays it.
# The last lines of each run give libFuzzer's "Done N runs in S second(s)".
set -euo pipefail
cd "$(dirname "$0")/.."
target="${1:?usage: fuzz/run.sh TARGET|all [SECONDS] [-- libFuzzer options]}"
seconds="${2:-60}"
shift $(( $# < 2 ? $# : 2 ))
[ "${1:-}" = "--" ] && shift
extra=("$@")
triple="$(rustc -vV | sed -n 's/^host: //p')"
export RUSTFLAGS="-C passes=sancov-module -C llvm-args=-sanitizer-coverage-level=4 \
-C llvm-args=-sanitizer-coverage-inline-8bit-counters -C llvm-args=-sanitizer-coverage-pc-table \
-C llvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing -C debug-assertions -C overflow-checks \
-C codegen-units=16"
# --target keeps the flags off build scripts and proc macros; a target dir of its own
# keeps the instrumented build apart from the normal one.
cargo build --release -p tassel-fuzz --features libfuzzer --bins \
  --target "$triple" --target-dir target/fuzz
bash fuzz/seeds.sh
targets=("$target")
[ "$target" = all ] && targets=(gltf_import ffi_load ffi_skeleton rig_toml state_machine_toml simulation)
for t in "${targets[@]}"; do
  mkdir -p "fuzz/corpus/$t" "fuzz/artifacts/$t"
  dict=()
  [ -f "fuzz/dict/$t.dict" ] && dict=(-dict="fuzz/dict/$t.dict")
  echo "== $t for ${seconds}s"
  "target/fuzz/$triple/release/$t" "fuzz/corpus/$t" "fuzz/regressions/$t" \
    -max_total_time="$seconds" -max_len=65536 -rss_limit_mb=2048 -timeout=10 \
    -artifact_prefix="fuzz/artifacts/$t/" -print_final_stats=1 "${dict[@]}" "${extra[@]}" \
    2>&1 | tee "target/fuzz/$t.log" | grep -E "^#[0-9]+ +(INITED|DONE|NEW)|Done [0-9]+ runs|stat::|ERROR|panicked|SUMMARY" | tail -n 12
done
