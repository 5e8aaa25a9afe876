#!/usr/bin/env python3
"""Read ravel's VTU series with meshio (a reader no one here wrote) and check it.

usage: check_vtu_meshio.py WRITE_TEST_VTU_EXE OUT_DIR
meshio is installed by scripts/setup (python3-meshio): a missing one fails the test.
"""
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import meshio
import numpy as np

exe, out = sys.argv[1], sys.argv[2]
os.makedirs(out, exist_ok=True)
expect = subprocess.run([exe, out], check=True, capture_output=True, text=True).stdout.split()
n_points, n_cells, n_broken, failure_strain = int(expect[0]), int(expect[1]), int(expect[2]), float(expect[3])

pvd = ET.parse(os.path.join(out, "frame.pvd")).getroot()
sets = pvd.findall("./Collection/DataSet")
assert len(sets) == 2, f"pvd lists {len(sets)} datasets"
assert abs(float(sets[1].get("timestep")) - 10e-6) < 1e-12

m = meshio.read(os.path.join(out, sets[1].get("file")))
assert m.points.shape == (n_points, 3), m.points.shape
lines = [c for c in m.cells if c.type == "line"]
assert len(lines) == 1 and lines[0].data.shape == (n_cells, 2), [c.type for c in m.cells]
assert lines[0].data.max() < n_points
cd = {k: v[0] for k, v in m.cell_data.items()}
for key in ("strain", "strain_ratio", "stress", "broken", "yarn_id", "family"):
    assert key in cd and len(cd[key]) == n_cells, f"cell data {key}"
assert int(cd["broken"].sum()) == n_broken, (cd["broken"].sum(), n_broken)
assert np.allclose(cd["strain_ratio"], cd["strain"] / failure_strain, rtol=1e-5, atol=1e-9)
assert "velocity" in m.point_data and m.point_data["velocity"].shape == (n_points, 3)
# Mirrored copies: the fabric is symmetric about x = 0 and y = 0.
assert abs(m.points[:, 0].min() + m.points[:, 0].max()) < 1e-7
assert abs(m.points[:, 1].min() + m.points[:, 1].max()) < 1e-7
print(f"meshio read {n_points} points, {n_cells} line cells, {n_broken} broken: ok")
