#!/usr/bin/env bash
# Every peer comparison in one go, one table in docs/performance.md (issue 31).
# Runs, each as it is and each creating its own Python environment when pip can:
#   eval    python3 bench/compare.py     surface evaluation vs OpenNURBS (rhino3dm) and geomdl
#   solids  bash bench/solids_peers.sh   mass-spring step vs Taichi and NVIDIA Warp (CPU)
#   ffd     python3 bench/ffd_peers.py   1M-vertex FFD vs PyGeM (needs VCLAY_PYGEM_SRC: see there)
#   fit     bash bench/check_fit.sh      scan fitting vs SciPy's FITPACK and geomdl
# Before and after each one it times the fixed reference workload (vclay-core's example
# `yardstick`, with the 1-minute load average), so a slow host can be told from a slow build.
# Every script checks that its peer computes the same thing before timing it, and appends
# one JSON row per comparison to the file named by VCLAY_PEERS_ROWS (bench/peers_rows.py);
# bench/peers_table.py then writes the table between the marker comments of
# docs/performance.md (the rows of suites not run this time are kept, with their own date) and
# the rows to bench/peers.json. A suite that says SKIPPED or fails gets a row saying so; the
# others still run. Logs and rows of the run: target/peers/<UTC time>/.
# Env: VCLAY_PEERS_ONLY (comma list of suites, default eval,solids,ffd,fit), VCLAY_NO_INSTALL,
# and each script's own (VCLAY_PEERS_LEVELS, VCLAY_PEERS_SECONDS, VCLAY_FFD_SIDE, ...).
# Takes 10-20 minutes on 2 cores with every suite: not part of .ci/run.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
target=${CARGO_TARGET_DIR:-$root/target}
only=${VCLAY_PEERS_ONLY:-eval,solids,ffd,fit}
for name in ${only//,/ }; do
  case $name in
    eval | solids | ffd | fit) ;;
    *) echo "peers: unknown suite '$name' in VCLAY_PEERS_ONLY (eval, solids, ffd, fit)" >&2; exit 2 ;;
  esac
done
work=$target/peers/$(date -u +%Y%m%dT%H%M%SZ)
mkdir -p "$work"
cargo build --release -q -p vclay-core --example yardstick
yardstick() { "$target/release/examples/yardstick" 0.5; }

run_suite() {
  local name=$1
  shift
  case ",$only," in
    *",$name,"*) ;;
    *) echo "peers: $name not selected (VCLAY_PEERS_ONLY=$only)"; return 0 ;;
  esac
  echo "peers: == $name: $*"
  date -u +%Y-%m-%dT%H:%MZ >"$work/$name.date"
  yardstick >"$work/$name.yard_start"
  local rc=0
  VCLAY_PEERS_ROWS=$work/$name.rows "$@" 2>&1 | tee "$work/$name.log" || rc=$?
  echo "$rc" >"$work/$name.rc"
  yardstick >"$work/$name.yard_end"
  echo "peers: $name exit $rc; yardstick $(cat "$work/$name.yard_start") -> $(cat "$work/$name.yard_end")"
}

run_suite eval python3 bench/compare.py
run_suite solids bash bench/solids_peers.sh
run_suite ffd python3 bench/ffd_peers.py
run_suite fit bash bench/check_fit.sh
python3 bench/peers_table.py "$work" docs/performance.md
echo "peers: table written to docs/performance.md; run folder $work"
