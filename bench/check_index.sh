#!/usr/bin/env bash
# Opens the demo's index.html in headless Chromium (Debian package `chromium`): checks that every
# picture on the page loads and writes a screenshot to target/demo-index.png.
# Says SKIPPED and exits 0 when Chromium is not installed (apt-get install chromium).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
chrome=$(command -v chromium || command -v chromium-browser || command -v google-chrome || true)
if [ -z "$chrome" ]; then
  echo "check_index: SKIPPED: Chromium is not installed (apt-get install chromium)"; exit 0
fi
target=${CARGO_TARGET_DIR:-$root/target}
cargo build --release -q -p vclay-cli
work=$root/target/check-index
rm -rf "$work"; mkdir -p "$work"
"$target/release/vclay" demo --out "$work/vclay-demo" > /dev/null 2>&1
page="file://$work/vclay-demo/index.html"
flags=(--headless --no-sandbox --disable-gpu --hide-scrollbars --allow-file-access-from-files)
"$chrome" "${flags[@]}" --virtual-time-budget=10000 --dump-dom "$page" 2>/dev/null > "$work/dom.html"
images=$(sed -n 's/.*data-images="\([0-9]*\)".*/\1/p' "$work/dom.html" | head -n 1)
broken=$(sed -n 's/.*data-broken="\([^"]*\)".*/\1/p' "$work/dom.html" | head -n 1)
if [ -z "$images" ]; then
  echo "check_index: FAILED: the page's load script did not run"; exit 1
fi
if [ "$images" -lt 5 ] || [ -n "$broken" ]; then
  echo "check_index: FAILED: $images pictures, broken: ${broken:-none}"; exit 1
fi
"$chrome" "${flags[@]}" --window-size=1200,4000 --screenshot="$root/target/demo-index.png" "$page" 2>/dev/null
test -s "$root/target/demo-index.png"
echo "check_index: passed: $images pictures loaded; screenshot target/demo-index.png"
