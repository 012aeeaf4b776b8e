#!/usr/bin/env python3
"""Time a cutting tool's topology work per step on the 19 k-tet raptor.

    python3 scripts/blade_cost.py [geometric|physical] [MESH_DIR]

The raptor (raptorTetra_19409.vtu, in cm: 16 cm long), corotational 30 kPa, all nodes fixed
so that stepping costs next to nothing and the topology work stands out. A 2 mm sphere whose
3 cm blade stands across the body is drawn into it along x at 60 Hz (60 steps, 40 % of its
length). Prints the median, p90 and largest `report.topology_seconds` per step, the faces
parted and the tets after. Under the physical criterion nothing breaks (fixed nodes carry no
load), so the figure is the per-step cost of finding the engaged length and holding the
material ahead. Needs the library (SOFTHAP_LIBRARY) and bindings/python on PYTHONPATH.
"""

import os
import sys

import numpy as np

import softhap


def main():
    criterion = sys.argv[1] if len(sys.argv) > 1 else "geometric"
    mesh_dir = sys.argv[2] if len(sys.argv) > 2 else os.path.join(os.path.dirname(__file__), "..", "..", "shared", "meshes")
    mesh = softhap.Mesh.load(os.path.join(mesh_dir, "raptorTetra_19409.vtu"), units="cm")
    lo, hi = mesh.nodes.min(0), mesh.nodes.max(0)
    centre = 0.5 * (lo + hi)
    with softhap.World() as world:
        body = world.add_fem_body(mesh, model="corotational", young=3e4, integrator="symplectic_euler")
        body.fix_nodes(np.arange(mesh.nodes.shape[0]))
        tool = world.add_tool("sphere", radius=0.002, position=(lo[0] - 0.01, centre[1], centre[2]))
        tool.set_cutting(edge=((0, 0, -0.015), (0, 0, 0.015)), criterion=criterion)
        times, faces = [], 0
        for i in range(60):
            x = lo[0] - 0.01 + (i + 1) * (0.4 * (hi[0] - lo[0]) + 0.01) / 60
            tool.set_pose((x, centre[1], centre[2]))
            report = world.step(1 / 60)
            times.append(1e3 * report.topology_seconds)
            faces += report.cut_faces
        ts = np.array(times)
        print("%s: topology time per step %.2f ms median, %.2f p90, %.1f max; %d faces parted, %d tets" % (
            criterion, np.median(ts), np.percentile(ts, 90), ts.max(), faces, body.tet_count))


if __name__ == "__main__":
    main()
