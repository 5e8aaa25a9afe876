#!/usr/bin/env bash
# Load (issue 8): a 200-case sweep with --jobs 2 on a tiny scene finishes, every case
# completes, and the process's peak memory does not grow with the number of cases (a
# 20-case sweep is the baseline). Prints the timings for docs/robustness.md.
#   sweep_load_test.sh path/to/ravel [cases] [rss_bound yes|no]
# (no under ASan/TSan: their allocators keep freed memory in quarantine on purpose, so
# peak RSS grows with the work done: 257 -> 477 MB measured under ASan.)
set -u
ravel="$1"
cases="${2:-200}"
rss_bound="${3:-yes}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0
bad() { echo "FAIL: $*"; fails=$((fails + 1)); }

base=(sweep --set fabric.width_mm=16 --set fabric.length_mm=16 --set projectile.diameter_mm=3
      --set projectile.mass_g=0.5 --set solver.end_time_us=30 --set solver.threads=1 --jobs 2 --quiet)

# run NAME N -> sets peak_kb and wall_s
run() {
  local stop
  stop=$(awk -v n="$2" 'BEGIN { printf "%.1f", 100 + (n - 1) * 0.5 }')
  /usr/bin/time -f "%M %e" -o "$tmp/$1.time" "$ravel" "${base[@]}" --vary "projectile.velocity_mps=100:$stop:0.5" \
    --out "$tmp/$1" >"$tmp/$1.log" 2>&1 || bad "$1: sweep failed: $(tail -3 "$tmp/$1.log")"
  read -r peak_kb wall_s <"$tmp/$1.time"
  local rows
  rows=$(($(wc -l <"$tmp/$1/results.csv") - 1))
  [ "$rows" -eq "$2" ] || bad "$1: results.csv has $rows rows, expected $2"
  local notdone
  notdone=$(python3 - "$tmp/$1/results.csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print(sum(1 for r in rows if r["status"] != "completed"))
PY
)
  [ "$notdone" -eq 0 ] || bad "$1: $notdone cases did not complete"
}

run small 20
small_kb=$peak_kb
small_s=$wall_s
run load "$cases"
echo "sweep load: 20 cases ${small_s}s peak ${small_kb} kB; $cases cases ${wall_s}s peak ${peak_kb} kB" \
     "($(awk -v n="$cases" -v s="$wall_s" 'BEGIN { printf "%.0f", n / s * 3600 }') cases/hour)"
# Peak memory may not grow with the number of cases: 10x the cases, at most +32 MB.
[ "$rss_bound" = no ] || [ "$peak_kb" -le $((small_kb + 32768)) ] || bad "peak RSS grew from $small_kb kB (20 cases) to $peak_kb kB ($cases cases)"
[ "$fails" -eq 0 ]
