"""softhap's implicit step beside pybullet's implicit deformable solver on the same cube, in one
run: a 0.1 m cube of 15 x 15 x 15 Kuhn-split cells (20,250 tets), 1 kg, E 1e4 Pa, nu 0.45,
gravity -z, each simulator's default implicit settings; "stand" fixes its bottom face (it sags
under its weight), "droop" its x = 0 face (it bends over: a large rotation). One JSON line per
case on stdout: the step's wall time (median, p99, max in ms over the timed steps, after one
untimed first step: each solver's set-up) and where the cube's far top corner ended (m), so that
the two simulators can be seen to simulate the same thing.

    pip install pybullet            # 3.2.7 was measured; optional: without it, softhap alone
    PYTHONPATH=bindings/python SOFTHAP_LIBRARY=build/libsofthap.so \\
        python3 bench/peers/pybullet_cube.py [--steps N] [--filter TEXT]

pybullet runs its neo-Hookean model (its only volumetric one besides mass-spring) with mu and
lambda from E and nu and NeoHookeanDamping 0.01 (--pybullet-damping): without damping its
default solver diverged on this cube within about 10 steps at 240 Hz (the corner flew to
kilometres); softhap runs corotational, StVK and neo-Hookean, undamped. Both take the
same nodes and tets (pybullet reads them from a legacy VTK file this script writes) and anchor
the same nodes to the world. Each case is timed on one thread of an otherwise idle process;
run it on a quiet machine and compare rows of the same run only.
"""

import argparse
import contextlib
import json
import os
import pathlib
import sys
import statistics
import tempfile
import time

import numpy as np

import softhap

SIZE = 0.1  # m
CELLS = 15
YOUNG, POISSON, DENSITY = 1e4, 0.45, 1000.0
SCENES = {"stand": 2, "droop": 0}  # the axis whose 0 face is fixed
STEPS = {"240hz": 1.0 / 240.0, "60hz": 1.0 / 60.0}
MODELS = ("corotational", "stvk", "neohookean")

def cube():
    """Nodes (n x 3) and tets (m x 4) of the cube (softhap.Mesh.box: six tets per cell)."""
    mesh = softhap.Mesh.box((SIZE, SIZE, SIZE), (CELLS, CELLS, CELLS))
    return mesh.nodes, mesh.tets


def corner(nodes):
    """The node at the far top corner (x, y, z all largest)."""
    return int(np.argmax(nodes.sum(axis=1)))


def timings(step, steps):
    """One untimed step, then the wall times (s) of steps more."""
    step()
    times = []
    for _ in range(steps):
        start = time.perf_counter()
        step()
        times.append(time.perf_counter() - start)
    return times


def emit(case, times, tip, **extra):
    ms = sorted(t * 1e3 for t in times)
    p99 = ms[min(len(ms) - 1, int(round(0.99 * (len(ms) - 1))))]
    row = {"case": case, "tets": 6 * CELLS**3, "steps": len(ms), "median_ms": round(statistics.median(ms), 3),
           "p99_ms": round(p99, 3), "max_ms": round(ms[-1], 3), "tip": [round(float(c), 5) for c in tip], **extra}
    print(json.dumps(row), flush=True)


def run_softhap(nodes, tets, scene, dt, model, steps):
    with softhap.World(gravity=(0.0, 0.0, -9.81)) as world:
        body = world.add_fem_body(softhap.Mesh(nodes, tets), model=model, young=YOUNG, poisson=POISSON,
                                  density=DENSITY, integrator="implicit_euler")
        body.fix_nodes(np.flatnonzero(nodes[:, SCENES[scene]] < 1e-9))
        times = timings(lambda: world.step(dt, report=False), steps)
        return times, body.positions[corner(nodes)]


