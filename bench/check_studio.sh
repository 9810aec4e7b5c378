#!/usr/bin/env bash
# A real window of the studio (issue 16): starts `vclay-studio` on the fig07 rope cube under
# Xvfb with Mesa's software OpenGL (llvmpipe), drags across the model with xdotool, waits,
# takes a screenshot with ImageMagick and checks that
#   - the screenshot is not blank (many colours, and the clay colour is present), and
#   - the autosaved session's geometry differs from the input (control points away from the
#     rest shape) and its log holds the studio's rope drag (`move-rope`) and a force-brush
#     stroke picked by its key (G; `region-force`).
# The screenshot stays in target/check-studio/ (a CI artifact). Says SKIPPED and exits 0 when
# Xvfb, xdotool or ImageMagick is missing. VCLAY_STUDIO=path uses a built binary; else this
# builds the debug one (the profile CI's `cargo test --workspace` already built).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
name=check_studio
work=$root/target/check-studio
# shellcheck source=bench/studio_window.sh
source bench/studio_window.sh

start_studio examples/scenarios/fig07_rope_cube.toml --autosave "$work/autosave.session" --no-recovery
sleep 4 # the scenario's own rope pulls the cube, a plastic reset keeps the shape at t = 0.9 s
# Fit the view to where the cube is now (the toolbar's Fit button), so it is at the centre of
# the viewport, between the tool panel (left) and the plot panel (right).
xdotool mousemove 179 12 click 1
sleep 1
x0=620; y0=420
xdotool mousemove $x0 $y0 mousedown 1
for k in $(seq 1 20); do
  xdotool mousemove $((x0 + 6 * k)) $((y0 - 4 * k)); sleep 0.05
done
sleep 1.5
xdotool mouseup 1
# A force-brush stroke (key G) across the re-fitted cube: several dabs along the drag.
xdotool mousemove 179 12 click 1
sleep 1
xdotool windowfocus "$win" 2>/dev/null || true
xdotool mousemove $x0 $y0 key g
sleep 0.5
xdotool mousedown 1
for k in $(seq 1 10); do
  xdotool mousemove $((x0 + 12 * k)) $((y0 + 2 * k)); sleep 0.1
done
xdotool mouseup 1
sleep 5 # autosave every 3 s
import -window root "$work/studio.png"
colors=$(convert "$work/studio.png" -format %k info:)
echo "check_studio: screenshot $work/studio.png has $colors colours"
[ "$colors" -gt 50 ] || { echo "check_studio: FAILED: the screenshot is (nearly) one colour"; exit 1; }
# Clay-coloured pixels (the shaded model; render::CLAY is (204, 158, 122) fully lit).
clay=$(convert "$work/studio.png" -fuzz 12% -fill white -opaque "rgb(190,146,112)" -fill black +opaque white -format "%[fx:mean*w*h]" info:)
echo "check_studio: about $clay clay-coloured pixels"
python3 - "$work/autosave.session" "$clay" <<'PY'
import json, sys
path, clay = sys.argv[1], float(sys.argv[2])
s = json.load(open(path))
m = s["models"][0]["state"]
cur, rest = m["state"]["control_points"], m["rest"]["control_points"]
# The scenario's lattice: 4 x 4 x 4 points on the grid of thirds in [0, 1]^3. In sculpt mode (the
# default) a pull ends with a plastic reset, so the rest shape moves too: compare with the grid.
grid = [[i / 3, j / 3, k / 3] for i in range(4) for j in range(4) for k in range(4)]
def away(pts):
    return max(min(max(abs(a - b) for a, b in zip(p, g)) for g in grid) for p in pts)
d = max(away(cur), away(rest))
actions = [e["command"]["action"] for e in s["log"]]
print(f"check_studio: autosave at t = {m['state']['time']:.3f}: {len(actions)} commands "
      f"({', '.join(sorted(set(actions)))}), max control point displacement {d:.4f}")
assert d > 1e-3, "the autosaved geometry equals the input"
assert "plastic-reset" in actions, "sculpt mode (the default) did not keep the pulled shape"
assert "move-rope" in actions, "the studio's drag is not in the autosaved log"
assert "region-force" in actions, "the force-brush stroke (key G) is not in the autosaved log"
assert clay > 2000, "the model is not visible in the screenshot"
PY
echo "check_studio: passed"
