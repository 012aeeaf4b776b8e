"""softhap.World and Body lifetimes, step reports, warnings, stability policies and errors."""

import gc
import math

import numpy as np
import pytest

import softhap

UNIT_TET = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
WARNING_NAMES = [
    "SH_WARN_UNSTABLE",
    "SH_WARN_SUBSTEPPED",
    "SH_WARN_INVERTED",
    "SH_WARN_CAPACITY",
    "SH_WARN_FORCE_CLAMPED",
    "SH_WARN_LOCKING",
    "SH_WARN_NOT_CONVERGED",
]


def tet_body(world, **kwargs):
    kwargs.setdefault("young", 1e4)
    kwargs.setdefault("poisson", 0.3)
    return world.add_fem_body(softhap.Mesh(UNIT_TET, [[0, 1, 2, 3]]), **kwargs)


def test_empty_world_steps_and_reports():
    with softhap.World() as world:
        assert world.gravity == (0.0, 0.0, -9.81)
        assert world.warnings == {name: 0 for name in WARNING_NAMES}
        report = world.step(0.01)
        assert isinstance(report, softhap.StepReport)
        assert report["wall_seconds"] == report.wall_seconds >= 0.0
        assert report.kinetic_energy == 0.0 and report.unstable_body_count == 0
        assert set(report) == {
            "wall_seconds", "substeps", "dt_critical", "kinetic_energy", "elastic_energy",
            "potential_energy", "warnings", "warning_bits", "unstable_body_count",
            "newton_iterations", "linear_iterations", "newton_residual", "factorize_seconds",
            "solve_seconds", "factorizations", "error_estimate", "error_estimate_seconds",
            "contact_count", "collision_seconds", "contact_substeps", "cut_faces",
            "topology_seconds", "springs_broken",
        }
        with pytest.raises(AttributeError):
            report.no_such_field


def test_step_without_a_report_steps_the_same():
    # report=False returns None and leaves out only the report: two worlds stepped alike, one
    # with reports and one without, hold bit-identical states (a falling, deforming tet).
    states = []
    for report in (True, False):
        with softhap.World() as world:
            body = tet_body(world, integrator="implicit_euler")
            body.fix_nodes([0])
            returned = [world.step(0.01, report=report) for _ in range(20)]
            assert all((r is None) != report for r in returned)
            states.append((body.positions, body.velocities))
    np.testing.assert_array_equal(states[0][0], states[1][0])
    np.testing.assert_array_equal(states[0][1], states[1][1])
    assert np.abs(states[0][0] - UNIT_TET).max() > 1e-6  # it moved
    with softhap.World() as world:
        with pytest.raises(softhap.Error) as info:
            world.step(-1.0, report=False)
        assert info.value.status == softhap.Status.SH_ERR_INVALID_ARGUMENT and info.value.report is None


@pytest.mark.parametrize("dt", [-1.0, math.nan, math.inf])
def test_bad_time_step_is_invalid_argument(dt):
    with softhap.World() as world:
        with pytest.raises(softhap.Error) as info:
            world.step(dt)
        assert info.value.status == softhap.Status.SH_ERR_INVALID_ARGUMENT
        assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
        assert info.value.function == "sh_world_step"
        assert info.value.message
        assert info.value.report is None


def test_bad_gravity():
    with pytest.raises(ValueError):
        softhap.World(gravity=(0.0, -9.81))
    with pytest.raises(softhap.Error) as info:
        softhap.World(gravity=(0.0, 0.0, math.nan))
    assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
    with softhap.World() as world:
        with pytest.raises(softhap.Error):
            world.set_gravity((math.inf, 0.0, 0.0))
        assert world.gravity == (0.0, 0.0, -9.81)


