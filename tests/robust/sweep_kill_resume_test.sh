#!/usr/bin/env bash
# A sweep killed at any moment resumes without redoing finished cases or keeping
# half-written ones (issue 8). kill -9 (no chance to clean up) at random points, several
# times, then resume to the end: results.csv must equal an uninterrupted run's (timing
# columns aside), every case folder must be whole, cases finished before the last kill
# must not have been run again, and no temporaries may remain.
#   sweep_kill_resume_test.sh path/to/ravel [kills] [seed]
set -u
ravel="$1"
kills="${2:-6}"
RANDOM="${3:-8}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0
bad() { echo "FAIL: $*"; fails=$((fails + 1)); }

# 24 tiny cases, 2 at a time: each a fraction of a second, so kills land mid-case.
args=(sweep --set fabric.width_mm=16 --set fabric.length_mm=16 --set projectile.diameter_mm=3
      --set projectile.mass_g=0.5 --set solver.end_time_us=40 --set solver.threads=1
      --vary projectile.velocity_mps=150:380:10 --jobs 2 --quiet)

# results.csv without the columns that time the run.
strip_timing() {
  python3 - "$1" <<'PY'
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))
drop = {i for i, h in enumerate(rows[0]) if h in ("wall_time_s", "node_steps_per_s")}
for r in rows:
    print(",".join(c for i, c in enumerate(r) if i not in drop))
PY
}

# Every visible case folder is whole: all four files, summary.json last.
check_whole() {
  local d n=0
  for d in "$1"/*/; do
    [ -d "$d" ] || continue
    [ "$(basename "$d")" = charts ] && continue
    n=$((n + 1))
    for f in case.json scene.toml history.csv summary.json; do
      [ -s "$d$f" ] || bad "$2: $d has no $f (half-written case visible)"
    done
  done
  echo "$n"
}

t0=$(date +%s.%N)
"$ravel" "${args[@]}" --out "$tmp/ref" >/dev/null 2>&1 || bad "reference sweep failed"
t1=$(date +%s.%N)
ref_s=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", b - a }')
[ -s "$tmp/ref/results.csv" ] || { bad "reference results.csv missing"; exit 1; }
ncases=$(($(wc -l <"$tmp/ref/results.csv") - 1))
[ "$ncases" -eq 24 ] || bad "reference has $ncases cases, expected 24"

# Kill at random moments.
mid=0
for k in $(seq 1 "$kills"); do
  "$ravel" "${args[@]}" --out "$tmp/run" >/dev/null 2>&1 &
  pid=$!
  # The clock starts when the sweep has its output folder, not at the launch: on a loaded
  # machine (CI's parallel tests) starting the process alone can take longer than the
  # delays below, and every kill then landed before the first case.
  for _ in $(seq 1 1000); do [ -d "$tmp/run" ] && break; kill -0 "$pid" 2>/dev/null || break; sleep 0.01; done
  # A few cases' worth of time: the kills spread over the whole sweep.
  delay=$(awk -v r=$RANDOM -v t="$ref_s" -v n="$ncases" 'BEGIN { printf "%.3f", 0.03 + (r / 32767) * 5 * t / n }')
  sleep "$delay"
  kill -9 "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null
  n=$(check_whole "$tmp/run" "after kill $k")
  t=$(ls -A "$tmp/run" | grep -c '^\.tmp-')
  mid=$((mid + (t > 0 ? 1 : 0)))
  echo "kill $k after ${delay}s: $n cases finished, $t half-written (hidden)"
done
# At least one kill must have caught cases half-written, or this tested nothing.
[ "$mid" -gt 0 ] || bad "no kill landed in the middle of a case"

# Cases finished before the final resume must not be run again.
declare -A before=()
for d in "$tmp"/run/*/; do
  [ -f "$d/summary.json" ] && before["$d"]=$(stat -c %Y.%i "$d/summary.json")
done
"$ravel" "${args[@]}" --out "$tmp/run" >/dev/null 2>&1 || bad "resumed sweep failed"
for d in "${!before[@]}"; do
  [ "$(stat -c %Y.%i "$d/summary.json")" = "${before[$d]}" ] || bad "$d was run again on resume"
done
echo "resume: ${#before[@]} of $ncases cases were already finished"
check_whole "$tmp/run" "after resume" >/dev/null
ls -A "$tmp/run" | grep -q '^\.tmp-' && bad "temporary case folders left after the resume: $(ls -A "$tmp/run" | grep '^\.tmp-')"
if ! diff <(strip_timing "$tmp/ref/results.csv") <(strip_timing "$tmp/run/results.csv") >"$tmp/diff"; then
  bad "results.csv differs from the uninterrupted run:"
  head -20 "$tmp/diff"
fi
echo "sweep kill/resume: $kills kills, reference ${ref_s}s, $fails failures"
[ "$fails" -eq 0 ]
