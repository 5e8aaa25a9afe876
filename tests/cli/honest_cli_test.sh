#!/usr/bin/env bash
# No silently wrong answer, no lost work, a command line that teaches itself (issue 19):
# each case a user hit, reproduced through the command line.
#   honest_cli_test.sh path/to/ravel
set -u
ravel="$1"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0
pass=0
small=(--set fabric.width_mm=24 --set fabric.length_mm=24 --set projectile.diameter_mm=4 --set projectile.mass_g=1 --quiet)

ok() { pass=$((pass + 1)); }
bad() { echo "FAIL: $*"; fails=$((fails + 1)); }
json() { sed -n "s/^  \"$2\": \(.*\)$/\1/p" "$1" | sed 's/,$//'; }
expect_exit() {  # expect_exit CODE NEEDLE -- command...
  local code="$1" needle="$2"; shift 3
  local out rc
  out=$("$@" 2>&1); rc=$?
  if [ "$rc" -ne "$code" ]; then bad "'$*' exited $rc, expected $code: $out"; return; fi
  if ! grep -qF -- "$needle" <<<"$out"; then bad "'$*' said '$out', expected '$needle'"; return; fi
  ok
}

# --- SCENE that is not a scene: refused, nothing run.
mkdir -p "$tmp/emptydir"
: >"$tmp/empty.toml"
printf '# only a comment\n\n' >"$tmp/comment.toml"
expect_exit 2 "is a folder without a scene.toml" -- "$ravel" run "$tmp/emptydir" --out "$tmp/o1"
expect_exit 2 "holds no scene keys" -- "$ravel" run "$tmp/empty.toml" --out "$tmp/o2"
expect_exit 2 "holds no scene keys" -- "$ravel" run "$tmp/comment.toml" --out "$tmp/o3"
expect_exit 2 "/dev/null: holds no scene keys" -- "$ravel" run /dev/null --out "$tmp/o4"
[ ! -e "$tmp/o1" ] && [ ! -e "$tmp/o2" ] && ok || bad "a refused scene created its output folder"
# ... a run's output folder stands for the scene it ran (and says so).
"$ravel" run "${small[@]}" --set projectile.velocity_mps=321 --set solver.end_time_us=2 --out "$tmp/first" >/dev/null 2>&1
expect_exit 0 "is a folder: using the scene it holds" -- "$ravel" run "$tmp/first" --set solver.end_time_us=2 --out "$tmp/again"
[ "$(json "$tmp/again/summary.json" impact_velocity_mps)" = "321.0" ] && ok ||
  bad "the folder's scene was not run: impact velocity $(json "$tmp/again/summary.json" impact_velocity_mps)"

# --- Options: a repeated single-valued option and an unknown one are errors, for every command.
expect_exit 2 "--out given twice ('$tmp/a' and '$tmp/b')" -- "$ravel" run --out "$tmp/a" --out "$tmp/b"
expect_exit 2 "--threads given twice" -- "$ravel" run --threads 1 --threads 2 --out "$tmp/a"
expect_exit 2 "unknown option --out for ravel keys" -- "$ravel" keys --out "$tmp/k"
expect_exit 2 "unknown option --vary for ravel limit" -- "$ravel" limit --vary x=1 --out "$tmp/l"
[ ! -e "$tmp/a" ] && ok || bad "a refused command created its output folder"

# --- Help that teaches: every command's help lists its options, the same ones it accepts.
for cmd in run snapshot sweep limit paper demo tradeoff stability gui; do
  h=$("$ravel" help "$cmd" 2>&1) && ok || bad "ravel help $cmd exited non-zero"
  h2=$("$ravel" "$cmd" --help 2>&1) && ok || bad "ravel $cmd --help exited non-zero"
  [ "$h" = "$h2" ] && ok || bad "ravel help $cmd and ravel $cmd --help differ"
  # Each listed option is accepted: parsing stops at a later, real error, not at "unknown option".
  [ "$cmd" = gui ] && continue  # would open a window
  for opt in $(grep -oE '^  --[a-z-]+' <<<"$h" | sed 's/^  --//'); do
    [ "$opt" = help ] && continue
    out=$("$ravel" "$cmd" "--$opt" 2>&1)
    grep -q "unknown option --$opt" <<<"$out" && bad "ravel $cmd lists --$opt but refuses it"
  done
