#!/usr/bin/env bash
# ravel sweep / limit / paper as a user runs them: bad input is refused with one clear
# message and nothing written; shards over the CLI complete a sweep; limit writes its json.
set -u
RAVEL=${1:?usage: studies_cli_test.sh path/to/ravel}
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
fails=0
CHEAP=(--set fabric.width_mm=20 --set fabric.length_mm=20 --set projectile.diameter_mm=4
       --set projectile.mass_g=0.5 --set solver.dt_factor=0.3 --set solver.end_time_us=1500)

fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

# expect_refused NAME EXPECTED_TEXT ARGS...: exit code 1 or 2, message on stderr, no --out folder.
expect_refused() {
  local name=$1 text=$2; shift 2
  local out="$WORK/$name"
  "$RAVEL" "$@" --out "$out" >"$WORK/$name.stdout" 2>"$WORK/$name.stderr"
  local rc=$?
  [[ $rc == 1 || $rc == 2 ]] || fail "$name: exit code $rc"
  grep -qF -- "$text" "$WORK/$name.stderr" || fail "$name: stderr lacks '$text': $(cat "$WORK/$name.stderr")"
  [[ $(wc -l <"$WORK/$name.stderr") == 1 ]] || fail "$name: more than one line on stderr"
  [[ -e $out ]] && fail "$name: $out was created"
}

expect_refused unknown_key "--vary projectile.speed: unknown scene key" sweep --vary projectile.speed=1,2
expect_refused bad_range "--vary projectile.velocity_mps: stop < start" sweep --vary projectile.velocity_mps=300:100:10
expect_refused bad_step "step must be > 0" sweep --vary projectile.velocity_mps=100:300:0
expect_refused bad_value "--vary yarn.friction: value 'x'" sweep --vary yarn.friction=0.1,x
expect_refused bad_shard "--shard: expected i/n" sweep --vary yarn.friction=0.1 --shard 4/3
expect_refused bad_jobs "--jobs: expected a whole number" sweep --vary yarn.friction=0.1 --jobs 0
expect_refused no_vary "sweep needs at least one --vary" sweep
expect_refused bad_chart_x "--chart-x yarn.friction: not a --vary key of this sweep (it varies projectile.velocity_mps)" \
  sweep --vary projectile.velocity_mps=80,120 --chart-x yarn.friction
expect_refused bad_set "scene error" sweep --vary yarn.friction=0.1 --set projectile.mass_g=-1
expect_refused bad_tol "--tolerance: expected a positive number" limit --tolerance -1
expect_refused limit_bad_set "projectile.velocity" limit --set projectile.velocity=3
mkdir -p "$WORK/ro" && chmod 555 "$WORK/ro"
if [[ $(id -u) != 0 ]]; then
  expect_refused unwritable "not writable" sweep --vary yarn.friction=0.1 --out "$WORK/ro/x"
fi
touch "$WORK/file"
"$RAVEL" sweep --vary yarn.friction=0.1 --out "$WORK/file" 2>"$WORK/file.err" >/dev/null
[[ $? == 1 ]] && grep -q "not a folder" "$WORK/file.err" || fail "out is a file: $(cat "$WORK/file.err")"

# Two shards into one folder make the whole sweep; the second writes results.csv with all rows.
for i in 1 2; do
  "$RAVEL" sweep "${CHEAP[@]}" --vary projectile.velocity_mps=80,120,160 --vary yarn.friction=0,0.2 \
    --shard $i/2 --jobs 1 --quiet --out "$WORK/sweep" >"$WORK/shard$i.out" 2>&1 || fail "shard $i: $(cat "$WORK/shard$i.out")"
done
rows=$(($(wc -l <"$WORK/sweep/results.csv") - 1))
[[ $rows == 6 ]] || fail "results.csv has $rows rows, expected 6"
head -1 "$WORK/sweep/results.csv" | grep -q '^case,projectile.velocity_mps,yarn.friction,.*perforated.*residual_velocity_mps.*energy_absorbed_J.*wall_time_s' ||
  fail "results.csv header: $(head -1 "$WORK/sweep/results.csv")"
# Rerun: everything is found finished.
"$RAVEL" sweep "${CHEAP[@]}" --vary projectile.velocity_mps=80,120,160 --vary yarn.friction=0,0.2 --quiet \
  --out "$WORK/sweep" >"$WORK/rerun.out" 2>&1
grep -q "0 run, 6 already finished" "$WORK/rerun.out" || fail "rerun: $(cat "$WORK/rerun.out")"
# The charts put the first --vary key on x (one series per friction) ...
head -1 "$WORK/sweep/charts/residual_velocity_mps_vs_projectile.velocity_mps.csv" |
  grep -q '^series,projectile.velocity_mps' || fail "charts: x is not the first --vary key"
