#!/usr/bin/env bash
# Feature unification (CI time): the release CLI (`vclay demo`) and the Python wheel are built
# into one target folder, and a crate is built twice when the two dependency trees ask for
# different features of it. crates/vclay-cli/Cargo.toml asks for the features the module's
# dependencies ask for; this fails, naming the crates, when a dependency update breaks that.
set -euo pipefail
cd "$(dirname "$0")/.."
tree() {
  cargo tree --locked -p "$1" -e normal,build -f '{p} [{f}]' --prefix none | sed 's/ (\*)//' |
    grep -v '^vclay' | sort -u
}
cli=$(mktemp) py=$(mktemp)
trap 'rm -f "$cli" "$py"' EXIT
tree vclay-cli >"$cli"
tree vclay-python >"$py"
python3 - "$cli" "$py" <<'PY'
import sys
def read(path):
    out = {}
    for line in open(path):
        name, _, feats = line.rstrip("\n").partition(" [")
        out.setdefault(name, set()).add(feats)
    return out
cli, py = read(sys.argv[1]), read(sys.argv[2])
if not cli or not py:
    sys.exit("check_features: cargo tree listed no crates")
bad = [f"{k}: CLI [{' | '.join(sorted(cli[k]))}, Python [{' | '.join(sorted(py[k]))}"
       for k in sorted(cli.keys() & py.keys()) if cli[k] != py[k]]
if bad:
    print("check_features: the CLI and the Python module build these crates with different "
          "features (each is built twice in CI; see crates/vclay-cli/Cargo.toml):")
    print("\n".join("  " + b for b in bad))
    sys.exit(1)
print(f"check_features: {len(cli.keys() & py.keys())} shared crates, same features")
PY
