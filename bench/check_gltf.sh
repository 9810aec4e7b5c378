#!/usr/bin/env bash
# External check of vclay's glTF export with the Khronos glTF validator (npm gltf-validator):
# the demo's animated wave.glb (morph targets) and `vclay convert` outputs of a surface model, a
# volume and a mesh. Installs gltf-validator into target/node-tools when npm can (set
# VCLAY_NO_INSTALL=1 to forbid installing). Says SKIPPED and exits 0 when node or the validator
# is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
tools=$root/target/node-tools
if ! command -v node >/dev/null 2>&1; then
  echo "check_gltf: SKIPPED: node is not installed"; exit 0
fi
if [ ! -d "$tools/node_modules/gltf-validator" ]; then
  if [ -n "${VCLAY_NO_INSTALL:-}" ] || ! command -v npm >/dev/null 2>&1; then
    echo "check_gltf: SKIPPED: gltf-validator not installed in $tools"; exit 0
  fi
  echo "check_gltf: installing gltf-validator into $tools"
  mkdir -p "$tools"
  if ! (cd "$tools" && npm install --silent --no-audit --no-fund gltf-validator >/dev/null); then
    echo "check_gltf: SKIPPED: could not install gltf-validator from npm"; exit 0
  fi
fi
target=${CARGO_TARGET_DIR:-$root/target}
cargo build --release -q -p vclay-cli
vclay=$target/release/vclay
work=$root/target/check-gltf
rm -rf "$work"; mkdir -p "$work"
"$vclay" demo --out "$work/demo" > /dev/null 2>&1
"$vclay" convert "$work/demo/torus.json" "$work/torus.glb" 2>/dev/null
"$vclay" convert "$work/demo/twisted_volume.json" "$work/volume.glb" 2>/dev/null
"$vclay" convert "$work/demo/ffd/fig3b-bottle.obj" "$work/bottle.glb" 2>/dev/null
NODE_PATH=$tools/node_modules node bench/validate_gltf.cjs \
  "$work/demo/wave.glb" "$work/torus.glb" "$work/volume.glb" "$work/bottle.glb"
