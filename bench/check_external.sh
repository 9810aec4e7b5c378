#!/usr/bin/env bash
# Runs every external validation of issue 8 (each says SKIPPED and passes when its tool is absent):
# glTF (Khronos validator), STEP and IGES (OpenCASCADE), geomdl JSON (NURBS-Python), lattices and
# scenario frames (VTK), and the demo page in headless Chromium (screenshot target/demo-index.png).
set -euo pipefail
cd "$(dirname "$0")"
for s in check_gltf.sh check_step.sh check_geomdl.sh check_vtk.sh check_index.sh; do
  echo "== bench/$s"
  bash "$s"
done
