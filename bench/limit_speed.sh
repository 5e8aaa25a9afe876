#!/usr/bin/env bash
# The ballistic limit, fast against reference (issue 36): for each case, `ravel limit` as a
# user runs it (the fast search, no flags but the case's --set) timed as a whole process
# into a fresh folder, and `ravel limit --reference` (full mesh, plain bisection, every run
# to its end) at the same settings. The reference keeps its runs in CACHE/ (a rerun of this
# benchmark reuses them: the reference costs its quarter of an hour once per physics change;
# its runs carry the scene's fingerprint, so a changed scene or code that changes the scene
# runs them again). Prints CSV on stdout.
#
# usage: bench/limit_speed.sh [--cache DIR] [--build DIR] [CASE ...]
#   CASE is name:key=value,key=value (default cases: mu0.2, mu0, mu0.1, mu1.0, pin)
#   e.g. bench/limit_speed.sh mu0.2:yarn.friction=0.2
#   RAVEL_LIMIT_SPEED_SCENE=path.toml runs the cases on another scene (default: the default scene)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=$root/build
cache=${XDG_CACHE_HOME:-$HOME/.cache}/ravel/limit_speed
cases=()
while [ $# -gt 0 ]; do
  case "$1" in
    --cache) cache=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    -h|--help) sed -n 2,14p "$0"; exit 0 ;;
    *) cases+=("$1"); shift ;;
  esac
done
[ ${#cases[@]} -gt 0 ] || cases=(mu0.2:yarn.friction=0.2 mu0:yarn.friction=0 mu0.1:yarn.friction=0.1
  mu1.0:yarn.friction=1.0 pin:solver.model=pin_jointed)
ravel=$build/app/ravel
[ -x "$ravel" ] || { echo "limit_speed: no $ravel: build first (scripts/setup)" >&2; exit 2; }
mkdir -p "$cache"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scene=(${RAVEL_LIMIT_SPEED_SCENE:+"$RAVEL_LIMIT_SPEED_SCENE"})
field() {  # field FILE KEY: a number from limit.json (empty when null)
  python3 -c 'import json,sys; v=json.load(open(sys.argv[1])).get(sys.argv[2]); print("" if v is None else v)' "$1" "$2"
}
echo "scene,case,friction,model,wall_s,runs,runs_cancelled,jobs,bl_mps,error_mps,reference_bl_mps,reference_runs,reference_wall_s,diff_mps,within,lowest_perforation_mps,perforations_below_reference,stops_above_fast"
for c in "${cases[@]}"; do
  name=${c%%:*}
  sets=()
  IFS=',' read -ra kv <<<"${c#*:}"
  for s in "${kv[@]}"; do [ -n "$s" ] && sets+=(--set "$s"); done
  echo "limit_speed: $name: fast search" >&2
  t0=$(date +%s.%N)
  "$ravel" limit "${scene[@]}" "${sets[@]}" --out "$work/$name" --quiet >/dev/null || true
  t1=$(date +%s.%N)
  echo "limit_speed: $name: reference (kept runs in $cache/$name)" >&2
  "$ravel" limit "${scene[@]}" "${sets[@]}" --reference --out "$cache/$name" --quiet >/dev/null || true
  mu=$(grep -o 'yarn.friction=[^,]*' <<<"$c" | cut -d= -f2 || true)
  model=$(grep -o 'solver.model=[^,]*' <<<"$c" | cut -d= -f2 || true)
  python3 - "$work/$name/limit.json" "$cache/$name/limit.json" "$(basename "${RAVEL_LIMIT_SPEED_SCENE:-default}")" \
    "$name" "${mu:-scene}" "${model:-sliding}" "$t0" "$t1" <<'EOF'
import json, sys
f, r, scene, name, mu, model, t0, t1 = sys.argv[1:9]
wall = float(t1) - float(t0)
a, b = json.load(open(f)), json.load(open(r))
full = lambda j: sum(not q.get("cancelled", False) for q in j["runs"])
bl, rbl = a.get("ballistic_limit_mps"), b.get("ballistic_limit_mps")
err = a.get("error_mps")
diff = "" if bl is None or rbl is None else f"{bl - rbl:.3f}"
# Issue 36: within 1 m/s (or 2 %) of the reference.
within = "" if not diff else str(abs(bl - rbl) <= max(1.0, 0.02 * rbl)).lower()
# The reference's cost: its runs one after another (kept runs count with the time they took).
ref_wall = sum(q.get("wall_time_s", 0) for q in b["runs"])
num = lambda v: "" if v is None else f"{v:.3f}"
# Where perforation is not a threshold in velocity (MODEL.md §9, non-monotone bands) the two
# searches can bracket different alternations: the runs of both, taken together, say which.
# lowest_perforation_mps: the lowest velocity either search saw perforate (the limit by its
# definition, SPEC §8, as far as these runs show); perforations_below_reference: runs of either
# search that perforated below the reference's bracket; stops_above_fast: runs that stopped
# above the fast search's bracket.
done = [q for q in a["runs"] + b["runs"] if not q.get("cancelled", False) and q.get("decided", True)]
perf = [q["velocity_mps"] for q in done if q.get("perforated")]
lowest = min(perf) if perf else None
rb, fb = b.get("bracket_mps") or [None, None], a.get("bracket_mps") or [None, None]
below = sum(1 for q in done if q.get("perforated") and rb[0] is not None and q["velocity_mps"] < rb[0])
above = sum(1 for q in done if not q.get("perforated") and fb[1] is not None and q["velocity_mps"] > fb[1])
print(",".join(map(str, [scene, name, mu, model, f"{float(wall):.1f}", full(a), a.get("runs_cancelled", 0),
                         a.get("jobs", 1), num(bl), num(err), num(rbl), full(b), f"{ref_wall:.1f}", diff, within,
                         num(lowest), below, above])))
EOF
done
