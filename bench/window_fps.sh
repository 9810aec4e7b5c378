#!/usr/bin/env bash
# The studio's frame rate in a real window (issue 27): the release `vclay-studio` under Xvfb with
# Mesa's llvmpipe (software OpenGL: every pixel is drawn by the CPU, on the same 2 cores as the
# simulation), on the frame-loop benchmark's models (`vclay-studio --bench`): the 4^3 cube at
# levels 3 and 4 and the 32 x 32 D-NURBS sheet with frozen and dynamic weights (the direct
# solve and the default for this size, the block-Schur one). For each, the
# studio opens the model, xdotool drags a rope across it for DRAG seconds (a slow circle, so
# the simulation and the picture both change every frame), and the window's `--frame-log`
# (one line a second: frames/s, steps/s, step and display ms) is read back. Prints one
# Markdown table with the load average before and after each case. Not a check: figures only.
#   bench/window_fps.sh [DRAG_SECONDS]      (default 10; VCLAY_STUDIO=path picks the binary)
# Says SKIPPED and exits 0 when Xvfb, xdotool or ImageMagick is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
name=window_fps
work=$root/target/window-fps
drag_s=${1:-10}
case "$drag_s" in '' | *[!0-9]*) echo "window_fps: DRAG_SECONDS must be a whole number of seconds: $drag_s"; exit 2 ;; esac
[ "$drag_s" -ge 3 ] && [ "$drag_s" -le 120 ] || { echo "window_fps: DRAG_SECONDS must be 3-120: $drag_s"; exit 2; }
if [ -z "${VCLAY_STUDIO:-}" ]; then
  cargo build -q --release -p vclay-studio
  export VCLAY_STUDIO=${CARGO_TARGET_DIR:-$root/target}/release/vclay-studio
fi
# shellcheck source=bench/studio_window.sh
source bench/studio_window.sh

cube() { # LEVEL DT
  printf '[model]\nkind = "subdivision-solid"\nprimitive = "box"\npoints = [4, 4, 4]\nlevel = %s\n[material]\ndamping = 2.0\nedge_stiffness = 100.0\nvirtual_stiffness = 50.0\n[simulation]\nintegrator = "symplectic"\ndt = %s\n' "$1" "$2"
}
sheet() { # MODEL_LINES SIMULATION_LINES
  printf '[model]\nkind = "dnurbs-surface"\nsize = [32, 32]\ndegree = [3, 3]\n%b[simulation]\ndt = 0.01\n%b' "$1" "${2:-}"
}
cube 3 0.002 >"$work/cube3.toml"
cube 4 0.001 >"$work/cube4.toml"
sheet 'engine = "frozen"\n' >"$work/sheet_frozen.toml"
sheet '' 'solver = "direct"\n' >"$work/sheet_dynamic_direct.toml"
sheet '' >"$work/sheet_dynamic_block_schur.toml" # the default for this size

median() { sort -g | awk '{a[NR] = $1} END {if (NR == 0) print "nan"; else if (NR % 2) print a[(NR + 1) / 2]; else print (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
load() { cut -d' ' -f1 /proc/loadavg; }

echo "| model | triangles | frames/s (median of the drag's seconds) | steps/s | step ms | display ms | load before / after |"
echo "| --- | ---: | ---: | ---: | ---: | ---: | --- |"
for m in cube3 cube4 sheet_frozen sheet_dynamic_direct sheet_dynamic_block_schur; do
  log=$work/$m.frames
  before=$(load)
  start_studio "$work/$m.toml" --autosave "$work/autosave.session" --no-recovery --frame-log "$log"
  sleep 3
  xdotool windowfocus "$win" 2>/dev/null || true
  # Front view of the cubes, top view of the sheets (they lie in the xy plane), framed; the
  # rope (R) grabs the model at the viewport's centre and circles.
  case "$m" in sheet*) view=7 ;; *) view=1 ;; esac
  xdotool mousemove 660 400; sleep 0.2; xdotool key "$view"; sleep 0.3; xdotool key f; sleep 1; xdotool key r; sleep 0.3
  start=$(awk 'END {print $1}' "$log")
  xdotool mousedown 1
  steps=$((drag_s * 10))
  for k in $(seq 1 "$steps"); do
    a=$(awk -v k="$k" 'BEGIN {printf "%d %d", 660 + 60 * sin(k / 8), 400 - 40 + 40 * cos(k / 8)}')
    # shellcheck disable=SC2086
    xdotool mousemove $a; sleep 0.1
  done
  xdotool mouseup 1
  end=$(awk 'END {print $1}' "$log")
  import -window root "$work/$m.png"
  kill "$studio_pid" 2>/dev/null || true; wait "$studio_pid" 2>/dev/null || true; studio_pid=
  after=$(load)
  # The seconds of the drag (after the first, which may include the grab).
  rows=$(awk -v s="$start" -v e="$end" '!/^#/ && $1 > s + 1 && $1 <= e' "$log")
  [ -n "$rows" ] || { echo "window_fps: FAILED: no frame-log lines during the drag of $m"; exit 1; }
  fps=$(echo "$rows" | awk '{print $2}' | median)
  sps=$(echo "$rows" | awk '{print $5}' | median)
  sms=$(echo "$rows" | awk '{print $6}' | median)
  dms=$(echo "$rows" | awk '{print $7}' | median)
  tris=$(echo "$rows" | awk 'END {print $8}')
  echo "| $m | $tris | $fps | $sps | $sms | $dms | $before / $after |"
done
echo "window_fps: screenshots and frame logs in $work"