grep -c '^yarn.friction = ' "$WORK/sweep/charts/residual_velocity_mps_vs_projectile.velocity_mps.csv" |
  grep -qx 6 || fail "charts: not 2 friction series of 3 points"
# ... and a rerun with --chart-x redraws them over the other key (nothing is run again): one
# series per velocity, two points each.
"$RAVEL" sweep "${CHEAP[@]}" --vary projectile.velocity_mps=80,120,160 --vary yarn.friction=0,0.2 --quiet \
  --chart-x yarn.friction --out "$WORK/sweep" >"$WORK/chartx.out" 2>&1
grep -q "0 run, 6 already finished" "$WORK/chartx.out" || fail "chart-x rerun: $(cat "$WORK/chartx.out")"
cx="$WORK/sweep/charts/residual_velocity_mps_vs_yarn.friction.csv"
[[ -s $cx && -s ${cx%.csv}.png && -s ${cx%.csv}.svg ]] || fail "chart-x: no chart over yarn.friction: $(ls "$WORK/sweep/charts")"
grep -c '^projectile.velocity_mps = ' "$cx" | grep -qx 6 || fail "chart-x: not 3 velocity series of 2 points: $(cat "$cx")"
# --chart-y charts another results.csv column (its unit from its name), again running nothing;
# a column results.csv lacks is refused by name, and the runs are kept.
"$RAVEL" sweep "${CHEAP[@]}" --vary projectile.velocity_mps=80,120,160 --vary yarn.friction=0,0.2 --quiet \
  --chart-y max_strain,friction_work_J --out "$WORK/sweep" >"$WORK/charty.out" 2>&1
grep -q "0 run, 6 already finished" "$WORK/charty.out" || fail "chart-y rerun: $(cat "$WORK/charty.out")"
cy="$WORK/sweep/charts/friction_work_J_vs_projectile.velocity_mps.csv"
[[ -s $cy && -s ${cy%.csv}.png && -s $WORK/sweep/charts/max_strain_vs_projectile.velocity_mps.csv ]] ||
  fail "chart-y: no charts: $(ls "$WORK/sweep/charts")"
grep -q 'friction work (J)' "${cy%.csv}.svg" || fail "chart-y: the axis is not 'friction work (J)'"
/usr/bin/python3 - "$cy" "$WORK/sweep/results.csv" <<'PY' || fail "chart-y: values differ from results.csv"
import csv, sys
chart = list(csv.reader(open(sys.argv[1])))[1:]
rows = list(csv.DictReader(open(sys.argv[2])))
want = {(float(r["projectile.velocity_mps"]), r["yarn.friction"]): float(r["friction_work_J"]) for r in rows}
assert len(chart) == 6, chart
for series, x, y in chart:
    key = (float(x), series.split(" = ")[1])
    assert abs(float(y) - want[key]) <= 1e-9 * max(1.0, abs(want[key])), (series, x, y, want[key])
PY
# (with a fourth velocity: its two new cases run, then the misspelt column is refused)
"$RAVEL" sweep "${CHEAP[@]}" --vary projectile.velocity_mps=80,120,160,200 --vary yarn.friction=0,0.2 --quiet \
  --chart-y "max_strain, friction_wrk_J" --out "$WORK/sweep" >"$WORK/charty_bad.out" 2>"$WORK/charty_bad.err"
rc=$?
[[ $rc == 2 ]] && grep -q -- "--chart-y friction_wrk_J: no such column" "$WORK/charty_bad.err" ||
  fail "chart-y bad column: exit $rc, $(cat "$WORK/charty_bad.err")"
grep -q "2 run, 6 already finished" "$WORK/charty_bad.out" || fail "chart-y bad column: $(cat "$WORK/charty_bad.out")"
[[ $(($(wc -l <"$WORK/sweep/results.csv") - 1)) == 8 ]] || fail "chart-y bad column: the new runs were not kept"

# --repeats: each velocity three times, 1e-6 m/s apart, each a case; perforation.csv counts
# each velocity's perforations from results.csv, and the probability is charted.
expect_refused repeats_no_velocity "--repeats needs --vary projectile.velocity_mps" sweep --vary yarn.friction=0.1 \
  --repeats 3
expect_refused repeats_overlap "lie closer than 2 x 1e-6 m/s" sweep --vary projectile.velocity_mps=80,80.000001 \
  --repeats 2
expect_refused repeats_bad "--repeats: expected a whole number from 1 to 1000" sweep \
  --vary projectile.velocity_mps=80 --repeats x
