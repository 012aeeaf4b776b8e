#!/usr/bin/env python3
"""Draw a capsule scalpel through a block, as a new user would, and print what each step cost.

    python3 scripts/blade_drag.py RADIUS [--friction MU] [--stiffness K] [--resolution H] [--verbose]

The block: 4 x 4 x 2 cm of 6 x 6 x 3 cells, corotational, 15 kPa, nu 0.45, its bottom fixed,
under gravity, implicit Euler at 60 Hz. The scalpel: an upright capsule of radius RADIUS (m),
2 cm long, from 2 mm above the block's bottom to 2 mm above its top, whose blade edge is its
axis (the geometric criterion, cut refined to H, default 5 mm), friction MU (default 0) and
contact stiffness K (N/m^1.5, default sh_contact_params_default's 1e4). It
enters the block through a side face and is drawn 4 cm across it in 1 s (0.67 mm per step).
Prints the faces cut, the SH_WARN_NOT_CONVERGED and SH_WARN_SUBSTEPPED counts, the step time
median / p90 / max and the final tet count; with --verbose, each step's faces, time,
sub-steps, Newton iterations, contacts, force and warnings.
Needs the library (SOFTHAP_LIBRARY) and bindings/python on PYTHONPATH.
"""

import argparse

import numpy as np

import softhap

STEP, STEPS, TRAVEL = 1.0 / 60.0, 60, 0.04


def step_line(i, x, report, tool):
    warnings = ",".join(sorted(w.replace("SH_WARN_", "") for w in report.warnings))
    return ("%2d x %5.1f mm: faces %3d, %7.1f ms, sub-steps %2d, Newton %2d, contacts %3d, |F| %.3f N %s"
            % (i, 1e3 * x, report.cut_faces, 1e3 * report.wall_seconds, report.substeps, report.newton_iterations,
               report.contact_count, np.linalg.norm(tool.force), warnings))


def main(radius, friction, stiffness, resolution, verbose):
    with softhap.World(gravity=(0.0, 0.0, -9.81)) as world:
        mesh = softhap.Mesh.box((0.04, 0.04, 0.02), (6, 6, 3))
        body = world.add_fem_body(mesh, model="corotational", young=15e3, poisson=0.45, integrator="implicit_euler")
        body.fix_nodes(np.flatnonzero(mesh.nodes[:, 2] == 0.0))
        start = np.array([-0.005, 0.017, 0.012])
        tool = world.add_tool("capsule", radius=radius, half_length=0.01, position=start, friction=friction,
                              stiffness=stiffness)
        tool.set_cutting(edge=((0.0, 0.0, -0.01), (0.0, 0.0, 0.01)), resolution=resolution)
        faces, times = 0, []
        for i in range(STEPS):
            x = start[0] + TRAVEL * (i + 1) / STEPS
            tool.set_pose((x, start[1], start[2]))
            report = world.step(STEP)
            faces += report.cut_faces
            times.append(1e3 * report.wall_seconds)
            if verbose:
                print(step_line(i, x, report, tool))
        print("capsule r %.1f mm, friction %g, stiffness %g: %d faces cut, SH_WARN_NOT_CONVERGED %d, SH_WARN_SUBSTEPPED %d; "
              "step median %.1f ms, p90 %.1f ms, max %.0f ms; %d tets"
              % (1e3 * radius, friction, stiffness, faces, world.warnings["SH_WARN_NOT_CONVERGED"],
                 world.warnings["SH_WARN_SUBSTEPPED"], np.median(times), np.percentile(times, 90), max(times),
                 body.tet_count))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("radius", type=float)
    parser.add_argument("--friction", type=float, default=0.0)
    parser.add_argument("--stiffness", type=float, default=1e4)
    parser.add_argument("--resolution", type=float, default=0.005)
    parser.add_argument("--verbose", action="store_true")
    args = parser.parse_args()
    main(args.radius, args.friction, args.stiffness, args.resolution, args.verbose)
