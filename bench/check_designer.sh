#!/usr/bin/env bash
# A designer's session in a real window (issue 27): the studio on the fig07 rope cube under Xvfb
# with Mesa's llvmpipe, driven by xdotool the way a person would, with screenshots kept in
# target/check-designer/ (CI artifacts). Steps and what is checked (from the sessions saved on
# the way, read back with Python):
#   1. front view (key 1), frame (F); the cube's box on screen is found from the clay colour;
#   2. once a saved session says the scenario has ended (t = 1.5 s), the fix brush (H), grown
#      twice with ], strokes along the cube's bottom edge: the control points it fixed (saved
#      and checked at once) are the bottom ones (all in the lower half, three or more at the
#      bottom), and they stay fixed through the pull;
#   3. symmetry X on, the rope (R) pulls the top right up: the mirrored rope pulls the top left,
#      and both sides rise alike;
#   4. released in sculpt mode (the default), the shape stays: the session saved 0.7 s after the
#      release and the one saved 2.5 s later have the same control points;
#   5. paused (Space) and saved, Ctrl+O opens the Open dialog, three clicks land in its path
#      field over the model, Esc closes it: no rope was attached (the log's rope count is
#      unchanged);
#   6. the last session saved is opened again in a new studio and saved at once: the control
#      points are the same.
# A failed step prints the window's last frame-log lines and the saved session's command log;
# a fix stroke that fixed no bottom point is tried once more, with a warning.
# Says SKIPPED and exits 0 when Xvfb, xdotool or ImageMagick is missing. VCLAY_STUDIO=path uses
# a built binary; else this builds the debug one.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
name=check_designer
work=$root/target/check-designer
# shellcheck source=bench/studio_window.sh
source bench/studio_window.sh

starts=0
start() { # FILE: starts the studio on FILE and waits for its window
  starts=$((starts + 1))
  start_studio "$1" --autosave "$work/autosave.session" --no-recovery \
    --frame-log "$work/frames_$starts.txt"
  sleep 3
  xdotool windowfocus "$win" 2>/dev/null || true
}
# What the studio did, printed when a step fails: the last frame-log lines (frames/s, simulated
# time, steps/s) and the commands of the session saved last (step, time, action, message).
diagnose() { # SESSION
  echo "check_designer: the window's last frame-log lines (wall_s frames/s sim_t steps steps/s ...):"
  tail -n 4 "$work"/frames_*.txt 2>/dev/null | sed 's/^/  /' || true
  python3 - "$1" <<'PY' || true
import json, sys
s = json.load(open(sys.argv[1]))
print(f"check_designer: the log of {sys.argv[1]}:")
for e in s["log"]:
    if e["command"]["action"] != "move-rope":
        print(f"  step {e['step']} t {e['time']:.3f} {e['command']['action']}: {e['message'][:70]}")
PY
  tail -n 5 "$work/studio.log" 2>/dev/null | sed 's/^/  studio: /' || true
}
save_as() { # PATH: Ctrl+Shift+S, type the path, Enter
  xdotool key ctrl+shift+s; sleep 0.8
  xdotool key ctrl+a; xdotool type --delay 5 "$1"; xdotool key Return
  for _ in $(seq 50); do [ -s "$1" ] && break; sleep 0.1; done
  [ -s "$1" ] || { echo "check_designer: FAILED: $1 was not saved"; exit 1; }
}
drag() { # X0 Y0 X1 Y1 STEPS HOLD: a press, a drag in STEPS moves, HOLD s, release
  xdotool mousemove "$1" "$2"; sleep 0.3; xdotool mousedown 1
  for k in $(seq 1 "$5"); do
    xdotool mousemove $(($1 + ($3 - $1) * k / $5)) $(($2 + ($4 - $2) * k / $5)); sleep 0.06
  done
  sleep "$6"; xdotool mouseup 1
}

# 1. The scenario's own rope pulls the cube and lets go; it ends (and pauses) at t = 1.5 s.
start examples/scenarios/fig07_rope_cube.toml
sleep 3
xdotool mousemove 600 500; sleep 0.3; xdotool key 1; sleep 0.5; xdotool key f; sleep 1.5
import -window root "$work/1_front.png"
# The viewport is x 308..1012, y 33..768 of the 1280 x 800 window.
box=$(convert "$work/1_front.png" -crop 704x735+308+33 +repage -fuzz 18% -fill white \
  -opaque "rgb(200,150,120)" -fill black +opaque white -format "%@" info:)
