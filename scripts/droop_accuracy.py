#!/usr/bin/env python3
"""How accurate, and how fast, the default implicit step is under large rotation.

    python3 scripts/droop_accuracy.py [MODEL] [CELLS] [STEPS]

The issue's cube (0.1 m, CELLS^3 Kuhn-split cells, 1 kg, E 1e4 Pa, nu 0.45) droops under
gravity from its fixed x = 0 face at 60 Hz for STEPS steps (default corotational, 15 cells =
20,250 tets, 30 steps: it bends over by about 3 cm). Each run's nodes at the end are compared
with the converged backward Euler step (Newton to 1e-9, a factorisation at every iteration),
relative to that run's largest displacement:

  - the default settings (one linearised update per step; a kept factorisation, or CG on the
    tangent where the tangent drifts too fast for new ones to pay off, preconditioned by the
    kept factorisation or, from 9,000 free DOF, by the warped multigrid);
  - exact linearised steps (factor_reuse 0: a factorisation every step);
  - backward Euler itself at dt / 4, which shows the size of its own time error at 60 Hz.

One JSON line per run: the error, the step's median and mean wall time (ms), factorisations
and linear iterations (direct solves and CG iterations). Needs the library (SOFTHAP_LIBRARY) and
bindings/python on PYTHONPATH.
"""

import json
import sys
import time

import numpy as np

import softhap

SIZE, YOUNG, POISSON, DENSITY, DT = 0.1, 1e4, 0.45, 1000.0, 1.0 / 60.0


def run(mesh, model, dt, steps, **implicit):
    """The nodes after steps of dt, and the steps' median and mean wall time (ms),
    factorisations and linear iterations."""
    with softhap.World(gravity=(0.0, 0.0, -9.81)) as world:
        body = world.add_fem_body(mesh, model=model, young=YOUNG, poisson=POISSON, density=DENSITY,
                                  integrator="implicit_euler", **implicit)
        body.fix_nodes(np.flatnonzero(mesh.nodes[:, 0] < 1e-9))
        times, factorizations, linear = [], 0, 0
        for _ in range(steps):
            start = time.perf_counter()
            report = world.step(dt)
            times.append(time.perf_counter() - start)
            factorizations += report.factorizations
            linear += report.linear_iterations
        return body.positions.copy(), 1e3 * float(np.median(times)), 1e3 * float(np.mean(times)), factorizations, linear


def main():
    model = sys.argv[1] if len(sys.argv) > 1 else "corotational"
    cells = int(sys.argv[2]) if len(sys.argv) > 2 else 15
    steps = int(sys.argv[3]) if len(sys.argv) > 3 else 30
    mesh = softhap.Mesh.box((SIZE, SIZE, SIZE), (cells, cells, cells))
    converged = dict(newton_max_iterations=50, newton_tolerance=1e-9, factor_reuse=0.0)
    reference = run(mesh, model, DT, steps, **converged)[0]
    scale = float(np.abs(reference - mesh.nodes).max())
    runs = [("default", DT, steps, {}), ("exact linearised (factor_reuse 0)", DT, steps, dict(factor_reuse=0.0)),
            ("backward Euler at dt/4", DT / 4, 4 * steps, converged)]
    for name, dt, count, implicit in runs:
        x, median, mean, factorizations, linear = run(mesh, model, dt, count, **implicit)
        print(json.dumps({"model": model, "tets": 6 * cells**3, "run": name, "dt": dt,
                          "error": round(float(np.abs(x - reference).max()) / scale, 6), "median_ms": round(median, 1),
                          "mean_ms": round(mean, 1), "factorizations": factorizations, "linear_iterations": linear,
                          "largest_displacement_m": round(scale, 5)}), flush=True)


if __name__ == "__main__":
    main()