done
grep -q -- "--tolerance MPS .*default 1 m/s" <<<"$("$ravel" help limit)" && ok || bad "help limit lacks --tolerance's default"
expect_exit 2 "no command 'fly'" -- "$ravel" help fly
v=$("$ravel" --version) && ok || bad "--version exited non-zero"
grep -qE '^ravel [0-9]+\.[0-9]+\.[0-9]+ \(source [0-9a-f]{7,}' <<<"$v" && ok || bad "--version said '$v'"
# keys: default and allowed range of each key.
k=$("$ravel" keys)
grep -qE '^yarn\.friction +0\.2 +\[0, 10\] ' <<<"$k" && ok || bad "keys: yarn.friction's default/range: $(grep '^yarn.friction' <<<"$k")"
grep -qE '^solver\.model +"sliding" +sliding \| pin_jointed ' <<<"$k" && ok || bad "keys: solver.model: $(grep '^solver.model' <<<"$k")"
grep -qE '^solver\.end_time_us +us +auto +.*or auto' <<<"$k" && ok || bad "keys: solver.end_time_us: $(grep '^solver.end_time_us' <<<"$k")"

# --- A diverged run has no outcome: its results are null, not the impact energy.
env RAVEL_TEST_FAULT=nan@20 "$ravel" run "${small[@]}" --out "$tmp/nan" >/dev/null 2>&1
for key in perforated residual_velocity_mps energy_absorbed_J perforation_time_s friction_work_J; do
  [ "$(json "$tmp/nan/summary.json" "$key")" = null ] && ok || bad "diverged run: $key = $(json "$tmp/nan/summary.json" "$key")"
done

# --- Counts on one basis: the whole fabric, and the modelled part beside it.
"$ravel" run "${small[@]}" --set solver.end_time_us=1 --out "$tmp/quarter" >/dev/null 2>&1
"$ravel" run "${small[@]}" --set solver.end_time_us=1 --set solver.symmetry=full --out "$tmp/full" >/dev/null 2>&1
for key in node_count element_count crossing_count; do
  q=$(json "$tmp/quarter/summary.json" "$key"); f=$(json "$tmp/full/summary.json" "$key")
  [ -n "$q" ] && [ "$q" = "$f" ] && ok || bad "$key: quarter $q, full $f"
  mq=$(json "$tmp/quarter/summary.json" "modelled_$key"); mf=$(json "$tmp/full/summary.json" "modelled_$key")
  [ "$mf" = "$f" ] && [ "$((mq * 3))" -lt "$mf" ] && ok || bad "modelled_$key: quarter $mq, full $mf"
done

# --- A reused --out: the earlier run's frames go, other files stay.
"$ravel" run "${small[@]}" --set solver.end_time_us=20 --frames every=20 --vtk --out "$tmp/re" >/dev/null 2>&1
n1=$(ls "$tmp/re/vtk" | grep -c 'frame_.*\.vtu')
touch "$tmp/re/notes.txt"
"$ravel" run "${small[@]}" --set solver.end_time_us=4 --frames every=20 --vtk --out "$tmp/re" >/dev/null 2>&1
n2=$(ls "$tmp/re/vtk" | grep -c 'frame_.*\.vtu')
n2png=$(ls "$tmp/re/frames" | grep -c 'frame_.*\.png')
pvd=$(grep -c '<DataSet' "$tmp/re/vtk/frame.pvd")
[ "$n2" -lt "$n1" ] && [ "$n2" -eq "$pvd" ] && [ "$n2png" -eq "$n2" ] && ok ||
  bad "reused --out: $n1 then $n2 VTU files, $n2png PNGs, $pvd in the PVD"
[ -e "$tmp/re/notes.txt" ] && ok || bad "reused --out removed a file the run did not write"
line=$("$ravel" run --set fabric.width_mm=24 --set fabric.length_mm=24 --set projectile.diameter_mm=4 --set projectile.mass_g=1 \
  --set solver.end_time_us=4 --frames every=20 --vtk --out "$tmp/re2" 2>/dev/null | grep 'results in')
grep -qF "summary.json, history.csv, scene.toml, frames/ (" <<<"$line" && grep -qF "vtk/frame.pvd" <<<"$line" && ok ||
  bad "the summary line does not name every output: $line"

# --- A scene name never leaves --out.
mkdir -p "$tmp/jail"
"$ravel" run "${small[@]}" --set "name=../../evil" --set solver.end_time_us=1 --out "$tmp/jail/run" >/dev/null 2>&1 && ok ||
  bad "a name with / failed the run"
