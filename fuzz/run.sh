#!/usr/bin/env bash
# Runs every fuzz target of fuzz/ for SECONDS each (default 60), starting from fuzz/seeds/TARGET
# and keeping what libFuzzer finds in fuzz/corpus/TARGET (not committed); crashes land in
# fuzz/artifacts/TARGET. Prints one line per target: executions, corpus size, result.
#
#   fuzz/run.sh [SECONDS] [TARGET...]
#
# Needs cargo-fuzz (`cargo install cargo-fuzz`; it builds on stable) and nightly compiler flags:
# a nightly toolchain when rustup has one, otherwise RUSTC_BOOTSTRAP=1 on the stable compiler.
# That is acceptable for this local script only, never in CI; CI runs the seeded mutation
# tests (crates/vclay-io/tests/hostile.rs, crates/vclay-session/tests/hostile.rs) instead.
set -euo pipefail
cd "$(dirname "$0")"
secs=${1:-60}
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    targets=(model_json params geomdl obj stl ply glb step iges ovm pde_spec expr scenario session)
fi
if rustup toolchain list 2>/dev/null | grep -q '^nightly'; then
    fuzz=(cargo +nightly fuzz)
else
    export RUSTC_BOOTSTRAP=1
    fuzz=(cargo fuzz)
fi
status=0
for t in "${targets[@]}"; do
    mkdir -p "corpus/$t" "artifacts/$t"
    log="artifacts/$t/last-run.log"
    # -rss_limit_mb: an input that makes a reader allocate 2 GB is a finding (issue 17).
    if "${fuzz[@]}" run --release "$t" "corpus/$t" "seeds/$t" -- \
        -max_total_time="$secs" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 \
        >"$log" 2>&1; then
        result=clean
    else
        result="FAILED (see $log and artifacts/$t)"
        status=1
    fi
    execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
    printf '%-11s %10s executions  %5s corpus files  %s\n' "$t" "$execs" \
        "$(ls "corpus/$t" | wc -l)" "$result"
done
exit $status
