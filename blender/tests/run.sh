#!/usr/bin/env bash
# Tassel for Blender's tests, headless, with Blender as a Python module (bpy 5.0.1, Python
# 3.11) and the VRM Add-on for Blender (bpy-vrm-format) in a virtual environment this
# script makes (target/blender-venv). Blender's user folders go to target/blender-user,
# so nothing of yours is touched.
#
#   bash blender/tests/run.sh          # set up (if needed), build the zip, run every test
#   bash blender/tests/run.sh setup    # only the virtual environment (CI starts it early)
#
# Needs target/release/tassel (the reference the tests compare with): cargo build --release.
set -euo pipefail
cd "$(dirname "$0")/../.."
venv=target/blender-venv
export BLENDER_USER_RESOURCES="$PWD/target/blender-user"
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c 'import bpy, io_scene_vrm' 2>/dev/null; then
  rm -rf "$venv"
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check bpy==5.0.1 bpy-vrm-format==4.10.2
fi
if [ "${1:-}" = setup ]; then
  exit 0
fi
[ -x target/release/tassel ] || cargo build --release -p tassel-cli
zip=$(bash blender/build.sh | tail -n 1)
py="$venv/bin/python"
# Blender's own extension validator (what `blender --command extension validate` runs).
"$py" "$("$py" -c 'import bpy, os; print(os.path.join(bpy.utils.system_resource("SCRIPTS"), "addons_core", "bl_pkg", "cli", "blender_ext.py"))' 2>/dev/null | tail -n 1)" validate "$zip"
log=target/blender-test.log
for test in test_pose test_fox test_vrm test_vrm0 test_sources test_bad_input test_preview; do
  echo "== blender/tests/$test.py"
  if ! "$py" "blender/tests/$test.py" "$zip" >"$log" 2>&1; then
    cat "$log" >&2
    echo "error: blender/tests/$test.py failed" >&2
    exit 1
  fi
  grep -E '^OK' "$log"
  # Headless, a bake says how far it is on the console, a line per 10 %.
  if [ "$test" = test_fox ]; then
    lines=$(grep -c "^Tassel: baking 'root' frames 0–120: " "$log" || true)
    if [ "$lines" -lt 10 ] || ! grep -q "^Tassel: baking 'root' frames 0–120: 100 %" "$log"; then
      echo "error: the headless bake printed $lines progress lines, not one per 10 % ending at 100 %" >&2
      exit 1
    fi
    echo "OK the headless bake printed $lines progress lines, the last at 100 %"
  fi
done
