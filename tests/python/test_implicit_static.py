"""The implicit (backward) Euler integrator and static equilibrium, against exact discrete
recursions, closed forms and a textbook linear-tetrahedron stiffness matrix."""

import ctypes
import math

import numpy as np
import pytest

import softhap

from conftest import run_python
from textbook import G, UNIT_TET, linear_tet_stiffness


# ------------------------------------------------------------------------------------------
# implicit Euler


def test_implicit_particle_follows_backward_euler():
    # v_{n+1} = v_n + dt a, x_{n+1} = x_n + dt v_{n+1}: z = z0 - g dt^2 n (n + 1) / 2
    z0, dt, n = 2.0, 0.01, 40
    with softhap.World() as world:
        body = world.add_spring_body([[0.0, 0.0, z0]], integrator="implicit_euler")
        for _ in range(n):
            report = world.step(dt)
        np.testing.assert_allclose(body.positions[0], [0, 0, z0 - G * dt * dt * n * (n + 1) / 2], atol=1e-12)
        np.testing.assert_allclose(body.velocities[0], [0, 0, -G * dt * n], atol=1e-12)
        assert report.substeps == 1


@pytest.mark.parametrize("damping", [0.0, 0.1])
def test_implicit_oscillator_matches_the_backward_euler_recursion(damping):
    # node 0 fixed, node 1 (mass m) on a spring k (and damping c) along x. Backward Euler on
    # s = (x, v): s_{n+1} = (I - dt A)^-1 s_n with A = [[0, 1], [-k/m, -c/m]].
    k, m, length, amplitude = 50.0, 0.02, 0.1, 1e-3
    omega = math.sqrt(k / m)
    dt = 5.0 / omega  # far beyond any explicit integrator's stable step
    with softhap.World(gravity=(0, 0, 0)) as world:
        body = world.add_spring_body(
            [[0.0, 0.0, 0.0], [length, 0.0, 0.0]], springs=[[0, 1]], stiffness=k, damping=damping,
            mass=m, integrator="implicit_euler",
        )
        body.fix_nodes([0])
        body.positions = [[0.0, 0.0, 0.0], [length + amplitude, 0.0, 0.0]]
        step = np.linalg.inv(np.eye(2) - dt * np.array([[0.0, 1.0], [-k / m, -damping / m]]))
        state = np.array([amplitude, 0.0])
        for _ in range(20):
            report = world.step(dt)
            state = step @ state
            assert body.positions[1, 0] - length == pytest.approx(state[0], rel=1e-9, abs=1e-15)
            assert body.velocities[1, 0] == pytest.approx(state[1], rel=1e-9, abs=1e-15)
        # A linear spring along its axis: one exact update per step, one solve, and the
        # factorisation of the first step serves every later one.
        assert report.substeps == 1
        assert report.newton_iterations == 1 and report.linear_iterations == 1
        assert report.factorizations == 0


def test_implicit_step_from_rest_of_two_laws_is_the_linear_bodys():
    # At the rest shape every law's tangent is linear elasticity's, so one exact linearised step
    # from rest (factor_reuse 0) of a cantilever made of a StVK region and a neo-Hookean one
    # moves it as the same cantilever of the linear law does, to round-off: the assembled
    # tangent puts each region's element matrices on its own elements. The StVK region is 40
    # tets, an odd number of the kernels' 8-element batches, where the assembly takes the
    # batches two at a time.
    mesh = softhap.Mesh.box((0.1, 0.02, 0.02), (10, 2, 2))  # 240 tets

    def step_from_rest(regions):
        with softhap.World() as world:
            body = world.add_fem_body(mesh, model="linear", young=3e5, poisson=0.45, integrator="implicit_euler",
                                      factor_reuse=0.0)
            for model, tets in regions:
                body.set_material(tets, model=model, young=3e5, poisson=0.45)
            rest = body.positions
            body.fix_nodes(np.nonzero(rest[:, 0] < 1e-9)[0])
            report = world.step(0.01)
            assert report.newton_iterations == 1
            return body.positions - rest

    linear = step_from_rest([])
    two_laws = step_from_rest([("stvk", range(40)), ("neohookean", range(40, 240))])
    assert np.abs(linear).max() > 5e-4  # the step moves the tip by about 1 mm
    assert np.abs(two_laws - linear).max() <= 1e-9 * np.abs(linear).max()