if "$ravel" help snapshot >/dev/null 2>&1 && "$ravel" snapshot "${small[@]}" --set "name=../../evil" --at 1 --out "$tmp/jail/snap" >/dev/null 2>&1; then
  [ -z "$(find "$tmp" -maxdepth 2 -name '*evil*' -not -path "$tmp/jail/*")" ] && ok || bad "a snapshot left --out"
  [ "$(ls "$tmp/jail/snap" | grep -c '\.png$')" -eq 1 ] && ok || bad "snapshot: $(ls "$tmp/jail/snap")"
  # Other overrides do not overwrite it.
  "$ravel" snapshot "${small[@]}" --set "name=../../evil" --set yarn.friction=0.5 --at 1 --out "$tmp/jail/snap" >/dev/null 2>&1
  [ "$(ls "$tmp/jail/snap" | grep -c '\.png$')" -eq 2 ] && ok || bad "snapshots of two overrides share a name: $(ls "$tmp/jail/snap")"
fi

# --- Too big for memory: refused before anything is allocated, naming the keys that made it so.
expect_exit 2 "fabric.width_mm: the fabric (fabric.width_mm = 3300, fabric.length_mm = 3300 at fabric.spacing_mm = 0.844) needs about" \
  -- "$ravel" run --set fabric.width_mm=3300 --set fabric.length_mm=3300 --set solver.symmetry=full --out "$tmp/huge"
expect_exit 2 "--set: fabric.width_mm: more than 4000 yarns per direction" -- \
  "$ravel" run --set fabric.width_mm=10000 --set fabric.length_mm=10000 --out "$tmp/huge"
[ ! -e "$tmp/huge" ] && ok || bad "a refused big scene created its output folder"

# --- A suggestion only for the scene it was measured on.
out=$("$ravel" run "${small[@]/--quiet/}" --set solver.end_time_us=2 --out "$tmp/patch" 2>&1)
grep -q "suggestion:" <<<"$out" && bad "a 24 mm patch got the default scene's tradeoff suggestion" || ok

# --- A resumed sweep never mixes physics: edit the scene file between two calls.
printf 'name = "pt"\n[fabric]\nwidth_mm = 24\nlength_mm = 24\n[projectile]\ndiameter_mm = 4\nmass_g = 1\n[solver]\nend_time_us = 2\n[yarn]\nfriction = 0.2\n' >"$tmp/pt.toml"
"$ravel" sweep "$tmp/pt.toml" --vary projectile.velocity_mps=100,200 --out "$tmp/sw" --quiet >/dev/null 2>&1
sed -i 's/friction = 0.2/friction = 0.9/' "$tmp/pt.toml"
expect_exit 2 "holds finished cases of a different sweep (the scene file's content changed since (yarn.friction))" -- \
  "$ravel" sweep "$tmp/pt.toml" --vary projectile.velocity_mps=100,200 --out "$tmp/sw" --quiet
expect_exit 0 "2 run, 0 already finished" -- "$ravel" sweep "$tmp/pt.toml" --vary projectile.velocity_mps=100,200 --out "$tmp/sw" --restart
[ "$(grep -c ',0.9,' "$tmp/sw/results.csv")" -eq 2 ] && ok || bad "--restart: results.csv does not hold the mu = 0.9 cases only"

# --- Ctrl-C on ravel limit keeps the finished runs, and the same command resumes from them.
# At the default time step the 4 mm sphere at 37.4 m/s on this 24 mm patch ends 0.5-1.6 % off
# balance after its wefts break (it lost 2.8 % and was stopped as diverged before the bending
# springs of broken elements were booked as released, docs/MODEL.md §2): which velocities the
# search visits depends on which of its two runs in flight ends first, so the step is halved
# here to keep this test about interrupting, far from the ledger's 5 % limit.
sed -i 's/end_time_us = 2/end_time_us = "auto"\ndt_factor = 0.25/' "$tmp/pt.toml"
"$ravel" limit "$tmp/pt.toml" --out "$tmp/lim" >"$tmp/lim1.log" 2>&1 &
pid=$!
for _ in $(seq 1 100); do [ "$(ls "$tmp/lim/runs" 2>/dev/null | wc -l)" -ge 2 ] && break; sleep 0.1; done
kill -INT $pid
wait $pid
rc=$?
[ $rc -eq 130 ] && ok || bad "interrupted limit: exit $rc"
grep -q '"interrupted": true' "$tmp/lim/limit.json" && ok || bad "interrupted limit: no limit.json with interrupted"
kept=$(ls "$tmp/lim/runs" | wc -l)
# limit.json lists the finished runs and, apart, the runs the interruption stopped (cancelled).
listed=$(/usr/bin/python3 -c 'import json,sys; print(sum(not r.get("cancelled", False) for r in json.load(open(sys.argv[1]))["runs"]))' "$tmp/lim/limit.json")
[ "$kept" -ge 2 ] && [ "$listed" -eq "$kept" ] && ok || bad "interrupted limit: $kept runs kept, $listed in limit.json"
out=$("$ravel" limit "$tmp/pt.toml" --out "$tmp/lim" 2>&1)
[ "$(grep -c 'kept from an earlier run' <<<"$out")" -eq "$kept" ] && ok || bad "resumed limit did not reuse the $kept kept runs: $out"
grep -q '"interrupted": false' "$tmp/lim/limit.json" && grep -q '"converged": true' "$tmp/lim/limit.json" && ok ||
  bad "resumed limit did not finish"

# --- Ctrl-C on ravel stability keeps the finished cells; the same command resumes from them.
st=("$tmp/pt.toml" --quick --set fabric.width_mm=48 --set fabric.length_mm=48 --map dt_factor --jobs 1)
"$ravel" stability "${st[@]}" --out "$tmp/stab" >"$tmp/stab1.log" 2>&1 &
pid=$!
for _ in $(seq 1 300); do [ "$(ls "$tmp"/stab/dt_factor/*/summary.json 2>/dev/null | wc -l)" -ge 2 ] && break; sleep 0.05; done
kill -INT $pid
wait $pid
rc=$?
[ $rc -eq 130 ] && ok || bad "interrupted stability: exit $rc: $(cat "$tmp/stab1.log")"
kept=$(ls "$tmp"/stab/dt_factor/*/summary.json 2>/dev/null | wc -l)
grep -q "ravel: interrupted; $kept finished runs are kept in $tmp/stab/" "$tmp/stab1.log" && ok ||
  bad "interrupted stability: message does not name the $kept kept runs: $(cat "$tmp/stab1.log")"
[ "$kept" -ge 2 ] && [ "$kept" -lt 12 ] && ok || bad "interrupted stability: $kept of 12 runs finished (the test proves nothing)"
[ -e "$tmp/stab/stability.csv" ] && bad "an interrupted stability wrote stability.csv" || ok
out=$("$ravel" stability "${st[@]}" --out "$tmp/stab" 2>&1)
grep -q "stability: 12 cells in [0-9]* s ($((12 - kept)) run now, $kept kept from an earlier run)" <<<"$out" && ok ||
  bad "resumed stability did not reuse the $kept kept runs: $out"
[ "$(($(wc -l <"$tmp/stab/stability.csv") - 1))" -eq 12 ] && ok || bad "resumed stability: stability.csv lacks cells"

# --- ... and on ravel tradeoff.
to=("$tmp/pt.toml" --quick --set fabric.width_mm=48 --set fabric.length_mm=48 --set solver.end_time_us=40 --jobs 1)
"$ravel" tradeoff "${to[@]}" --out "$tmp/to" >"$tmp/to1.log" 2>&1 &
pid=$!
for _ in $(seq 1 300); do [ "$(ls "$tmp"/to/cases/*/summary.json 2>/dev/null | wc -l)" -ge 2 ] && break; sleep 0.05; done
kill -INT $pid
wait $pid
rc=$?
[ $rc -eq 130 ] && ok || bad "interrupted tradeoff: exit $rc: $(cat "$tmp/to1.log")"
grep -qF "ravel: interrupted; finished runs are kept in $tmp/to/cases/" "$tmp/to1.log" && ok ||
  bad "interrupted tradeoff: no message naming the folder: $(cat "$tmp/to1.log")"