def test_removed_body_is_stale():
    with softhap.World() as world:
        body = tet_body(world)
        other = tet_body(world)
        assert body.is_valid
        world.remove_body(body)
        assert not body.is_valid
        assert other.is_valid
        for use in (lambda: body.positions, lambda: body.info, body.elastic_energy,
                    lambda: body.fix_nodes([0]), lambda: world.remove_body(body)):
            with pytest.raises(softhap.Error) as info:
                use()
            assert info.value.status == softhap.Status.SH_ERR_INVALID_HANDLE
            assert info.value.status_name == "SH_ERR_INVALID_HANDLE"
        # a new body does not revive the stale id
        third = tet_body(world)
        assert third.id != body.id
        assert not body.is_valid
        world.step(1e-4)


def test_body_of_a_closed_world_raises_instead_of_crashing():
    world = softhap.World()
    body = tet_body(world)
    world.close()
    world.close()  # twice is fine
    assert world.closed and not body.is_valid
    uses = [
        lambda: body.positions,
        lambda: setattr(body, "positions", UNIT_TET),
        lambda: body.velocities,
        lambda: body.masses,
        lambda: body.info,
        lambda: body.critical_dt,
        body.elastic_forces,
        body.elastic_energy,
        lambda: body.fix_nodes([0]),
        lambda: body.set_external_forces(None),
        lambda: body.set_node_damping(None),
        lambda: body.set_material([0], young=1e3),
        lambda: body.write_vtu("never.vtu"),
        lambda: world.step(0.01),
        lambda: world.warnings,
        lambda: world.remove_body(body),
        lambda: tet_body(world),
    ]
    for use in uses:
        with pytest.raises(softhap.Error) as info:
            use()
        assert info.value.status == softhap.Status.SH_ERR_INVALID_HANDLE


def test_body_keeps_its_world_alive():
    def make():
        world = softhap.World(gravity=(0.0, 0.0, 0.0))
        return tet_body(world)

    body = make()
    gc.collect()
    assert body.is_valid and not body.world.closed
    np.testing.assert_array_equal(body.positions, UNIT_TET)


def test_remove_body_checks_its_argument():
    with softhap.World() as a, softhap.World() as b:
        body = tet_body(a)
        with pytest.raises(ValueError):
            b.remove_body(body)
        with pytest.raises(TypeError):
            a.remove_body(body.id)
        body.remove()
        assert not body.is_valid


def test_reject_policy_raises_unstable_with_report_and_keeps_state():
    with softhap.World() as world:
        body = tet_body(world, on_unstable="reject")
        particle = world.add_spring_body([[0.0, 0.0, 1.0]], integrator="rk4")
        dt = 5.0 * body.critical_dt
        positions, velocities = body.positions, body.velocities
        with pytest.raises(softhap.Error) as info:
            world.step(dt)
        error = info.value
        assert error.status == softhap.Status.SH_ERR_UNSTABLE
        assert error.status_name == "SH_ERR_UNSTABLE"
        assert error.message
        report = error.report
        assert isinstance(report, softhap.StepReport)
        assert report.unstable_body_count == 1
        assert "SH_WARN_UNSTABLE" in report.warnings
        assert report.warning_bits & (1 << softhap.WarningKind.SH_WARN_UNSTABLE)
        # the rejected body is untouched ...
        np.testing.assert_array_equal(body.positions, positions)
        np.testing.assert_array_equal(body.velocities, velocities)
        # ... and the other bodies still advanced (RK4 is exact for constant gravity)
        assert particle.positions[0, 2] == pytest.approx(1.0 - 9.81 * dt * dt / 2, rel=1e-12)
        assert world.warnings["SH_WARN_UNSTABLE"] == 1
        # a step below the critical step works
        world.step(0.5 * body.critical_dt)
        assert world.warnings["SH_WARN_UNSTABLE"] == 1


def test_substep_policy_splits_large_steps():
    with softhap.World() as world:
        body = tet_body(world, on_unstable="substep")
        dt_crit = body.critical_dt
        report = world.step(5.0 * dt_crit)
        assert report.substeps >= 5
        assert report.dt_critical == pytest.approx(dt_crit, rel=1e-12)
        assert "SH_WARN_SUBSTEPPED" in report.warnings
        assert report.warning_bits & (1 << softhap.WarningKind.SH_WARN_SUBSTEPPED)
        assert world.warnings["SH_WARN_SUBSTEPPED"] >= 1
        assert world.warnings["SH_WARN_UNSTABLE"] == 0
        assert np.all(np.isfinite(body.positions))
        small = world.step(0.5 * dt_crit)
        assert small.substeps == 1 and "SH_WARN_SUBSTEPPED" not in small.warnings


