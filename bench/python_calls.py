"""What a call from Python costs on top of the C call it makes: Haptic.step against the same
sh_haptic_step through a bare ctypes call with its arguments made once, and World.step with and
without its report. One JSON line per case on stdout (median and p99.9 over the calls, in us).

    PYTHONPATH=bindings/python SOFTHAP_LIBRARY=build/libsofthap.so \
        python3 bench/python_calls.py [--meshes DIR] [--calls N]

The scene: liver2.msh scaled by 0.1 (1,493 tets), corotational, 15 kPa, no gravity, symplectic
Euler; a 5 mm sphere tool 1 cm above its highest node, so that the haptic step renders the
proxy only and its C cost is small next to the wrapper's (the quantity measured here); a haptic
context of 15 mm at 10 kHz (so each world step also extracts its buffer). Each call is timed
on its own with time.perf_counter().

"python/machine_busy_loop" is a pure-Python loop whose median is calibrated to the block case's:
its p99.9 is what this machine and the interpreter add to any call that long (the floor under
the block case's p99.9).

"python/haptic_step_block500_stiff" is softhap_bench's haptic/rate/10000hz/stiff/500 case from
Python: the 6 x 6 x 3 cm block (12 x 12 x 6 Kuhn-split cells, 5184 tets, corotational, 15 kPa,
nu 0.45, mass damping 5/s, base fixed), a 1 cm sphere of 2e5 N/m^1.5 pressed 3 mm into its
top over 0.3 s and then circling 1 mm once a second, a 500-tet buffer at 10 kHz; the full
model is stepped once at the start and then left alone (frozen); 0.2 s of ticks warm up.
"""

import argparse
import ctypes
import json
import pathlib
import time

import numpy as np

import softhap
from softhap._lib import sh_haptic_output
from softhap._loaded import lib


def timed(call, count):
    """Median and p99.9 (us) of count timed calls of call()."""
    samples = np.empty(count)
    for i in range(count):
        start = time.perf_counter()
        call()
        samples[i] = time.perf_counter() - start
    return float(np.median(samples) * 1e6), float(np.percentile(samples, 99.9) * 1e6)


def emit(case, count, median, p999, **extra):
    print(json.dumps({"case": case, "calls": count, "median_us": round(median, 2), "p999_us": round(p999, 2), **extra}))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshes", default=str(pathlib.Path(__file__).resolve().parents[2] / "shared" / "meshes"))
    parser.add_argument("--calls", type=int, default=20000)
    args = parser.parse_args()
    mesh = softhap.Mesh.load(str(pathlib.Path(args.meshes) / "liver2.msh")).transform(0.1)
    with softhap.World(gravity=(0.0, 0.0, 0.0)) as world:
        body = world.add_fem_body(mesh, model="corotational", young=15e3, poisson=0.45)
        x = body.positions
        top = x[np.argmax(x[:, 2])]
        pose = (top[0], top[1], top[2] + 0.01)
        tool = world.add_tool("sphere", radius=0.005, position=pose)
        haptic = world.add_haptic(tool, radius=0.015, dt=1e-4)
        world.step(1e-4)

        median, p999 = timed(lambda: haptic.step(pose), args.calls)
        emit("python/haptic_step", args.calls, median, p999)
        position = (ctypes.c_double * 3)(*pose)
        orientation = (ctypes.c_double * 4)(1.0, 0.0, 0.0, 0.0)
        out = sh_haptic_output()
        handle, out_ref = haptic._handle, ctypes.byref(out)
        median_c, p999_c = timed(lambda: lib.sh_haptic_step(handle, position, orientation, 1e-4, out_ref), args.calls)
        emit("python/haptic_step_bare_ctypes", args.calls, median_c, p999_c, wrapper_us=round(median - median_c, 2))

        dt = 0.5 * body.info.dt_critical
        steps = max(1, args.calls // 10)
        median, p999 = timed(lambda: world.step(dt), steps)
        emit("python/world_step_report", steps, median, p999, tets=mesh.tet_count)
        median, p999 = timed(lambda: world.step(dt, report=False), steps)
        emit("python/world_step_no_report", steps, median, p999, tets=mesh.tet_count)
    median, p999 = block_press(args.calls)
    emit("python/haptic_step_block500_stiff", args.calls, median, p999, buffer_tets=500, rate_hz=10000)
    length = busy_length(median)
    median_busy, p999_busy = timed(lambda: busy(length), args.calls)
    emit("python/machine_busy_loop", args.calls, median_busy, p999_busy, loop_length=length)


def busy(length):
    """A pure-Python loop of length iterations: no allocation, no call into C."""
    for _ in range(length):
        pass


def busy_length(target_us):
    """The busy() length whose median is target_us on this machine: timed like a call, its
    p99.9 is the tail the machine and the interpreter add to any call that long."""
    length = 100
    for _ in range(3):
        median, _ = timed(lambda: busy(length), 2000)
        length = max(1, int(length * target_us / median))
    return length


def block_press(calls):
    """Median and p99.9 (us) of Haptic.step on the pressed block (see the module docstring)."""
    mesh = softhap.Mesh.box((0.06, 0.06, 0.03), (12, 12, 6))
    with softhap.World(gravity=(0.0, 0.0, 0.0)) as world:
        body = world.add_fem_body(mesh, model="corotational", young=15e3, poisson=0.45, damping_mass=5.0)
        body.fix_nodes(np.flatnonzero(mesh.nodes[:, 2] < 1e-9))
        touch = np.array([0.03, 0.03, 0.03 + 0.01])
        tool = world.add_tool("sphere", radius=0.01, position=touch, stiffness=2e5)
        haptic = world.add_haptic(tool, capacity_tets=500, capacity_nodes=2004, radius=0.05, dt=1e-4,
                                  stale_after=1e3)
        world.step(1e-4)

        def pose(tick):
            t = (tick + 1) * 1e-4
            angle = 2.0 * np.pi * (t - 0.3) if t > 0.3 else 0.0
            return (touch[0] + 1e-3 * (np.cos(angle) - 1.0), touch[1] + 1e-3 * np.sin(angle),
                    touch[2] - 3e-3 * min(1.0, t / 0.3))

        poses = [pose(tick) for tick in range(2000 + calls)]
        for tick in range(2000):
            haptic.step(poses[tick])
        ticks = iter(poses[2000:])
        return timed(lambda: haptic.step(next(ticks)), calls)


if __name__ == "__main__":
    main()