"$RAVEL" sweep "${CHEAP[@]}" --vary projectile.velocity_mps=45,70 --repeats 3 --quiet --out "$WORK/rep" \
  >"$WORK/rep.out" 2>&1 || fail "repeats: $(cat "$WORK/rep.out")"
[[ -s $WORK/rep/charts/perforation_probability_vs_projectile.velocity_mps.png ]] ||
  fail "repeats: no probability chart: $(ls "$WORK/rep/charts")"
/usr/bin/python3 - "$WORK/rep/results.csv" "$WORK/rep/perforation.csv" <<'PY' || fail "repeats: perforation.csv"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
table = list(csv.DictReader(open(sys.argv[2])))
assert sorted(r["projectile.velocity_mps"] for r in rows) == [
    "45", "45.000001", "45.000002", "70", "70.000001", "70.000002"], rows
assert [t["projectile.velocity_mps"] for t in table] == ["45", "70"], table
for t in table:
    mine = [r for r in rows if r["projectile.velocity_mps"].split(".")[0] == t["projectile.velocity_mps"]]
    assert int(t["runs"]) == 3, t
    decided = [r for r in mine if r["status"] == "completed" and r["end_reason"] != "end_time"]
    assert decided, t
    perf = sum(r["perforated"] == "true" for r in decided)
    assert int(t["perforated"]) == perf, (t, perf)
    assert abs(float(t["perforation_probability"]) - perf / len(decided)) < 1e-6, t
PY
# (a rerun with more repeats runs only the new ones)
"$RAVEL" sweep "${CHEAP[@]}" --vary projectile.velocity_mps=45,70 --repeats 4 --quiet --out "$WORK/rep" \
  >"$WORK/rep4.out" 2>&1 || fail "repeats 4: $(cat "$WORK/rep4.out")"
grep -q "2 run, 6 already finished" "$WORK/rep4.out" || fail "repeats 4: $(cat "$WORK/rep4.out")"
grep -q "^45,4," "$WORK/rep/perforation.csv" || fail "repeats 4: $(cat "$WORK/rep/perforation.csv")"
# (and without --repeats the table goes: it would disagree with results.csv)
"$RAVEL" sweep "${CHEAP[@]}" --vary projectile.velocity_mps=45,70 --quiet --out "$WORK/rep" >/dev/null 2>&1
[[ -e $WORK/rep/perforation.csv || -e $WORK/rep/charts/perforation_probability_vs_projectile.velocity_mps.png ]] &&
  fail "repeats: a rerun without --repeats left perforation.csv or its chart"
expect_refused tolerance_tiny "--tolerance: at least 0.0001 m/s" limit --tolerance 1e-7

# limit on the cheap scene: limit.json with the bracket, the fit and every run. First the
# reference search (its progress lines count the runs still to make) ...
"$RAVEL" limit "${CHEAP[@]}" --start 50 --tolerance 2 --reference --out "$WORK/limit" >"$WORK/limit.out" 2>&1
rc=$?
[[ $rc == 0 ]] || fail "limit exit $rc: $(cat "$WORK/limit.out")"
# Progress: each run is followed by where the search stands, ending with "run N of N".
grep -qE '^    run [0-9]+, bracketing \(' "$WORK/limit.out" || fail "limit: no bracketing progress line"
n=$(/usr/bin/python3 -c 'import json,sys; print(len(json.load(open(sys.argv[1]))["runs"]))' "$WORK/limit/limit.json")
grep -qE "^    run $n of $n, bracket " "$WORK/limit.out" || fail "limit: the last progress line is not run $n of $n: $(tail -3 "$WORK/limit.out")"
for key in ballistic_limit_mps bracket_mps lambert_jonas runs; do
  grep -q "\"$key\"" "$WORK/limit/limit.json" || fail "limit.json lacks $key"
done
for f in residual_velocity.png residual_velocity.svg residual_velocity.csv; do
  [[ -s $WORK/limit/$f ]] || fail "limit: $f missing"
done
# ... and its values: a limit inside its bracket, the bracket within the tolerance, and
# every run on the right side of it (perforated above, stopped below).
/usr/bin/python3 - "$WORK/limit/limit.json" <<'PY' || fail "limit.json values"
import json, sys
j = json.load(open(sys.argv[1]))
bl, (lo, hi) = j["ballistic_limit_mps"], j["bracket_mps"]
assert isinstance(bl, float) and lo <= bl <= hi, (bl, lo, hi)
assert 0 < hi - lo <= 2.0, (lo, hi)
for r in j["runs"]:
    if r["failed"] or not r["decided"]:
        continue
    v = r["velocity_mps"]
    assert (v >= hi) if r["perforated"] else (v <= lo), r
    assert (r["residual_velocity_mps"] > 0) == r["perforated"], r
