#!/usr/bin/env bash
# External check of vclay's lattice and frame files with VTK itself (the engine of ParaView),
# bench/check_vtk.py: `vclay subdivide` output of every primitive (control lattices with wedges
# and polyhedra, subdivided lattices) and the frames of a `vclay run` scenario (VTU, OBJ, PLY,
# STL) and the closed surfaces of `vclay demo` are read by VTK's readers; every cell must have
# positive volume by vtkCellSizeFilter, the surfaces must be closed and oriented outward, and the
# lattices' surfaces must enclose the cells' volume.
# Uses bench/.venv and installs the `vtk` wheel there when pip can (VCLAY_NO_INSTALL=1 forbids
# it). Says SKIPPED and exits 0 otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
venv=$root/bench/.venv
if ! "$venv/bin/python" -c "import vtk" 2>/dev/null; then
  if [ -n "${VCLAY_NO_INSTALL:-}" ]; then
    echo "check_vtk: SKIPPED: vtk not installed in $venv (VCLAY_NO_INSTALL set)"; exit 0
  fi
  echo "check_vtk: installing vtk into $venv"
  if ! { [ -x "$venv/bin/pip" ] || python3 -m venv "$venv"; } || ! "$venv/bin/pip" install -q vtk numpy; then
    echo "check_vtk: SKIPPED: could not install vtk (no python3 venv or no PyPI)"; exit 0
  fi
fi
target=${CARGO_TARGET_DIR:-$root/target}
cargo build --release -q -p vclay-cli
vclay=$target/release/vclay
work=$root/target/check-vtk
rm -rf "$work"; mkdir -p "$work"
"$venv/bin/python" bench/check_vtk.py "$vclay" "$work"
