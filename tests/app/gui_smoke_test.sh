#!/usr/bin/env bash
# GUI smoke test: the real app under a virtual X server (xvfb-run), driven for a few
# hundred frames the way a user would: play, change the yarn friction, restart with it,
# reset, play again, export the scene, screenshot. Passes when the app exits 0, the run
# was rebuilt twice with mu = 0.4, the exported scene says so, and the screenshot is the
# whole window with UI text and the colour-mapped fabric in the 3D view.
#
# usage: gui_smoke_test.sh RAVEL OUT_DIR [PYTHON3]
set -euo pipefail
ravel=$1
out=$2
python=${3:-python3}
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$out"
mkdir -p "$out"

xvfb-run -a -s "-screen 0 1600x1000x24" "$ravel" gui --frames 240 --pause-at-us 12 \
  --do 1:play --do 40:set:yarn.friction=0.4 --do 41:restart --do 90:reset --do 91:play \
  --do 230:export-scene --export-dir "$out" --screenshot "$out/app.png" >"$out/log.txt" 2>&1 || {
  echo "FAIL: ravel gui exited with $?"
  cat "$out/log.txt"
  exit 1
}
cat "$out/log.txt"
# run 1 -> restart (run 2, mu 0.4) -> reset (run 3, same scene)
grep -q "run 3 " "$out/log.txt" || { echo "FAIL: expected run 3 after a restart and a reset"; exit 1; }
grep -q "mu 0.40" "$out/log.txt" || { echo "FAIL: the friction edit did not reach the run"; exit 1; }
grep -Eq "^friction = 0\.4\b" "$out/twaron_ct716.toml" || {
  echo "FAIL: the exported scene does not carry friction = 0.4"
  cat "$out/twaron_ct716.toml"
  exit 1
}
# Without --size the window takes 1600 x 1000 or 90 % of a smaller screen: 1440 x 900 here.
"$python" "$here/check_screenshot.py" "$out/app.png" 1440 900

# Without a display the app says so in one line and exits 2.
set +e
msg=$(env -u DISPLAY -u WAYLAND_DISPLAY "$ravel" gui 2>&1 >/dev/null)
rc=$?
set -e
[ "$rc" -eq 2 ] || { echo "FAIL: no display: exit $rc, expected 2"; exit 1; }
[ "$(printf '%s\n' "$msg" | wc -l)" -eq 1 ] || { echo "FAIL: no display: expected one line, got: $msg"; exit 1; }
printf '%s\n' "$msg" | grep -q "ravel run" || { echo "FAIL: the no-display message does not point to ravel run"; exit 1; }
echo "gui smoke test ok"