read -r bw bh bx by <<<"$(echo "$box" | sed 's/[x+]/ /g')"
bx=$((bx + 308)); by=$((by + 33))
echo "check_designer: the cube on screen: ${bw}x${bh} at ($bx, $by)"
[ "$bw" -gt 100 ] && [ "$bh" -gt 100 ] || { echo "check_designer: FAILED: no cube in the front view"; exit 1; }
# The designer starts once the scenario has ended (t = 1.5 s; its timeline frees the bottom at
# t = 0.9, which would undo a fix stroke made before): saved until the saved time says so.
ended=
for k in $(seq 1 20); do
  save_as "$work/0_before_$k.session"
  if python3 -c 'import json, sys; s = json.load(open(sys.argv[1]))
sys.exit(0 if s["models"][0]["state"]["state"]["time"] >= 1.5 - 1e-9 else 1)' \
    "$work/0_before_$k.session"; then
    cp "$work/0_before_$k.session" "$work/0_before.session"; ended=1; break
  fi
  sleep 1
done
[ -n "$ended" ] || { diagnose "$work/0_before_$k.session"; echo "check_designer: FAILED: the scenario did not end"; exit 1; }

# 2. Fix brush, grown twice (]), along the bottom edge; saved and checked at once. A stroke
# that fixed nothing is tried once more after the diagnosis is printed (CI saw one once, on a
# machine whose screenshots it did not keep); a second failure fails the check.
fix_ok() { # SESSION: the fix brush fixed bottom points, and only points in the lower half
  python3 - "$work/0_before.session" "$1" <<'PY'
import json, sys
p0 = json.load(open(sys.argv[1]))["models"][0]["state"]["state"]["control_points"]
m = json.load(open(sys.argv[2]))["models"][0]["state"]
zs = [p[2] for p in p0]
zlo, zhi = min(zs), max(zs)
fixed = [i for i, f in enumerate(m["rest"]["fixed"]) if f]
heights = [(p0[i][2] - zlo) / (zhi - zlo) for i in fixed]
print(f"check_designer: fix brush fixed {len(fixed)} control points, heights {[round(h, 2) for h in heights]}")
if sum(h < 0.1 for h in heights) < 3:
    sys.exit("check_designer: the fix stroke fixed too few bottom points")
if max(heights) >= 0.5:
    sys.exit("check_designer: the fix brush fixed points away from the stroke")
PY
}
fixed_ok=
for try in 1 2; do
  xdotool key h; sleep 0.3
  # Grown twice (once more on the second try, should the first have missed a key).
  xdotool key bracketright; sleep 0.2
  [ "$try" = 2 ] || { xdotool key bracketright; sleep 0.3; }
  drag $((bx + bw / 10)) $((by + bh * 93 / 100)) $((bx + bw * 9 / 10)) $((by + bh * 93 / 100)) 20 0.2
  sleep 0.5
  save_as "$work/0_fixed_$try.session"
  if fix_ok "$work/0_fixed_$try.session"; then
    cp "$work/0_fixed_$try.session" "$work/0_fixed.session"; fixed_ok=1; break
  fi
  diagnose "$work/0_fixed_$try.session"
  [ "$try" = 2 ] || echo "check_designer: WARNING: the fix stroke fixed nothing at the bottom; once more"
done
[ -n "$fixed_ok" ] || { echo "check_designer: FAILED: the fix stroke fixed too few bottom points"; exit 1; }

# 3. Symmetry X, rope up from the top right (its mirror pulls the top left). The top of the
# clay in that column (the scenario's rope left a dome on the top face, so the box's top is
# the dome's).
gx=$((bx + bw * 8 / 10))
col=$(convert "$work/1_front.png" -crop "1x735+$gx+33" +repage -fuzz 18% -fill white \
  -opaque "rgb(200,150,120)" -fill black +opaque white -format "%@" info: 2>/dev/null)
