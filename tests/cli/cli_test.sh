#!/usr/bin/env bash
# The command line as a user drives it: outputs, bad input, exit codes, Ctrl-C.
#   cli_test.sh path/to/ravel
set -u
ravel="$1"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0
pass=0
small=(--set fabric.width_mm=24 --set fabric.length_mm=24 --set projectile.diameter_mm=4 --set projectile.mass_g=1)

check() {  # check NAME CONDITION...
  local name="$1"; shift
  if "$@"; then pass=$((pass + 1)); else echo "FAIL: $name"; fails=$((fails + 1)); fi
}
expect_exit() {  # expect_exit CODE NEEDLE -- command...
  local code="$1" needle="$2"; shift 3
  local out rc
  out=$("$@" 2>&1); rc=$?
  if [ "$rc" -ne "$code" ]; then echo "FAIL: '$*' exited $rc, expected $code: $out"; fails=$((fails + 1)); return; fi
  if ! grep -qF -- "$needle" <<<"$out"; then echo "FAIL: '$*' said '$out', expected '$needle'"; fails=$((fails + 1)); return; fi
  pass=$((pass + 1))
}

# A good run writes all three files with the documented keys.
"$ravel" run "${small[@]}" --set projectile.velocity_mps=400 --out "$tmp/ok" >/dev/null 2>&1
check "run exit 0" test $? -eq 0
for f in history.csv summary.json scene.toml; do check "run wrote $f" test -s "$tmp/ok/$f"; done
for k in perforated residual_velocity_mps energy_absorbed_J perforation_time_s energy_balance_error model \
         node_count step_count dt_s wall_time_s status friction_work_J warnings; do
  check "summary has $k" grep -q "\"$k\"" "$tmp/ok/summary.json"
done
# ... and their values: the 400 m/s strike perforates the 24 mm patch (1 g at 400 m/s is
# 80 J; such a patch absorbs a few J), the absorbed energy is M (V0^2 - Vr^2) / 2 as
# documented, and the ledger balances within the method's 1 %.
check "400 m/s perforates" bash -c "/usr/bin/python3 - '$tmp/ok/summary.json' <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
assert s['status'] == 'completed' and s['perforated'] is True, s['status']
vr = s['residual_velocity_mps']
assert 300 < vr < 400, vr
assert abs(s['energy_absorbed_J'] - 0.5e-3 * (400**2 - vr**2)) < 1e-9 * 80, s['energy_absorbed_J']
assert abs(s['energy_balance_error']) < 0.01, s['energy_balance_error']
PY"
check "history starts with t_s" bash -c "head -1 '$tmp/ok/history.csv' | grep -q '^t_s,'"
for c in projectile_velocity_mps friction_work_J broken_warp broken_weft max_strain sliding_crossings stuck_crossings; do
  check "history has $c" bash -c "head -1 '$tmp/ok/history.csv' | grep -q '$c'"
done
check "no temp files left" bash -c "! ls -a '$tmp/ok' | grep -q tmp"
# The written scene reproduces the run.
"$ravel" run "$tmp/ok/scene.toml" --out "$tmp/again" >/dev/null 2>&1
check "scene.toml reruns" cmp -s <(grep -v wall_time "$tmp/ok/summary.json" | grep -v node_steps) \
                                  <(grep -v wall_time "$tmp/again/summary.json" | grep -v node_steps)

# Bad input: one message naming the key and the problem, exit 2, nothing written.
printf '[projectile]\nvelocty_mps = 300\n' > "$tmp/typo.toml"
expect_exit 2 "did you mean 'projectile.velocity_mps'" -- "$ravel" run "$tmp/typo.toml" --out "$tmp/typo"
check "typo wrote nothing" test ! -e "$tmp/typo"
expect_exit 2 "typo.toml:2" -- "$ravel" run "$tmp/typo.toml" --out "$tmp/typo"
expect_exit 2 "projectile.mass_g: must be positive" -- "$ravel" run --set projectile.mass_g=-7 --out "$tmp/neg"
expect_exit 2 "yarn.friction: is NaN" -- "$ravel" run --set yarn.friction=NaN --out "$tmp/nan"
printf '[projectile]\nmass_g = "heavy"\n' > "$tmp/type.toml"
expect_exit 2 "wrong type" -- "$ravel" run "$tmp/type.toml" --out "$tmp/type"
expect_exit 2 "projectile.diameter_mm: the projectile (500 mm) is larger than the fabric (120 x 120 mm)" -- "$ravel" run --set projectile.diameter_mm=500 --out "$tmp/geo"
expect_exit 2 "projectile.offset_y_mm: the projectile does not fit inside the fabric at the strike point" -- "$ravel" run --set projectile.offset_y_mm=-58 --out "$tmp/geo"
expect_exit 2 "cannot open scene file" -- "$ravel" run "$tmp/missing.toml" --out "$tmp/missing"
expect_exit 2 "unknown option --fast" -- "$ravel" run --fast --out "$tmp/x"
expect_exit 2 "run needs --out" -- "$ravel" run
expect_exit 2 "unknown command" -- "$ravel" frobnicate
# Unwritable output folder: exit 1, named.
expect_exit 1 "cannot create the folder" -- "$ravel" run "${small[@]}" --out /proc/ravel_out
touch "$tmp/afile"
expect_exit 1 "exists and is not a folder" -- "$ravel" run "${small[@]}" --out "$tmp/afile"
# A diverging run says so and exits 3.
expect_exit 3 "lower solver.dt_factor" -- "$ravel" run "${small[@]}" --set solver.dt_factor=2 --out "$tmp/div"
check "diverged summary written" grep -q '"status": "diverged"' "$tmp/div/summary.json"
# Ctrl-C: the run stops, writes what it has with status interrupted, exits 130.
"$ravel" run --set solver.end_time_us=5000 --set projectile.velocity_mps=60 --out "$tmp/int" >/dev/null 2>&1 &
pid=$!
sleep 2
kill -INT $pid
wait $pid
rc=$?
check "interrupted exit 130" test $rc -eq 130
check "interrupted summary" grep -q '"status": "interrupted"' "$tmp/int/summary.json"
check "interrupted history" test -s "$tmp/int/history.csv"
# Keys are listed with units.
check "keys lists projectile.velocity_mps" bash -c "'$ravel' keys | grep -q 'projectile.velocity_mps *m/s'"

echo "cli: $pass passed, $fails failed"
[ "$fails" -eq 0 ]