def implicit_liver_positions(meshes, solver, factor_reuse=0.0):
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    with softhap.World() as world:
        body = world.add_fem_body(
            mesh, model="corotational", integrator="implicit_euler", linear_solver=solver,
            factor_reuse=factor_reuse,
        )
        body.fix_nodes(range(10))
        for _ in range(3):
            world.step(0.05)
        return body.positions


def test_linear_solvers_agree(meshes):
    reference = implicit_liver_positions(meshes, "ldlt")
    solvers = ["default", "cg"]
    if "SH_FEATURE_CHOLMOD" in softhap.build_features():
        solvers.append("cholmod")
    for solver in solvers:
        scale = np.abs(reference).max()
        np.testing.assert_allclose(implicit_liver_positions(meshes, solver), reference, atol=1e-6 * scale)


def test_factor_reuse_is_validated_and_reported(meshes):
    with softhap.World() as world:
        with pytest.raises(softhap.Error) as info:
            world.add_spring_body([[0, 0, 0]], integrator="implicit_euler", factor_reuse=1.0)
        assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
        assert "factor_reuse" in str(info.value)
    # A linear material's tangent never changes: one factorisation serves every step, and the
    # steps are exactly those of a factorisation per step.
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    positions = []
    for factor_reuse in (0.0, 0.25):
        with softhap.World() as world:
            body = world.add_fem_body(mesh, model="linear", integrator="implicit_euler",
                                      factor_reuse=factor_reuse)
            body.fix_nodes(range(10))
            counts = [world.step(0.05).factorizations for _ in range(4)]
            assert counts == ([1, 1, 1, 1] if factor_reuse == 0.0 else [1, 0, 0, 0])
            positions.append(body.positions)
    np.testing.assert_allclose(positions[1], positions[0], atol=1e-12 * np.abs(positions[0]).max())


def test_unknown_linear_solver_lists_the_valid_ones():
    with softhap.World() as world:
        with pytest.raises(ValueError) as info:
            world.add_spring_body([[0, 0, 0]], linear_solver="lu")
        for name in ("default", "cholmod", "ldlt", "cg"):
            assert name in str(info.value)


# ------------------------------------------------------------------------------------------
# static equilibrium


def test_tripod_static_equilibrium():
    # Node 3 (mass m) hangs below three fixed anchors on a circle of radius r, each linked by a
    # linear spring k of rest length l0 = sqrt(r^2 + h^2). At depth z below the anchors,
    # vertical balance is 3 k (l - l0) z / l = m g with l = sqrt(r^2 + z^2); solved here by
    # bisection.
    k, m, r, h = 20.0, 0.05, 0.1, 0.2
    anchors = [[r * math.cos(a), r * math.sin(a), 0.0] for a in (0.0, 2 * math.pi / 3, 4 * math.pi / 3)]
    l0 = math.hypot(r, h)

    def imbalance(z):
        length = math.hypot(r, z)
        return 3 * k * (length - l0) * z / length - m * G

    lo, hi = h, h + 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if imbalance(mid) < 0 else (lo, mid)
    depth = 0.5 * (lo + hi)

    with softhap.World() as world:
        body = world.add_spring_body(
            anchors + [[0.0, 0.0, -h]], springs=[[0, 3], [1, 3], [2, 3]], stiffness=k, mass=m
        )
        body.fix_nodes([0, 1, 2])
        body.velocities = np.tile([0.1, 0.0, 0.0], (4, 1))
        report = world.solve_static()
        assert isinstance(report, softhap.StaticReport)
        assert report.converged is True
        assert 1 <= report.iterations <= 50
        assert report.residual <= 1e-10
        assert report.residual_history.size == min(report.iterations, 64)
        assert report.residual_history[-1] == pytest.approx(report.residual)
        np.testing.assert_allclose(body.positions[3], [0.0, 0.0, -depth], rtol=1e-8, atol=1e-12)
        np.testing.assert_array_equal(body.positions[:3], anchors)
        np.testing.assert_array_equal(body.velocities, 0.0)