PY

# ... then the default, fast search (two runs in flight): the same guarantee, its method and
# error estimate stated, moot runs listed as cancelled, and an answer within the tolerance of
# the reference's.
"$RAVEL" limit "${CHEAP[@]}" --start 50 --tolerance 2 --jobs 2 --out "$WORK/limit_fast" >"$WORK/limit_fast.out" 2>&1
rc=$?
[[ $rc == 0 ]] || fail "fast limit exit $rc: $(cat "$WORK/limit_fast.out")"
grep -qE '^    [0-9]+ runs.*bracket ' "$WORK/limit_fast.out" || fail "fast limit: no progress line with the bracket"
/usr/bin/python3 - "$WORK/limit/limit.json" "$WORK/limit_fast/limit.json" <<'PY' || fail "fast limit.json values"
import json, sys
ref, j = (json.load(open(p)) for p in sys.argv[1:3])
assert ref["method"] == "reference" and j["method"] == "fast", (ref["method"], j["method"])
assert j["jobs"] == 2 and j["rules"], j
bl, (lo, hi) = j["ballistic_limit_mps"], j["bracket_mps"]
assert lo <= bl <= hi and 0 < hi - lo <= 2.0, (bl, lo, hi)
assert abs(j["error_mps"] - (hi - lo) / 2) < 1e-9, j["error_mps"]
# The probes below the bracket only ever move the answer down (the limit is the lowest
# velocity that perforates); an answer more than the tolerance below the reference's stands on
# a perforation the bisection did not see, and the stopped runs above it are warned of.
rbl = ref["ballistic_limit_mps"]
assert bl <= rbl + 2.0, (bl, rbl)
warned = [w for w in j["warnings"] if w.startswith("non-monotone")]
assert bl >= rbl - 2.0 or warned, (bl, rbl, j["warnings"])
assert any(r["name"] == "probe_below" for r in j["rules"]), j["rules"]
cancelled = [r for r in j["runs"] if r.get("cancelled")]
decided = [r for r in j["runs"] if r.get("decided_passing")]
assert all(r["perforated"] for r in decided), decided
assert j["runs_decided_passing"] == len(decided), j
assert len(cancelled) == j["runs_cancelled"] and j["skipped_full_runs"] == (len(cancelled) + len(decided) > 0), j
for r in j["runs"]:
    if r.get("cancelled"):
        assert not r["decided"] and r["cancel_reason"] and r["velocity_mps"] not in (lo, hi), r
        continue
    if r["failed"] or not r["decided"]:
        continue
    v = r["velocity_mps"]
    if r["perforated"]:
        assert v >= hi, r
    else:
        assert v <= lo or any(f"{v:.2f} m/s did not perforate" in w for w in warned), r
PY

# --without leaves rules out (and says so in limit.json); an unknown rule is refused by name.
"$RAVEL" limit "${CHEAP[@]}" --start 50 --tolerance 2 --jobs 2 --without residual_guess,cancel_moot \
  --out "$WORK/limit_without" >"$WORK/limit_without.out" 2>&1 || fail "limit --without: $(cat "$WORK/limit_without.out")"
/usr/bin/python3 - "$WORK/limit_without/limit.json" <<'PY' || fail "limit --without: limit.json rules"
import json, sys
j = json.load(open(sys.argv[1]))
names = [r["name"] for r in j["rules"]]
assert "residual_guess" not in names and "cancel_moot" not in names and "ksection" in names, names
assert j["runs_cancelled"] == 0, j["runs_cancelled"]
PY
# A search on a graded mesh says in limit.json that its limit is not the full mesh's; the
# full-mesh searches above say nothing of the kind.
"$RAVEL" limit "${CHEAP[@]}" --set fabric.far_yarns_per_element=2 --set fabric.full_resolution_mm=4 \
  --set fabric.clamp_resolution_mm=2 --start 50 --tolerance 5 --jobs 2 --out "$WORK/limit_graded" \
  >"$WORK/limit_graded.out" 2>&1 || fail "limit on a graded mesh: $(cat "$WORK/limit_graded.out")"
