#!/usr/bin/env python3
"""A real run's VTU series read with meshio, as a ParaView user would use it.

usage: check_run_vtu_meshio.py RAVEL OUT_DIR

Runs a small patch through perforation (quarter model, then the full one) and checks that
the series counts the whole fabric once (cells and points with duplicate = 0 match
summary.json's whole-fabric counts, also for the broken elements), that yarn ids are
unique across the mirrored copies (one id per yarn, one line per id), and that the
projectile's field data matches the run's history.
"""
import csv
import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import meshio  # installed by scripts/setup (python3-meshio); a missing one fails the test
import numpy as np

ravel, out = sys.argv[1], sys.argv[2]
patch = ["--set", "fabric.width_mm=24", "--set", "fabric.length_mm=24", "--set", "projectile.diameter_mm=4",
         "--set", "projectile.mass_g=1", "--set", "projectile.velocity_mps=400", "--quiet"]
fails = []


def check(ok, what):
    if not ok:
        fails.append(what)


def run(name, extra):
    d = os.path.join(out, name)
    subprocess.run([ravel, "run", *patch, *extra, "--vtk", "--frames", "every=40", "--out", d], check=True,
                   stdout=subprocess.DEVNULL)
    s = json.load(open(os.path.join(d, "summary.json")))
    sets = ET.parse(os.path.join(d, "vtk", "frame.pvd")).getroot().findall("./Collection/DataSet")
    first = meshio.read(os.path.join(d, "vtk", sets[0].get("file")))
    last = meshio.read(os.path.join(d, "vtk", sets[-1].get("file")))
    return d, s, sets, first, last


counts = {}
for name, extra in (("quarter", []), ("full", ["--set", "solver.symmetry=full"])):
    d, s, sets, first, last = run(name, extra)
    check(s["model"] == name, f"{name}: model {s['model']}")
    cd = {k: v[0] for k, v in last.cell_data.items()}
    pdup = last.point_data["duplicate"].astype(bool)
    cdup = cd["duplicate"].astype(bool)
    check(int((~pdup).sum()) == s["node_count"], f"{name}: {(~pdup).sum()} points without duplicate, node_count {s['node_count']}")
    check(int((~cdup).sum()) == s["element_count"],
          f"{name}: {(~cdup).sum()} cells without duplicate, element_count {s['element_count']}")
    broken = int(cd["broken"][~cdup].sum())
    check(broken == s["broken_warp_elements"] + s["broken_weft_elements"] and broken > 0,
          f"{name}: {broken} broken cells, summary {s['broken_warp_elements']} + {s['broken_weft_elements']}")
    # Duplicates coincide with a cell of another copy.
    pts = last.points
    lines = last.cells_dict["line"]
    mids = 0.5 * (pts[lines[:, 0]] + pts[lines[:, 1]])
    if cdup.any():
        keep = {tuple(np.round(m, 9)) for m in mids[~cdup]}
        check(all(tuple(np.round(m, 9)) in keep for m in mids[cdup]), f"{name}: a duplicate cell has no original")
    # Unique yarn ids: contiguous, one family and one straight line each at t = 0.
    c0 = {k: v[0] for k, v in first.cell_data.items()}
    ids = c0["yarn_id"][~first.cell_data["duplicate"][0].astype(bool)]
    fam = c0["family"][~first.cell_data["duplicate"][0].astype(bool)]
    m0 = 0.5 * (first.points[first.cells_dict["line"][:, 0]] + first.points[first.cells_dict["line"][:, 1]])
    m0 = m0[~first.cell_data["duplicate"][0].astype(bool)]
    uniq = np.unique(ids)
    check(uniq[0] == 0 and uniq[-1] == len(uniq) - 1, f"{name}: yarn ids not 0..N-1")
    where = []
    for i in uniq:
        sel = ids == i
        f = set(fam[sel].tolist())
        check(len(f) == 1, f"{name}: yarn {i} has cells of both families")
        axis = 0 if f == {0} else 1  # warp runs along y at x = I L0
        check(np.ptp(m0[sel, axis]) < 1e-6, f"{name}: yarn {i} is not one line")
        where.append((min(f), round(float(m0[sel, axis].mean()), 7)))
    check(len(set(where)) == len(where), f"{name}: two yarn ids on one line")
    counts[name] = (len(uniq), s["node_count"], s["element_count"])
    # The projectile: field data against history.csv at the frame's time.
    fd = last.field_data
    t = float(np.ravel(fd["TimeValue"])[0])
    check(abs(t - float(sets[-1].get("timestep"))) < 1e-12, f"{name}: TimeValue {t}")
    check(abs(float(np.ravel(fd["projectile_radius_m"])[0]) - 2e-3) < 1e-9, f"{name}: projectile radius")
    rows = list(csv.DictReader(open(os.path.join(d, "history.csv"))))
    z = min(rows, key=lambda r: abs(float(r["t_s"]) - t))
    dz = abs(float(np.ravel(fd["projectile_position_m"])[2]) - float(z["projectile_z_m"]))
    # The history is sampled every history interval: within one sample's travel (400 m/s).
    dt_hist = float(rows[2]["t_s"]) - float(rows[1]["t_s"])
    check(dz <= 400 * dt_hist + 1e-9, f"{name}: projectile z off the history by {dz} m")

check(counts["quarter"] == counts["full"], f"quarter and full series differ: {counts}")
if fails:
    print("\n".join("FAIL: " + f for f in fails))
    sys.exit(1)
print(f"meshio: quarter and full series agree: {counts['full'][0]} yarns, {counts['full'][1]} nodes, "
      f"{counts['full'][2]} elements")
