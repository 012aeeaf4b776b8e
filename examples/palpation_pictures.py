"""Palpation pictures, headless: a 1 cm sphere presses 1.5 cm into SOFA's liver2 (21 cm,
1,493 tets, corotational, 3 kPa, its lowest 1.5 cm held, no gravity, so that the press is the
only load; implicit Euler at 60 Hz) over the middle of its base, and lifts off; every tenth step is rendered off-screen to frames/palpation_png/frame_NNN.png, the surface
coloured by displacement (mm), with the sphere. Prints the tool's force as it goes.

    pip install pyvista
    PYTHONPATH=bindings/python python3 examples/palpation_pictures.py [../shared/meshes]
"""

import pathlib
import sys

import numpy as np

import softhap
from softhap import viz


def main():
    meshes = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "../shared/meshes")
    out = pathlib.Path("frames/palpation_png")
    out.mkdir(parents=True, exist_ok=True)
    liver = softhap.Mesh.load(meshes / "liver2.msh", units=0.1)  # the file's unit is 10 cm: 21 cm across
    rest = liver.nodes
    radius = 0.01
    base = rest[:, 2] < rest[:, 2].min() + 0.015
    over_base = np.linalg.norm(rest[:, :2] - rest[base, :2].mean(axis=0), axis=1) < 0.02
    top = rest[over_base][np.argmax(rest[over_base, 2])] + (0.0, 0.0, radius)
    centre = rest.mean(axis=0)
    camera = (centre + (0.25, -0.3, 0.25), centre, (0.0, 0.0, 1.0))
    with softhap.World(gravity=(0.0, 0.0, 0.0)) as world:
        body = world.add_fem_body(liver, model="corotational", young=3e3, poisson=0.45, integrator="implicit_euler",
                                  damping_mass=2.0)
        body.fix_nodes(np.flatnonzero(base))
        tool = world.add_tool("sphere", radius=radius, position=top, stiffness=1e3, friction=0.5)
        steps = 150
        for i in range(1, steps + 1):
            t = i / 60.0
            depth = 0.015 * min(1.0, t, max(0.0, 2.5 - t))  # down over 1 s, held, up over the last second
            position = top - (0.0, 0.0, depth)
            tool.set_pose(position)
            world.step(1.0 / 60.0, report=False)
            if i % 10 == 0:
                viz.screenshot(body, out / ("frame_%03d.png" % (i // 10)), rest=rest, tool=(position, radius),
                               camera=camera)
                print("t = %.2f s: sphere %.1f mm down, force %.3f N" % (t, 1e3 * depth, np.linalg.norm(tool.force)))
    print("wrote %d pictures in %s" % (steps // 10, out))


if __name__ == "__main__":
    main()
