# Sourced by bench/check_studio.sh and bench/check_designer.sh: a real window of the studio
# under Xvfb with Mesa's software OpenGL. Needs `name` (the check's name, for messages) and
# `work` (its output folder, under target/). Sets `studio` (the binary: VCLAY_STUDIO, else the
# debug build), starts Xvfb on a free display (no server reset between clients, so a second
# studio can connect), exports DISPLAY, and kills the studio (`studio_pid`) and Xvfb on exit.
# `start_studio FILE [ARGS...]` starts the studio on FILE (its output appended to
# $work/studio.log), waits for its window, sets `win` and `studio_pid`, and moves the window to
# the top-left corner at 1280 x 800.
# Exits 0 with SKIPPED when Xvfb, xdotool, ImageMagick or python3 is missing.
for tool in Xvfb xdotool import convert python3; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "$name: SKIPPED: $tool not installed (apt-get install xvfb xdotool imagemagick libgl1-mesa-dri)"
    exit 0
  fi
done
target=${CARGO_TARGET_DIR:-$PWD/target}
studio=${VCLAY_STUDIO:-}
if [ -z "$studio" ]; then
  cargo build -q -p vclay-studio
  studio=$target/debug/vclay-studio
fi
rm -rf "$work"; mkdir -p "$work"
n=80
while [ -e "/tmp/.X$n-lock" ] && [ "$n" -lt 99 ]; do n=$((n + 1)); done
Xvfb ":$n" -screen 0 1280x800x24 -nolisten tcp -noreset >"$work/xvfb.log" 2>&1 &
xvfb=$!
studio_pid=
cleanup() {
  [ -n "$studio_pid" ] && kill "$studio_pid" 2>/dev/null || true
  kill "$xvfb" 2>/dev/null || true
}
trap cleanup EXIT
export DISPLAY=":$n" LIBGL_ALWAYS_SOFTWARE=1 VCLAY_NO_NATIVE_DIALOGS=1
ready=
for _ in $(seq 100); do
  if command -v xdpyinfo >/dev/null 2>&1; then
    xdpyinfo >/dev/null 2>&1 && { ready=1; break; }
  else
    sleep 2; ready=1; break
  fi
  kill -0 "$xvfb" 2>/dev/null || break
  sleep 0.1
done
[ -n "$ready" ] || { cat "$work/xvfb.log"; echo "$name: FAILED: Xvfb did not start"; exit 1; }

start_studio() {
  "$studio" "$@" >>"$work/studio.log" 2>&1 &
  studio_pid=$!
  win=
  for _ in $(seq 300); do
    win=$(xdotool search --name "vclay studio" 2>/dev/null | head -1 || true)
    [ -n "$win" ] && break
    kill -0 "$studio_pid" 2>/dev/null || { cat "$work/studio.log"; echo "$name: FAILED: the studio exited"; exit 1; }
    sleep 0.1
  done
  [ -n "$win" ] || { echo "$name: FAILED: no window"; exit 1; }
  xdotool windowmove "$win" 0 0 windowsize "$win" 1280 800 2>/dev/null || true
}
