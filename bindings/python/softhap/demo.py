"""softhap.demo(): a small scene that needs no file, for a first run after installing."""

from __future__ import annotations

import os
import pathlib
from typing import Union

from .mesh import Mesh
from .series import Series
from .world import World


def demo(folder: Union[str, os.PathLike] = "softhap-demo", seconds: float = 2.0, rate: float = 60.0) -> pathlib.Path:
    """Press a 1 cm sphere into a soft block and lift it off, print the tool's force, and write
    the block's frames (.vtu and a .pvd index to open in ParaView) into folder.

    The block: 4 x 4 x 2 cm, 8 x 8 x 4 cubes of six tets, corotational, E 5 kPa, nu 0.45,
    1000 kg/m^3, its base fixed, implicit Euler at rate (Hz) under gravity. The sphere goes
    5 mm into the middle of the top over the first half of the run and back out over the
    second. Returns the .pvd path."""
    size = (0.04, 0.04, 0.02)
    radius = 0.005
    steps = max(2, int(round(seconds * rate)))
    mesh = Mesh.box(size, (8, 8, 4))
    with World(gravity=(0.0, 0.0, -9.81)) as world:
        block = world.add_fem_body(mesh, model="corotational", young=5e3, poisson=0.45, integrator="implicit_euler")
        block.fix_nodes([i for i, x in enumerate(mesh.nodes) if x[2] < 1e-9])
        top = (size[0] / 2, size[1] / 2, size[2] + radius)
        tool = world.add_tool("sphere", radius=radius, position=top)
        series = Series(folder, "block")
        for i in range(1, steps + 1):
            depth = 0.005 * (1.0 - abs(2.0 * i / steps - 1.0))
            tool.set_pose((top[0], top[1], top[2] - depth))
            world.step(1.0 / rate, report=False)
            series.add(block, time=i / rate)
            if i % max(1, steps // 8) == 0:
                print("t = %.2f s: sphere %.1f mm deep, force on it %.3f N up" % (i / rate, depth * 1e3, tool.force[2]))
    print("wrote %d frames; open %s in ParaView" % (series.frame_count, series.index_path))
    return series.index_path