gy=$(($(echo "$col" | sed 's/.*+//') + 33 + bh * 4 / 100))
echo "check_designer: the rope grabs at ($gx, $gy)"
xdotool key x; sleep 0.2; xdotool key r; sleep 0.3
drag "$gx" "$gy" "$gx" $((gy - bh * 36 / 100)) 25 1.5
import -window root "$work/2_pulled.png"

# 4. Saved 0.7 s after the release and 2.5 s later.
sleep 0.7
save_as "$work/1_released.session"
sleep 2.5
# Paused (Space) and saved: nothing is unsaved, so Ctrl+O opens its dialog without a prompt.
xdotool key space; sleep 0.5
save_as "$work/2_later.session"
import -window root "$work/3_later.png"

# 5. Clicks inside the Open dialog over the model attach nothing.
xdotool key ctrl+o; sleep 0.8
import -window root "$work/4_dialog.png"
for k in 1 2 3; do xdotool mousemove $((600 + 10 * k)) 400 click 1; sleep 0.3; done
xdotool key Escape; sleep 0.5
save_as "$work/3_after_dialog.session"

# 6. Reopen in a new studio, save at once.
kill "$studio_pid" 2>/dev/null || true; wait "$studio_pid" 2>/dev/null || true; studio_pid=
start "$work/3_after_dialog.session"
save_as "$work/4_reopened.session"
import -window root "$work/5_reopened.png"

python3 - "$work" <<'PY' || { diagnose "$work/3_after_dialog.session"; exit 1; }
import json, sys
work = sys.argv[1]
def load(name):
    s = json.load(open(f"{work}/{name}.session"))
    return s, s["models"][0]["state"]
def points(m):
    return m["state"]["control_points"]
def ropes(s):
    # The studio's ropes (the scenario's own rope is named `rope`).
    return [e for e in s["log"] if e["command"]["action"] == "rope"
            and str(e["command"].get("name", "")).startswith("studio-rope")]
before_s, before = load("0_before")
released_s, released = load("1_released")
later_s, later = load("2_later")
dialog_s, dialog = load("3_after_dialog")
reopened_s, reopened = load("4_reopened")
p0 = points(before)
size = max(max(p[k] for p in p0) - min(p[k] for p in p0) for k in range(3))

# 2. The fix stroke's points (checked when it was saved) are still fixed after the pull.
fixed = [i for i, f in enumerate(load("0_fixed")[1]["rest"]["fixed"]) if f]
assert fixed and all(released["rest"]["fixed"][i] for i in fixed), "the pull freed fixed points"

# 3. Two ropes, mirrored; both sides rose alike.
fixed_s = load("0_fixed")[0]
r = ropes(released_s)[len(ropes(fixed_s)):]
print(f"check_designer: ropes {[e['command'].get('name') for e in r]}")
assert len(r) == 2, f"symmetry X gives two ropes: {len(r)}"
xs = [p[0] for p in p0]
cx = 0.5 * (min(xs) + max(xs))
p1 = points(released)
def rise(side):
    return max(p1[i][2] - p0[i][2] for i in range(len(p0)) if side * (p0[i][0] - cx) > 0.1 * size)
left, right = rise(-1), rise(1)
print(f"check_designer: the pull raised the left by {left:.3f}, the right by {right:.3f} (size {size:.3f})")
assert right > 0.05 * size, "the rope did not pull the top up"
assert abs(left - right) < 0.35 * max(left, right), "the mirrored side did not move alike"

# 4. Sculpt mode keeps the shape after the release.
p2 = points(later)
drift = max(abs(a - b) for p, q in zip(p1, p2) for a, b in zip(p, q))
print(f"check_designer: 2.5 s after the release the shape moved by {drift:.2e}")
assert drift < 1e-3 * size, "the released shape did not stay"
assert "plastic-reset" in [e["command"]["action"] for e in released_s["log"]]

# 5. The dialog's clicks attached nothing.
assert len(ropes(dialog_s)) == len(ropes(later_s)), "a click in the dialog attached a rope"

# 6. Reopened, the same shape.
p3, p4 = points(dialog), points(reopened)
diff = max(abs(a - b) for p, q in zip(p3, p4) for a, b in zip(p, q))
print(f"check_designer: reopened and saved again: control points differ by {diff:.2e}")
assert len(p3) == len(p4) and diff < 1e-9 * size, "the reopened session differs"
PY
echo "check_designer: passed (screenshots in $work)"
