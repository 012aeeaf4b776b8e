#!/usr/bin/env python3
"""Press a sphere into the top of a tetrahedral mesh, as a new user would, and print the force.

    python3 scripts/press_probe.py MESH SIZE RADIUS [--stiffness L] [--friction MU] [--plot PNG]
                                   [--capsule HALF_LENGTH | --box HALF_X HALF_Y]

MESH is a file under ../shared/meshes (or a path), scaled so that its largest extent is SIZE (m);
RADIUS is the sphere's (m). Corotational, 5 kPa, nu 0.45, implicit Euler at 60 Hz, no gravity,
nodes within 1.5 cm of the bottom fixed; the sphere (L N/m^1.5, default 1e3, n = 1.5, friction
MU, default 0) starts touching the highest node and presses 1.5 cm down in 1 s, then holds 0.5 s,
while a haptic context renders it at 1 kHz (16-17 ticks per full step). Prints the mesh's surface
edge lengths against the radius, the full model's and the rendered force every 10 steps, the step
times, the count of SH_WARN_NOT_CONVERGED and the largest tick-to-tick change of the rendered
force; with --plot, draws both forces against the tool's travel into PNG (needs matplotlib). With
--capsule the tool is a capsule of that half length (m) lying along x instead of the sphere; with
--box a level box of those half widths along x and y (m) and half thickness RADIUS.
Needs the library (SOFTHAP_LIBRARY) and bindings/python on PYTHONPATH.
"""

import argparse
import os
import time

import numpy as np

import softhap

PRESS, PRESS_TIME, HOLD_TIME, STEP = 0.015, 1.0, 0.5, 1.0 / 60.0


def load(name, size):
    path = name if os.path.exists(name) else os.path.join("..", "shared", "meshes", name)
    mesh = softhap.Mesh.load(path)
    return mesh.transform(size / np.ptp(mesh.nodes, axis=0).max())


def surface_edges(mesh):
    x, tri = mesh.nodes, mesh.surface_triangles
    return np.concatenate([np.linalg.norm(x[tri[:, i]] - x[tri[:, (i + 1) % 3]], axis=1) for i in range(3)])


def pose(top, t):
    return top - (0.0, 0.0, PRESS * min(1.0, t / PRESS_TIME))


def plot(path, title, travel_full, full, travel_ticks, rendered):
    """Full model's and rendered force against the tool's travel, into the PNG at path."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    ax.plot(travel_ticks, rendered, lw=0.8, label="haptic buffer, rendered (1 kHz ticks)")
    ax.plot(travel_full, full, "o", ms=3, label="full model (60 Hz steps)")
    ax.set_xlabel("tool travel from first touch (mm)")
    ax.set_ylabel("force (N)")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def tool_shape(radius, half_length, box):
    """The tool's kind, shape arguments, orientation and name (for the plot)."""
    if box is not None:
        return "box", dict(half_extents=(box[0], box[1], radius)), (1.0, 0.0, 0.0, 0.0), \
            "box (half widths %g x %g mm)" % (1e3 * box[0], 1e3 * box[1])
    if half_length is not None:  # lying along x: the local z axis turned onto x
        orientation = (np.sqrt(0.5), 0.0, np.sqrt(0.5), 0.0)
        return "capsule", dict(radius=radius, half_length=half_length, orientation=orientation), orientation, \
            "capsule (half length %g mm)" % (1e3 * half_length)
    return "sphere", dict(radius=radius), (1.0, 0.0, 0.0, 0.0), "sphere"


def main(name, size, radius, stiffness, friction, plot_path, half_length=None, box=None):
    mesh = load(name, size)
    x = mesh.nodes
    edges = surface_edges(mesh)
    print("%s: %d tets, surface edges median %.1f mm (max %.1f), tool radius %.1f mm"
          % (name, len(mesh.tets), 1e3 * np.median(edges), 1e3 * edges.max(), 1e3 * radius))
    kind, shape, orientation, tool_name = tool_shape(radius, half_length, box)
    with softhap.World(gravity=(0, 0, 0)) as world:
        body = world.add_fem_body(mesh, model="corotational", young=5e3, poisson=0.45, integrator="implicit_euler")
        body.fix_nodes(np.flatnonzero(x[:, 2] < x[:, 2].min() + 0.015))
        top = x[np.argmax(x[:, 2])] + (0.0, 0.0, radius)
        tool = world.add_tool(kind, position=top, stiffness=stiffness, exponent=1.5, friction=friction, **shape)
        haptic = world.add_haptic(tool, dt=1e-3)
        rendered, times, travel_ticks, travel_full, full = [], [], [], [], []
        steps = int(round((PRESS_TIME + HOLD_TIME) / STEP))
        for step in range(steps):
            ticks = 16 if step % 3 == 0 else 17
            for tick in range(ticks):
                device = pose(top, (step + tick / ticks) * STEP)
                rendered.append(np.linalg.norm(haptic.step(device, orientation).force))
                travel_ticks.append(1e3 * (top - device)[2])
            tool.set_pose(pose(top, (step + 1) * STEP), orientation)
            start = time.perf_counter()
            world.step(STEP)
            times.append(1e3 * (time.perf_counter() - start))
            travel_full.append(1e3 * (top - pose(top, (step + 1) * STEP))[2])
            full.append(np.linalg.norm(tool.force))
            if step % 10 == 9:
                print("  t %.2f s  depth %4.1f mm  full %.4f N  rendered %.4f N  contacts %d"
                      % ((step + 1) * STEP, 1e3 * (top - pose(top, (step + 1) * STEP))[2],
                         np.linalg.norm(tool.force), rendered[-1], tool.contacts))
        rendered = np.array(rendered)
        jump = np.abs(np.diff(rendered)).max() / rendered.max() if rendered.max() > 0 else 0.0
        print("  steps: median %.1f ms, p99 %.1f ms; SH_WARN_NOT_CONVERGED %d; largest tick-to-tick change %.0f %% of peak"
              % (np.median(times), np.percentile(times, 99), world.warnings["SH_WARN_NOT_CONVERGED"], 100 * jump))
    if plot_path:
        title = ("%s (%.0f cm), %s r = %g mm, %g N/m^1.5, friction %g\nlargest tick-to-tick change %.1f %% of peak"
                 % (os.path.basename(name), 100 * size, tool_name, 1e3 * radius, stiffness, friction, 100 * jump))
        plot(plot_path, title, travel_full, full, travel_ticks, rendered)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mesh")
    parser.add_argument("size", type=float)
    parser.add_argument("radius", type=float)
    parser.add_argument("--stiffness", type=float, default=1e3)
    parser.add_argument("--friction", type=float, default=0.0)
    parser.add_argument("--plot")
    shapes = parser.add_mutually_exclusive_group()
    shapes.add_argument("--capsule", type=float, metavar="HALF_LENGTH")
    shapes.add_argument("--box", type=float, nargs=2, metavar=("HALF_X", "HALF_Y"))
    args = parser.parse_args()
    main(args.mesh, args.size, args.radius, args.stiffness, args.friction, args.plot, args.capsule, args.box)