def test_static_tet_matches_textbook_stiffness():
    # Linear material: one solve is exact. Nodes 0, 2, 3 fixed; a force on node 1.
    young, poisson = 1e4, 0.3
    force = np.array([30.0, -10.0, 5.0])
    k = linear_tet_stiffness(UNIT_TET, young, poisson)
    u1 = np.linalg.solve(k[3:6, 3:6], force)
    with softhap.World(gravity=(0, 0, 0)) as world:
        body = world.add_fem_body(
            softhap.Mesh(UNIT_TET, [[0, 1, 2, 3]]), model="linear", young=young, poisson=poisson
        )
        body.fix_nodes([0, 2, 3])
        forces = np.zeros((4, 3))
        forces[1] = force
        body.set_external_forces(forces)
        report = world.solve_static()
        assert report.converged
        np.testing.assert_allclose(body.positions[1], UNIT_TET[1] + u1, rtol=1e-9)
        np.testing.assert_array_equal(body.positions[[0, 2, 3]], UNIT_TET[[0, 2, 3]])
        # at equilibrium the elastic force balances the load on the free node
        np.testing.assert_allclose(body.elastic_forces()[1], -force, rtol=1e-8)


def test_static_without_fixed_nodes_is_a_solver_error_and_changes_nothing():
    with softhap.World() as world:
        body = world.add_fem_body(softhap.Mesh(UNIT_TET, [[0, 1, 2, 3]]), model="linear")
        with pytest.raises(softhap.Error) as info:
            world.solve_static()
        assert info.value.status_name == "SH_ERR_SOLVER"
        assert info.value.report is not None and info.value.report.converged is False
        np.testing.assert_array_equal(body.positions, UNIT_TET)


def unconverged_liver(meshes):
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    world = softhap.World(gravity=(0.0, 0.0, -50.0))
    body = world.add_fem_body(mesh, model="stvk")
    body.fix_nodes(range(10))
    return world, body


def test_static_not_converged_keeps_state(meshes):
    world, body = unconverged_liver(meshes)
    with world:
        before = body.positions
        with pytest.raises(softhap.Error) as info:
            world.solve_static(tolerance=1e-14, max_iterations=1)
        assert info.value.status_name == "SH_ERR_NOT_CONVERGED"
        np.testing.assert_array_equal(body.positions, before)


def test_static_not_converged_error_carries_the_report(meshes):
    world, body = unconverged_liver(meshes)
    with world:
        with pytest.raises(softhap.Error) as info:
            world.solve_static(tolerance=1e-14, max_iterations=1)
        report = info.value.report
        assert isinstance(report, softhap.StaticReport) and report.converged is False
        assert report.iterations >= 1 and report.residual > 1e-14


def test_implicit_failure_carries_the_step_report():
    # CG capped at one iteration cannot solve the stiff implicit body (SH_ERR_NOT_CONVERGED):
    # that body keeps its state while a free particle in the same world still falls one step.
    with softhap.World(gravity=(0, 0, -9.81)) as world:
        particle = world.add_spring_body([[0.0, 0.0, 0.0]], integrator="symplectic_euler")
        body = world.add_spring_body([[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, -1.0]],
                                     springs=[[0, 1], [1, 2], [0, 2]], stiffness=1e6,
                                     integrator="implicit_euler", linear_solver="cg",
                                     cg_max_iterations=1, cg_tolerance=1e-14)
        body.fix_nodes([0])
        before = body.positions
        with pytest.raises(softhap.Error) as info:
            world.step(0.01)
        assert info.value.status_name == "SH_ERR_NOT_CONVERGED"
        assert isinstance(info.value.report, softhap.StepReport)
        assert info.value.report.unstable_body_count == 1
        np.testing.assert_array_equal(body.positions, before)
        assert particle.positions[0, 2] == pytest.approx(-9.81 * 0.01 * 0.01, rel=1e-12)
        with pytest.raises(softhap.Error) as info:
            world.step(-1.0)
        assert info.value.report is None


@pytest.mark.parametrize("bad", [2.5, -(2**32) + 1, 2**31, float("nan")])
def test_integer_arguments_must_be_whole_int32(bad):
    with softhap.World() as world:
        body = world.add_spring_body([[0.0, 0.0, 0.0], [0.0, 0.0, -1.0]], springs=[[0, 1]])
        body.fix_nodes([0])
        with pytest.raises(ValueError) as info:
            world.solve_static(max_iterations=bad)
        assert "max_iterations" in str(info.value)


