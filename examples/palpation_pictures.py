"""Palpation and incision pictures, headless: SOFA's liver2 (21 cm, 1,493 tets, corotational,
3 kPa, its lowest 1.5 cm held, no gravity, so that the tools are the only loads; implicit Euler
at 60 Hz). A 1 cm sphere presses 1.5 cm into it over the middle of its base and lifts off;
then a scalpel (a 3 cm blade, upright) goes 1 cm into the top and draws a 6 cm incision. Every
tenth step is rendered off-screen to frames/palpation_png/press_NNN.png and incision_NNN.png,
the surface coloured by displacement (mm), with the tool. Prints the tools' forces.

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
        press(world, body, rest, top, radius, out, camera)
        incise(world, body, rest, top, out, camera)
    print("wrote the pictures in %s" % out)


def press(world, body, rest, top, radius, out, camera):
    """The sphere down 1.5 cm over 1 s, held, and up over the last second (2.5 s)."""
    tool = world.add_tool("sphere", radius=radius, position=top, stiffness=1e3, friction=0.5)
    for i in range(1, 151):
        t = i / 60.0
        depth = 0.015 * min(1.0, t, max(0.0, 2.5 - t))
        position = top - (0.0, 0.0, depth)
        tool.set_pose(position)
        world.step(1.0 / 60.0, report=False)
        if i % 10 == 0:
            viz.screenshot(body, out / ("press_%03d.png" % (i // 10)), rest=rest, tool=(position, radius),
                           camera=camera)
            print("press, t = %.2f s: sphere %.1f mm down, force %.3f N" % (t, 1e3 * depth, np.linalg.norm(tool.force)))
    tool.destroy()


def incise(world, body, rest, top, out, camera):
    """A scalpel 1 cm into the top over 0.5 s, then 6 cm along x over 2 s; seen from above."""
    centre = rest.mean(axis=0)
    above = (centre + (0.0, -0.08, 0.35), centre, (0.0, 1.0, 0.0))
    half = 0.015
    start = top + (-0.03, 0.0, half - 0.01 - 0.01)  # the blade's tip 1 cm above the surface, then 1 cm in
    scalpel = world.add_tool("capsule", radius=0.0005, half_length=half, position=start + (0.0, 0.0, 0.01))
    scalpel.set_cutting(edge=((0.0, 0.0, -half), (0.0, 0.0, half)))
    for i in range(1, 151):
        t = i / 60.0
        position = start + (0.06 * min(1.0, max(0.0, t - 0.5) / 2.0), 0.0, 0.01 * max(0.0, 1.0 - t / 0.5))
        scalpel.set_pose(position)
        report = world.step(1.0 / 60.0)
        if i % 10 == 0:
            viz.screenshot(body, out / ("incision_%03d.png" % (i // 10)), rest=rest, camera=above,
                           tool=(position, 0.002))
            print("incision, t = %.2f s: %d faces cut this step, %d tets, force %.3f N" % (
                t, report.cut_faces, body.info["element_count"], np.linalg.norm(scalpel.force)))


if __name__ == "__main__":
    main()