/usr/bin/python3 - "$WORK/limit_graded/limit.json" "$WORK/limit_without/limit.json" <<'PY' || fail "limit: graded-mesh warning"
import json, sys
g = json.load(open(sys.argv[1]))["warnings"]
f = json.load(open(sys.argv[2]))["warnings"]
assert any("fabric.far_yarns_per_element = 2" in w and "full mesh" in w for w in g), g
assert not any("mesh is graded" in w or "mesh is lumped" in w for w in f), f
PY
out=$("$RAVEL" limit "${CHEAP[@]}" --without guess --out "$WORK/limit_bad" 2>&1)
[[ $? == 2 ]] && grep -q "unknown rule 'guess'" <<<"$out" || fail "limit --without guess: $out"

# tradeoff --searches: the reference search, the fast one and the fast one without a rule,
# one after another; searches.csv, tradeoff.json and the chart; a rerun keeps them. The
# reference row is `ravel limit --reference` at the same settings (the same runs: the
# reference search is deterministic and the solver's threads do not change a result).
"$RAVEL" limit "${CHEAP[@]}" --tolerance 2 --reference --no-fit --out "$WORK/limit_ref100" >/dev/null 2>&1 ||
  fail "limit --reference (start 100) failed"
"$RAVEL" tradeoff "${CHEAP[@]}" --only searches --searches decide_passing --tolerance 2 --jobs 2 \
  --out "$WORK/to_search" >"$WORK/to_search.out" 2>&1 || fail "tradeoff --searches: $(cat "$WORK/to_search.out")"
for f in searches.csv tradeoff.json tradeoff.md tradeoff_searches.png tradeoff_searches.svg tradeoff_searches.csv \
  search/reference/limit.json search/fast/limit.json search/decide_passing/limit.json; do
  [[ -s $WORK/to_search/$f ]] || fail "tradeoff --searches: $f missing"
done
/usr/bin/python3 - "$WORK/to_search" "$WORK/limit_ref100/limit.json" <<'PY' || fail "tradeoff --searches values"
import csv, json, sys
d, ref_path = sys.argv[1], sys.argv[2]
rows = list(csv.DictReader(open(d + "/searches.csv")))
assert [r["search"] for r in rows] == ["reference", "fast", "without decide_passing"], rows
ref = json.load(open(ref_path))
r0 = rows[0]
assert abs(float(r0["ballistic_limit_mps"]) - ref["ballistic_limit_mps"]) < 1e-3, (r0, ref["ballistic_limit_mps"])
assert float(r0["diff_from_reference_mps"]) == 0 and float(r0["time_vs_reference"]) == 1
for r in rows:
    assert r["status"] == "converged", r
    lo, hi = float(r["bracket_lo_mps"]), float(r["bracket_hi_mps"])
    assert hi - lo <= 2 + 1e-9 and lo <= float(r["ballistic_limit_mps"]) <= hi, r
    assert abs(float(r["diff_from_reference_mps"]) - (float(r["ballistic_limit_mps"]) - float(r0["ballistic_limit_mps"]))) < 2e-3, r
# Passing decided only where the rule is on; the rule's saving is the two searches' difference.
assert int(rows[0]["runs_decided_passing"]) == 0 and int(rows[2]["runs_decided_passing"]) == 0, rows
assert abs(float(rows[2]["rule_saves_s"]) - (float(rows[2]["wall_time_s"]) - float(rows[1]["wall_time_s"]))) < 0.11, rows
j = json.load(open(d + "/tradeoff.json"))
assert [q["search"] for q in j["searches"]] == [r["search"] for r in rows], j["searches"]
assert j["searches"][2]["rule_left_out"] == "decide_passing"
fast = json.load(open(d + "/search/fast/limit.json"))
assert fast["method"] == "fast" and "decide_passing" in [q["name"] for q in fast["rules"]], fast["method"]
without = json.load(open(d + "/search/decide_passing/limit.json"))
assert "decide_passing" not in [q["name"] for q in without["rules"]]
PY
grep -q "## Ballistic-limit searches" "$WORK/to_search/tradeoff.md" || fail "tradeoff.md lacks the searches section"
grep -q "## Verdict" "$WORK/to_search/tradeoff.md" && fail "tradeoff.md: a verdict with no knob rows"
out=$("$RAVEL" tradeoff "${CHEAP[@]}" --only searches --searches decide_passing --tolerance 2 --jobs 2 \
  --out "$WORK/to_search" 2>&1) || fail "tradeoff --searches rerun: $out"
[[ $(grep -c "kept from an earlier run" <<<"$out") == 3 ]] || fail "tradeoff --searches rerun searched again: $out"
expect_refused to_bad_rule "--searches: unknown rule 'guess'" tradeoff --searches guess
expect_refused to_only_searches "--only searches: needs --searches" tradeoff --only searches

if [[ $fails == 0 ]]; then echo "studies CLI: all passed"; else echo "studies CLI: $fails failed"; exit 1; fi