def test_runaway_speed_rolls_back():
    with softhap.World() as world:
        body = world.add_spring_body([[0.0, 0.0, 1.0]], runaway_speed=0.5)
        with pytest.raises(softhap.Error) as info:
            world.step(0.1)  # the particle would reach 0.981 m/s
        assert info.value.status_name == "SH_ERR_UNSTABLE"
        assert info.value.report.unstable_body_count == 1
        np.testing.assert_array_equal(body.positions, [[0.0, 0.0, 1.0]])
        np.testing.assert_array_equal(body.velocities, [[0.0, 0.0, 0.0]])
        world.step(0.01)  # 0.0981 m/s is fine
        assert body.positions[0, 2] < 1.0


def test_step_report_sums_over_bodies():
    m = 1e-3
    with softhap.World() as world:
        a = world.add_spring_body([[0.0, 0.0, 1.0]], mass=m, integrator="rk4")
        b = world.add_spring_body([[0.0, 0.0, 3.0]], mass=2 * m, integrator="rk4")
        report = world.step(0.1)
        v = 9.81 * 0.1
        assert report.kinetic_energy == pytest.approx(0.5 * 3 * m * v * v, rel=1e-12)
        za, zb = a.positions[0, 2], b.positions[0, 2]
        assert report.potential_energy == pytest.approx(9.81 * (m * za + 2 * m * zb), rel=1e-12)


def test_fem_body_vtu_output_loads_back(meshes, tmp_path):
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    with softhap.World() as world:
        body = world.add_fem_body(mesh)
        body.fix_nodes(range(5))
        world.step(0.01)
        path = tmp_path / "frame.vtu"
        body.write_vtu(path)
        text = path.read_text()
        assert "UnstructuredGrid" in text and "velocity" in text
        frame = softhap.Mesh.load(path)
        np.testing.assert_allclose(frame.nodes, body.positions, rtol=1e-12, atol=1e-12)
        np.testing.assert_array_equal(frame.tets, mesh.tets)


def test_spring_body_vtu_output(tmp_path):
    with softhap.World() as world:
        body = world.add_spring_body([[0, 0, 0], [1, 0, 0], [0, 1, 0]], springs=[[0, 1], [1, 2]])
        path = tmp_path / "springs.vtu"
        body.write_vtu(path)
        text = path.read_text()
        assert "UnstructuredGrid" in text and "velocity" in text


def test_write_vtu_to_unwritable_path_is_io_error(tmp_path):
    with softhap.World() as world:
        body = tet_body(world)
        with pytest.raises(softhap.Error) as info:
            body.write_vtu(tmp_path / "no_such_dir" / "x.vtu")
        assert info.value.status_name == "SH_ERR_IO"


def test_repr_and_ids():
    with softhap.World() as world:
        body = tet_body(world)
        assert body.id != 0
        assert "World" in repr(world) and "Body" in repr(body)
    assert "closed" in repr(world)


def test_non_finite_state_is_rolled_back():
    with softhap.World(gravity=(0.0, 0.0, 0.0)) as world:
        body = world.add_spring_body([[0.0, 0.0, 1.0]], mass=1e-3)
        body.set_external_forces([[1e308, 0.0, 0.0]])  # finite, but a = F / m overflows to inf
        with pytest.raises(softhap.Error) as info:
            world.step(0.01)
        assert info.value.status_name == "SH_ERR_UNSTABLE"
        assert info.value.report.unstable_body_count == 1
        np.testing.assert_array_equal(body.positions, [[0.0, 0.0, 1.0]])
        np.testing.assert_array_equal(body.velocities, [[0.0, 0.0, 0.0]])
        assert world.warnings["SH_WARN_UNSTABLE"] == 1
        body.set_external_forces(None)
        world.step(0.01)  # usable again