def test_static_def_values_are_checked_by_the_library():
    with softhap.World() as world:
        body = world.add_spring_body([[0.0, 0.0, 0.0], [0.0, 0.0, -1.0]], springs=[[0, 1]])
        body.fix_nodes([0])
        for bad in ({"tolerance": -1.0}, {"max_iterations": 0}, {"load_steps": 0}):
            with pytest.raises(softhap.Error) as info:
                world.solve_static(**bad)
            assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT", bad
            assert info.value.report is None  # rejected before anything was tried
        with pytest.raises(ValueError):
            world.solve_static(linear_solver="qr")


def test_step_doubling_error_estimate():
    # A 1 kg mass on a 100 N/m spring, backward Euler by hand: (m + h^2 k) v1 = m v0 - h k d0,
    # d1 = d0 + h v1 (d: stretch). The estimate is |one step - two half steps|.
    def backward_euler(d, v, h):
        v = (1.0 * v - h * 100.0 * d) / (1.0 + h * h * 100.0)
        return d + h * v, v

    for flag in (True, False):
        with softhap.World(gravity=(0, 0, 0), error_estimate=flag) as world:
            body = world.add_spring_body([[0, 0, 0], [1, 0, 0]], [[0, 1]], stiffness=100.0,
                                         mass=1.0, integrator="implicit_euler")
            body.fix_nodes([0])
            body.positions = [[0, 0, 0], [1.01, 0, 0]]
            report = world.step(0.02)
            full = backward_euler(0.01, 0.0, 0.02)[0]
            half = backward_euler(*backward_euler(0.01, 0.0, 0.01), 0.01)[0]
            if flag:
                assert report.error_estimate == pytest.approx(abs(full - half), rel=1e-9)
                assert report.error_estimate_seconds > 0.0
            else:
                assert report.error_estimate == -1.0 and report.error_estimate_seconds == 0.0
            assert body.positions[1, 0] == pytest.approx(1.0 + full, abs=1e-14)


_THREADS_SCRIPT = """
import ctypes, os
import numpy as np
import softhap
gomp = ctypes.CDLL("libgomp.so.1")
gomp.omp_set_num_threads(3)
gomp.omp_set_dynamic(0)
mesh = softhap.Mesh.load(sys.argv[1]).transform(0.1)
with softhap.World(gravity=(0.0, 0.0, -9.81)) as world:
    body = world.add_fem_body(mesh, model="stvk", young=3e4, poisson=0.45, integrator="implicit_euler",
                              linear_solver="cholmod")
    x = body.positions
    body.fix_nodes(np.where(x[:, 2] < x[:, 2].min() + 0.1 * np.ptp(x[:, 2]))[0])
    before = len(os.listdir("/proc/self/task"))
    for _ in range(3):
        world.step(0.01)
    after = len(os.listdir("/proc/self/task"))
print(before, after, gomp.omp_get_max_threads(), gomp.omp_get_dynamic())
"""


def test_cholmod_runs_on_the_calling_thread_and_keeps_the_hosts_openmp_settings(meshes):
    """CHOLMOD's OpenMP loops (a fixed num_threads(4) in Debian's CHOLMOD 3) run on the
    calling thread: an implicit liver2 step starts no thread (/proc/self/task), in a fresh
    process so that no earlier test's thread pool hides one, and the host's own OpenMP settings
    on that thread (3 threads, dynamic off) are as it set them afterwards."""
    if "SH_FEATURE_CHOLMOD" not in softhap.build_features():
        pytest.skip("built without CHOLMOD")
    try:
        ctypes.CDLL("libgomp.so.1")
    except OSError:
        pytest.skip("no libgomp here")
    result = run_python(_THREADS_SCRIPT.replace("sys.argv[1]", repr(str(meshes / "liver2.msh"))))
    assert result.returncode == 0, result.stderr
    before, after, threads, dynamic = (int(v) for v in result.stdout.split())
    assert after == before
    assert (threads, dynamic) == (3, 0)
