#!/usr/bin/env python3
"""The two yarns through the strike point, frame by frame, from a run's VTU series.

    ravel run --vtk --frames every=66 --set solver.end_time_us=92 --out RUN
    /usr/bin/python3 bench/pole_yarns.py RUN [--csv FILE]

For the weft (along x) and the warp (along y) whose centre line passes within half a yarn
spacing of the strike point, on the positive half of the quarter model (the VTU's copy 0),
each frame gives (CSV on stdout, or into FILE):

- strain_core / strain_far / strain_clamp: mean element strain within 6 mm of the strike
  point, 20-50 mm out, and beyond 58 mm (by the clamp, for a clamped yarn), in %;
- strain_max: the yarn's largest element strain, in %, and where (mm from the strike point);
- rise_mm: the median zig-zag rise between neighbouring nodes 6-50 mm out, each node's
  distance from the midpoint of its two neighbours (L1 = the crossing gap at rest; a crimp
  taken up by compressed crossings or interchange makes it smaller);
- slip_mps: mean |slip rate| of the yarn's nodes 6-30 mm out (0: stuck to its crossings);
- v_along_min / v_along_max: the range of its nodes' velocity along the yarn 6-30 mm out.

docs/MODEL.md §9 (260 m/s, mu = 0.2 against 1.0) quotes this tool's numbers. Needs Debian's
python3-meshio (the system python: /usr/bin/python3).
"""
import argparse
import glob
import math
import os
import sys

import meshio
import numpy as np

CORE_MM, FAR_MM, CLAMP_MM = 6.0, (20.0, 50.0), 58.0


def yarn_rows(m):
    cells = m.cells_dict["line"]
    p = m.points * 1000.0
    strain = m.cell_data["strain"][0] * 100.0
    family = m.cell_data["family"][0]
    copy = m.cell_data["copy"][0]
    slip = m.point_data["slip_rate"]
    vel = m.point_data["velocity"]
    mid = 0.5 * (p[cells[:, 0]] + p[cells[:, 1]])
    # the yarn spacing: the most common element length projected on the plane
    d = p[cells[:, 1]] - p[cells[:, 0]]
    spacing = float(np.median(np.hypot(d[:, 0], d[:, 1])))
    t_us = float(np.ravel(m.field_data["TimeValue"])[0]) * 1e6
    out = {"t_us": t_us}
    for name, fam, along in (("weft", 1, 0), ("warp", 0, 1)):
        across = 1 - along
        sel = (copy == 0) & (family == fam) & (np.abs(mid[:, across]) < 0.5 * spacing) & (mid[:, along] > 0)
        idx = np.where(sel)[0]
        if idx.size == 0:
            raise SystemExit(f"pole_yarns: no {name} elements through the strike point in this frame")
        s = strain[idx]
        r = np.abs(mid[idx, along])
        core = s[r < CORE_MM]
        far = s[(r > FAR_MM[0]) & (r < FAR_MM[1])]
        clamp = s[r > CLAMP_MM]
        k = int(np.argmax(s))
        # nodes of the yarn in order along it
        nodes = np.unique(cells[idx].ravel())
        nodes = nodes[np.argsort(p[nodes, along])]
        xs = p[nodes]
        rise = np.linalg.norm(xs[1:-1] - 0.5 * (xs[:-2] + xs[2:]), axis=1)
        rpos = np.abs(xs[1:-1, along])
        rise_band = rise[(rpos > CORE_MM) & (rpos < FAR_MM[1])]
        band = (np.abs(xs[:, along]) > CORE_MM) & (np.abs(xs[:, along]) < 30.0)
        nan = float("nan")
        out.update(
            {
                f"{name}_strain_core": float(core.mean()) if core.size else nan,
                f"{name}_strain_far": float(far.mean()) if far.size else nan,
                f"{name}_strain_clamp": float(clamp.mean()) if clamp.size else nan,
                f"{name}_strain_max": float(s[k]),
                f"{name}_strain_max_at_mm": float(r[k]),
                f"{name}_rise_mm": float(np.median(rise_band)) if rise_band.size else nan,
                f"{name}_slip_mps": float(np.abs(slip[nodes[band]]).mean()) if band.any() else nan,
                f"{name}_v_along_min": float(vel[nodes[band], along].min()) if band.any() else nan,
                f"{name}_v_along_max": float(vel[nodes[band], along].max()) if band.any() else nan,
            }
        )
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run", help="a ravel run's output folder (with vtk/frame_*.vtu)")
    ap.add_argument("--csv", help="write the CSV here (atomically) instead of stdout")
    a = ap.parse_args()
    frames = sorted(glob.glob(os.path.join(a.run, "vtk", "frame_*.vtu")))
    if not frames:
        sys.exit(f"pole_yarns: no VTU frames in {a.run}/vtk (run ravel with --vtk)")
    rows = [yarn_rows(meshio.read(f)) for f in frames]
    keys = list(rows[0].keys())
    lines = [",".join(keys)]
    for r in rows:
        lines.append(",".join("" if isinstance(r[k], float) and math.isnan(r[k]) else f"{r[k]:.6g}" for k in keys))
    text = "\n".join(lines) + "\n"
    if a.csv:
        tmp = a.csv + ".tmp"
        with open(tmp, "w") as f:
            f.write(text)
        os.replace(tmp, a.csv)
    else:
        sys.stdout.write(text)


if __name__ == "__main__":
    main()
