#!/usr/bin/env bash
# External check of vclay's geomdl JSON read/write with NURBS-Python (geomdl) itself
# (bench/check_geomdl.py). Uses bench/.venv (the peers' venv of bench/compare.py) and installs
# geomdl there when pip can (VCLAY_NO_INSTALL=1 forbids it). Says SKIPPED and exits 0 otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
venv=$root/bench/.venv
if ! "$venv/bin/python" -c "import geomdl" 2>/dev/null; then
  if [ -n "${VCLAY_NO_INSTALL:-}" ]; then
    echo "check_geomdl: SKIPPED: geomdl not installed in $venv (VCLAY_NO_INSTALL set)"; exit 0
  fi
  echo "check_geomdl: installing geomdl into $venv"
  if ! { [ -x "$venv/bin/pip" ] || python3 -m venv "$venv"; } || ! "$venv/bin/pip" install -q geomdl; then
    echo "check_geomdl: SKIPPED: could not install geomdl (no python3 venv or no PyPI)"; exit 0
  fi
fi
target=${CARGO_TARGET_DIR:-$root/target}
cargo build --release -q -p vclay-cli
vclay=$target/release/vclay
work=$root/target/check-geomdl
rm -rf "$work"; mkdir -p "$work"
"$vclay" demo --out "$work/demo" > /dev/null 2>&1
"$venv/bin/python" bench/check_geomdl.py "$vclay" "$work" \
  "$work/demo/torus.json" "$work/demo/sheet.json" "$work/demo/twisted_volume.json" \
  bench/models/curves.json