kept=$(ls "$tmp"/to/cases/*/summary.json 2>/dev/null | wc -l)
[ "$kept" -ge 2 ] && ok || bad "interrupted tradeoff: only $kept runs finished"
[ -e "$tmp/to/tradeoff.md" ] && bad "an interrupted tradeoff wrote tradeoff.md" || ok
out=$("$ravel" tradeoff "${to[@]}" --out "$tmp/to" 2>&1)
grep -qE "^tradeoff: [1-9][0-9]* runs \($kept already finished\)" <<<"$out" && ok ||
  bad "resumed tradeoff did not reuse the $kept kept runs: $out"
[ -s "$tmp/to/tradeoff.md" ] && ok || bad "resumed tradeoff: no tradeoff.md"

# --- A sweep says k of N and each case's outcome; a diverged case is not "done".
out=$("$ravel" sweep "${small[@]/--quiet/}" --set solver.end_time_us=20 --vary solver.dt_factor=0.5,2 --jobs 1 --out "$tmp/swd" 2>&1)
grep -qE '^  \[1/2\] solver.dt_factor=0.5: ' <<<"$out" && ok || bad "sweep progress line: $out"
grep -qE '^  \[2/2\] solver.dt_factor=2: DIVERGED: ' <<<"$out" && ok || bad "a diverged case is not reported as such: $out"
grep -q "done:" <<<"$out" && bad "sweep still prints done: $out" || ok

echo "honest cli: $pass passed, $fails failed"
[ "$fails" -eq 0 ]
