#!/usr/bin/env bash
# Peer comparison of one mass-spring step (issue 4): vclay's dynamic solid lattice (4^3 cube,
# subdivision levels 2..5) beside the same lattice stepped by Taichi and NVIDIA Warp on the CPU.
# 1. builds and runs `vclay-solids`'s example `spring_export` in release per level: it writes the
#    lattice as .npy files (layout in crates/vclay-solids/examples/spring_export.rs) and times
#    vclay's step on 1 thread and on rayon's pool;
# 2. bench/solids_peers.py steps the same lattice with Taichi (1 and 2 threads) and Warp, checks
#    their forces against vclay's, and writes the Markdown table to bench/solids_peers.md.
# Uses bench/.venv-peers (taichi, warp-lang, numpy from PyPI, pinned below; tooling only, not a
# Rust dependency); creates it when pip can (set VCLAY_NO_INSTALL=1 to forbid installing).
# Says SKIPPED and exits 0 when the packages are absent.
# Env: VCLAY_PEERS_LEVELS (default "2 3 4 5"), VCLAY_PEERS_SECONDS (timing per measurement,
# default 2).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
venv=$root/bench/.venv-peers
pkgs=(taichi==1.7.4 warp-lang==1.19.0 numpy==2.4.6)
if ! "$venv/bin/python" -c "import taichi, warp, numpy" >/dev/null 2>&1; then
  if [ -n "${VCLAY_NO_INSTALL:-}" ]; then
    echo "solids_peers: SKIPPED: taichi/warp-lang not installed in $venv (VCLAY_NO_INSTALL set)"; exit 0
  fi
  echo "solids_peers: installing ${pkgs[*]} into $venv"
  if ! { python3 -m venv "$venv" && "$venv/bin/pip" install -q "${pkgs[@]}"; }; then
    echo "solids_peers: SKIPPED: could not install taichi/warp-lang (no python3 venv or no PyPI)"; exit 0
  fi
fi
levels=${VCLAY_PEERS_LEVELS:-2 3 4 5}
seconds=${VCLAY_PEERS_SECONDS:-2}
target=${CARGO_TARGET_DIR:-$root/target}
cargo build --release -q -p vclay-solids --example spring_export
work=$target/solids-peers
mkdir -p "$work"
dirs=()
for level in $levels; do
  "$target/release/examples/spring_export" "$level" "$work/level$level" "$seconds"
  dirs+=("$work/level$level")
done
"$venv/bin/python" bench/solids_peers.py --seconds "$seconds" --out bench/solids_peers.md "${dirs[@]}"
