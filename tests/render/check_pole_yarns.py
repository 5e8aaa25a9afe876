#!/usr/bin/env python3
"""bench/pole_yarns.py on a real run: the numbers docs/MODEL.md §9 quotes start right.

usage: check_pole_yarns.py RAVEL POLE_YARNS_PY OUT_DIR

Runs the default scene for 12 us with VTU frames every 66 steps and reads them back:
- at t = 0 the yarns are at rest as built: the zig-zag rise is the crossing gap L1 = 0.2 mm
  (geometry, to rounding), every strain and slip rate is zero;
- at 12 us the weft under the projectile is stretched (its strain under the projectile
  above 0.3 %: a 260 m/s strike has by then pushed the pole 3 mm deep over a 6 mm core),
  its crimp has started to come out (rise below L1) and its nodes are drawn toward the
  strike point (velocity along the yarn negative on the positive half);
- --csv writes the same text as stdout; a folder without frames is refused, non-zero.
"""
import csv
import io
import os
import shutil
import subprocess
import sys

ravel, tool, out = sys.argv[1], sys.argv[2], sys.argv[3]
shutil.rmtree(out, ignore_errors=True)
os.makedirs(out)
run = os.path.join(out, "run")
subprocess.run([ravel, "run", "--vtk", "--frames", "every=66", "--set", "solver.end_time_us=12", "--quiet",
                "--out", run], check=True, stdout=subprocess.DEVNULL)
py = sys.executable
text = subprocess.run([py, tool, run], check=True, capture_output=True, text=True).stdout
rows = list(csv.DictReader(io.StringIO(text)))
fails = []


def check(ok, what):
    if not ok:
        fails.append(what)


check(len(rows) >= 3, f"{len(rows)} frames")
r0, r1 = rows[0], rows[-1]
check(float(r0["t_us"]) == 0.0, f"first frame at {r0['t_us']} us")
for fam in ("weft", "warp"):
    check(abs(float(r0[f"{fam}_rise_mm"]) - 0.2) < 1e-6, f"{fam} rise at rest {r0[f'{fam}_rise_mm']} mm, not L1")
    for k in ("strain_core", "strain_far", "strain_max", "slip_mps"):
        check(abs(float(r0[f"{fam}_{k}"])) < 1e-6, f"{fam}_{k} at rest {r0[f'{fam}_{k}']}")
check(abs(float(r1["t_us"]) - 12.0) < 0.5, f"last frame at {r1['t_us']} us")
check(float(r1["weft_strain_core"]) > 0.3, f"weft core strain {r1['weft_strain_core']} % at 12 us")
check(float(r1["weft_rise_mm"]) < 0.2 - 1e-3, f"weft rise {r1['weft_rise_mm']} mm at 12 us: no crimp out")
check(float(r1["weft_v_along_min"]) < 0.0, f"weft v_along_min {r1['weft_v_along_min']}: not drawn in")

dest = os.path.join(out, "pole.csv")
subprocess.run([py, tool, run, "--csv", dest], check=True)
check(open(dest).read() == text, "--csv differs from stdout")
check(not os.path.exists(dest + ".tmp"), "temporary file left")
empty = os.path.join(out, "empty")
os.makedirs(empty)
bad = subprocess.run([py, tool, empty], capture_output=True, text=True)
check(bad.returncode != 0 and "no VTU frames" in bad.stderr, f"empty folder: rc {bad.returncode}, {bad.stderr!r}")

if fails:
    print("FAIL:\n  " + "\n  ".join(fails))
    sys.exit(1)
print(f"pole_yarns: {len(rows)} frames, weft core {r1['weft_strain_core']} %, rise {r1['weft_rise_mm']} mm at 12 us")