def write_vtk(path, nodes, tets):
    """A legacy ASCII VTK unstructured grid of tets (cell type 10), as pybullet reads it."""
    with open(path, "w") as f:
        f.write("# vtk DataFile Version 2.0\ncube\nASCII\nDATASET UNSTRUCTURED_GRID\n")
        f.write(f"POINTS {len(nodes)} double\n")
        np.savetxt(f, nodes, fmt="%.17g")
        f.write(f"CELLS {len(tets)} {5 * len(tets)}\n")
        np.savetxt(f, np.hstack([np.full((len(tets), 1), 4), tets]), fmt="%d")
        f.write(f"CELL_TYPES {len(tets)}\n")
        np.savetxt(f, np.full(len(tets), 10), fmt="%d")


@contextlib.contextmanager
def stdout_to_stderr():
    """Send what C code prints on stdout (pybullet's loader does) to stderr, so that stdout
    keeps only the JSON lines."""
    sys.stdout.flush()
    saved = os.dup(1)
    os.dup2(2, 1)
    try:
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def run_pybullet(pb, vtk, nodes, scene, dt, steps, damping):
    client = pb.connect(pb.DIRECT)
    try:
        pb.resetSimulation(pb.RESET_USE_DEFORMABLE_WORLD, physicsClientId=client)
        pb.setGravity(0.0, 0.0, -9.81, physicsClientId=client)
        pb.setTimeStep(dt, physicsClientId=client)
        mu = YOUNG / (2.0 * (1.0 + POISSON))
        lam = YOUNG * POISSON / ((1.0 + POISSON) * (1.0 - 2.0 * POISSON))
        with stdout_to_stderr():
            body = pb.loadSoftBody(str(vtk), basePosition=[0.0, 0.0, 0.0], mass=DENSITY * SIZE**3, useNeoHookean=1,
                                   NeoHookeanMu=mu, NeoHookeanLambda=lam, NeoHookeanDamping=damping, useSelfCollision=0,
                                   physicsClientId=client)
        loaded = np.array(pb.getMeshData(body, -1, flags=pb.MESH_DATA_SIMULATION_MESH, physicsClientId=client)[1])
        if loaded.shape != nodes.shape or np.abs(loaded - nodes).max() > 1e-9:
            raise SystemExit("pybullet did not load the cube's nodes in order: the anchors would be wrong")
        for node in np.flatnonzero(nodes[:, SCENES[scene]] < 1e-9):
            pb.createSoftBodyAnchor(body, int(node), -1, -1, physicsClientId=client)
        times = timings(lambda: pb.stepSimulation(physicsClientId=client), steps)
        final = pb.getMeshData(body, -1, flags=pb.MESH_DATA_SIMULATION_MESH, physicsClientId=client)[1]
        return times, np.array(final[corner(nodes)])
    finally:
        pb.disconnect(client)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10, help="timed steps per case (default 10)")
    parser.add_argument("--filter", default="", help="keep the cases whose name contains it")
    parser.add_argument("--pybullet-damping", type=float, default=0.01, help="pybullet's NeoHookeanDamping")
    args = parser.parse_args()
    try:
        import pybullet as pb
    except ImportError:
        pb = None
        print(json.dumps({"note": "pybullet is not installed (pip install pybullet): softhap only"}), flush=True)
    nodes, tets = cube()
    with tempfile.TemporaryDirectory() as folder:
        vtk = pathlib.Path(folder) / "cube.vtk"
        write_vtk(vtk, nodes, tets)
        for scene in SCENES:
            for rate, dt in STEPS.items():
                for model in MODELS:
                    case = f"cube-{scene}/{rate}/softhap/{model}"
                    if args.filter in case:
                        times, tip = run_softhap(nodes, tets, scene, dt, model, args.steps)
                        emit(case, times, tip, dt=dt)
                case = f"cube-{scene}/{rate}/pybullet/neohookean"
                if pb is not None and args.filter in case:
                    times, tip = run_pybullet(pb, vtk, nodes, scene, dt, args.steps, args.pybullet_damping)
                    emit(case, times, tip, dt=dt, damping=args.pybullet_damping, version=pb.getAPIVersion())


if __name__ == "__main__":
    main()
