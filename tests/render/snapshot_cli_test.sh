#!/usr/bin/env bash
# `ravel snapshot` as a user calls it: two PNGs of the right size, errors for bad input.
set -u
ravel=$1
out=$2
rm -rf "$out"
fail() { echo "FAIL: $*"; exit 1; }

"$ravel" snapshot --at 2,5 --view top --size 320x200 --field velocity --out "$out" --quiet ||
  fail "snapshot exited $?"
n=$(ls "$out"/*.png 2>/dev/null | wc -l)
[ "$n" -eq 2 ] || fail "expected 2 PNGs, found $n"
f="$out/twaron_ct716_top_velocity_t0005.00us.png"  # a field other than strain is named
[ -f "$f" ] || fail "missing $f"
# PNG signature and IHDR width/height (bytes 16..23, big endian).
sig=$(head -c 8 "$f" | od -An -tx1 | tr -d ' \n')
[ "$sig" = "89504e470d0a1a0a" ] || fail "not a PNG: $sig"
wh=$(dd if="$f" bs=1 skip=16 count=8 2>/dev/null | od -An -tu1 | tr -s ' ')
[ "$wh" = " 0 0 1 64 0 0 0 200" ] || fail "PNG size bytes: $wh"
ls "$out" | grep -q '\.tmp\.' && fail "temporary file left behind"

"$ravel" snapshot --at 5 --view sideways --out "$out" 2>/dev/null; rc=$?
[ $rc -eq 2 ] || fail "bad --view should exit 2, got $rc"
"$ravel" snapshot --at -1 --out "$out" 2>/dev/null; rc=$?
[ $rc -eq 2 ] || fail "negative --at should exit 2, got $rc"
"$ravel" snapshot --at 5 --size 10x10 --out "$out" 2>/dev/null; rc=$?
[ $rc -eq 2 ] || fail "tiny --size should exit 2, got $rc"
"$ravel" snapshot --out "$out" 2>/dev/null; rc=$?
[ $rc -eq 2 ] || fail "missing --at should exit 2, got $rc"
# `ravel run --frames final --vtk`: the initial and final states as PNG and VTU.
run_out="$out/run"
"$ravel" run --set solver.end_time_us=2 --frames final --vtk --out "$run_out" --quiet >/dev/null ||
  fail "run --frames exited $?"
[ -f "$run_out/frames/frame_00000.png" ] || fail "run --frames final wrote no PNG"
grep -q 'file="frame_00000.vtu"' "$run_out/vtk/frame.pvd" || fail "run --vtk wrote no series"
"$ravel" run --frames every=0 --out "$run_out" 2>/dev/null; rc=$?
[ $rc -eq 2 ] || fail "--frames every=0 should exit 2, got $rc"
echo "snapshot cli: ok"
