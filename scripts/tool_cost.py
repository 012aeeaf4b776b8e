#!/usr/bin/env python3
"""Time a tool's contact on liver2: the haptic step at 1 kHz and the full model's step at 60 Hz.

    python3 scripts/tool_cost.py sphere RADIUS
    python3 scripts/tool_cost.py capsule RADIUS HALF_LENGTH
    python3 scripts/tool_cost.py box HALF_X HALF_Y HALF_Z

liver2 scaled to 21 cm (units 0.1 m), corotational, 5 kPa, nu 0.45, implicit Euler at 60 Hz, no
gravity, its lowest 1.5 cm fixed. The tool (1e4 N/m^1.5, n 1.5, no friction; a capsule lies
level along x, a box level with its half widths along x, y, z) starts touching the highest node and presses 8 mm in 0.5 s, then holds 0.5 s,
while a haptic context renders it at 1 kHz (16 ticks per full step). Prints the haptic step's
median and p99.9 (after the first 160 ticks) and the full step's median, with the last force.
Needs the library (SOFTHAP_LIBRARY) and bindings/python on PYTHONPATH.
"""

import argparse
import os
import time

import numpy as np

import softhap

LEVEL_ALONG_X = (np.sqrt(0.5), 0.0, np.sqrt(0.5), 0.0)


def tool_shape(kind, sizes):
    """The tool's shape arguments, its orientation and how far its lowest point lies below its
    position."""
    if kind == "box":
        return dict(half_extents=tuple(sizes[:3])), (1.0, 0.0, 0.0, 0.0), sizes[2]
    shape = dict(radius=sizes[0])
    if kind == "capsule":
        shape["half_length"] = sizes[1]
        return shape, LEVEL_ALONG_X, sizes[0]
    return shape, (1.0, 0.0, 0.0, 0.0), sizes[0]


def main(kind, sizes):
    mesh = softhap.Mesh.load(os.path.join("..", "shared", "meshes", "liver2.msh"), units=0.1)
    x = mesh.nodes
    with softhap.World(gravity=(0, 0, 0)) as world:
        body = world.add_fem_body(mesh, model="corotational", young=5e3, poisson=0.45, integrator="implicit_euler")
        body.fix_nodes(np.flatnonzero(x[:, 2] < x[:, 2].min() + 0.015))
        shape, q, below = tool_shape(kind, sizes)
        top = x[np.argmax(x[:, 2])] + (0.0, 0.0, below)
        tool = world.add_tool(kind, position=top, orientation=q, stiffness=1e4, exponent=1.5, **shape)
        haptic = world.add_haptic(tool, dt=1e-3)
        ticks, steps = [], []
        for step in range(60):
            for tick in range(16):
                p = top - (0.0, 0.0, 0.008 * min(1.0, (16 * step + tick) / 480.0))
                start = time.perf_counter()
                haptic.step(p, q)
                ticks.append(time.perf_counter() - start)
            tool.set_pose(p, q)
            start = time.perf_counter()
            world.step(1.0 / 60.0)
            steps.append(time.perf_counter() - start)
        ticks = 1e6 * np.array(ticks[160:])
        names = {"sphere": "radius", "capsule": "radius, half length", "box": "half widths"}[kind]
        print("%s %s %s mm: haptic step median %.0f us, p99.9 %.0f us; full step median %.1f ms; force %.3f N"
              % (kind, names, ", ".join("%g" % (1e3 * size) for size in sizes), np.median(ticks), np.percentile(ticks, 99.9), 1e3 * np.median(steps), np.linalg.norm(tool.force)))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("kind", choices=["sphere", "capsule", "box"])
    parser.add_argument("sizes", type=float, nargs="+", help="RADIUS; RADIUS HALF_LENGTH; or HALF_X HALF_Y HALF_Z (m)")
    args = parser.parse_args()
    wanted = {"sphere": 1, "capsule": 2, "box": 3}[args.kind]
    if len(args.sizes) != wanted:
        parser.error("%s takes %d size(s), got %d" % (args.kind, wanted, len(args.sizes)))
    main(args.kind, args.sizes)
