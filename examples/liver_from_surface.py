"""A simulated liver from a surface: liver-smooth.obj (a closed triangle surface in cm) is
filled with tets (softhap.tetrahedralize, pytetwild backend), its lowest 12 mm held (as the
body around an organ holds it), and a 1 cm sphere comes down 10 mm onto its highest point
while it settles under gravity (corotational, implicit Euler at 60 Hz, 1.5 s). Writes
frames/liver_surface/liver.pvd (open it in ParaView) and prints the tool's force.

    pip install meshio pytetwild
    PYTHONPATH=bindings/python python3 examples/liver_from_surface.py [../shared/meshes]
"""

import pathlib
import sys

import numpy as np

import softhap


def main():
    meshes = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "../shared/meshes")
    liver = softhap.tetrahedralize(meshes / "liver-smooth.obj", units="cm", edge_length=0.008)
    nodes = liver.nodes
    print("liver: %d nodes, %d tets, %.1f cm^3, %.1f cm across" % (
        liver.info["node_count"], liver.info["tet_count"], liver.info["volume"] * 1e6,
        100 * np.ptp(nodes, axis=0).max()))
    highest = nodes[np.argmax(nodes[:, 2])]
    radius = 0.005
    with softhap.World(gravity=(0.0, 0.0, -9.81)) as world:
        body = world.add_fem_body(liver, model="corotational", young=4e3, poisson=0.45, integrator="implicit_euler",
                                  damping_mass=2.0)
        body.fix_nodes(np.flatnonzero(nodes[:, 2] < nodes[:, 2].min() + 0.012))
        above = highest + (0.0, 0.0, radius + 0.002)
        tool = world.add_tool("sphere", radius=radius, position=above)
        series = softhap.Series("frames/liver_surface", "liver")
        for i in range(1, 91):
            depth = 0.010 * min(1.0, i / 60.0)  # 10 mm down over the first second, then held
            tool.set_pose(above - (0.0, 0.0, depth))
            world.step(1.0 / 60.0, report=False)
            series.add(body, time=i / 60.0)
            if i % 15 == 0:
                print("t = %.2f s: tool %.1f mm below its start, force %.3f N up, highest node z %.1f mm" % (
                    i / 60.0, depth * 1e3, tool.force[2], 1e3 * body.positions[:, 2].max()))
    print("wrote %d frames: %s" % (series.frame_count, series.index_path))


if __name__ == "__main__":
    main()
