#!/usr/bin/env bash
# External check of vclay's STEP and IGES export: loads the files in OpenCASCADE (cadquery-ocp from PyPI)
# and compares points with `vclay eval` to 1e-9 (bench/check_step.py).
# Uses target/venv-ocp; creates it and installs cadquery-ocp-novtk when pip can (set
# VCLAY_NO_INSTALL=1 to forbid installing). Says SKIPPED and exits 0 when OpenCASCADE is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
venv=$root/target/venv-ocp
if ! "$venv/bin/python" -c "import OCP" 2>/dev/null; then
  if [ -n "${VCLAY_NO_INSTALL:-}" ]; then
    echo "check_step: SKIPPED: cadquery-ocp not installed in $venv (VCLAY_NO_INSTALL set)"; exit 0
  fi
  echo "check_step: installing cadquery-ocp-novtk into $venv"
  if ! { python3 -m venv "$venv" && "$venv/bin/pip" install -q cadquery-ocp-novtk; }; then
    echo "check_step: SKIPPED: could not install cadquery-ocp (no python3 venv or no PyPI)"; exit 0
  fi
fi
target=${CARGO_TARGET_DIR:-$root/target}
cargo build --release -q -p vclay-cli
vclay=$target/release/vclay
work=$root/target/check-step
rm -rf "$work"; mkdir -p "$work"
"$vclay" demo --out "$work/demo" > /dev/null 2>&1
for fmt in step iges; do
  "$venv/bin/python" bench/check_step.py "$vclay" "$work" "$fmt" \
    "$work/demo/torus.json" "$work/demo/sheet.json" "$work/demo/twisted_volume.json" \
    bench/models/curves.json
done
