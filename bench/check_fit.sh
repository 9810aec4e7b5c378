#!/usr/bin/env bash
# Scan fitting against SciPy (FITPACK LSQBivariateSpline) and geomdl (approximate_surface) on
# the same clouds, in one run (issue 20): bench/get_scan.py makes the clouds (the Jacksboro
# fault DEM that matplotlib ships, and seeded synthetic waves of 100k and 1M points, also with
# 1 % and 2 % one-sided gross outliers: issue 29),
# bench/compare_fit.py fits them with all three at 32 x 32 bicubic and prints errors and times.
# Installs numpy, scipy, geomdl and matplotlib into a venv under target/ when pip can
# (VCLAY_NO_INSTALL=1 forbids it); says SKIPPED and exits 0 otherwise. Takes about a minute
# (geomdl is pure Python): not part of .ci/run.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
target=${CARGO_TARGET_DIR:-$root/target}
venv=$target/fit-venv
if ! "$venv/bin/python" -c "import numpy, scipy, geomdl, matplotlib" 2>/dev/null; then
  if [ -n "${VCLAY_NO_INSTALL:-}" ]; then
    echo "check_fit: SKIPPED: numpy/scipy/geomdl/matplotlib not installed in $venv (VCLAY_NO_INSTALL set)"; exit 0
  fi
  echo "check_fit: installing numpy scipy geomdl matplotlib into $venv"
  if ! { [ -x "$venv/bin/pip" ] || python3 -m venv "$venv"; } ||
     ! "$venv/bin/pip" install -q numpy scipy geomdl matplotlib; then
    echo "check_fit: SKIPPED: could not install scipy/geomdl (no python3 venv or no PyPI)"; exit 0
  fi
fi
cargo build --release -q -p vclay-cli
data=$target/fit-data
"$venv/bin/python" bench/get_scan.py "$data"
"$venv/bin/python" bench/compare_fit.py "$target/release/vclay" "$data"
