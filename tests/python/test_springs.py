"""Mass-spring bodies: free particles against the integrators' exact discrete solutions, a
1-DOF oscillator against the analytic solution, spring laws against their formulas, loads and
damping against closed forms, and the errors for bad definitions."""

import math

import numpy as np
import pytest

import softhap

from textbook import G


def particle(world, z0=2.0, mass=1e-3, **kwargs):
    return world.add_spring_body([[0.0, 0.0, z0]], mass=mass, **kwargs)


# ------------------------------------------------------------------------------------------
# free particle under gravity


def expected_fall(integrator, z0, dt, n):
    """Exact result of n steps of size dt for constant acceleration -g, from rest."""
    if integrator == "forward_euler":  # x += dt v_old: z = z0 - g dt^2 n(n-1)/2
        z = z0 - G * dt * dt * n * (n - 1) / 2.0
    elif integrator == "symplectic_euler":  # x += dt v_new: z = z0 - g dt^2 n(n+1)/2
        z = z0 - G * dt * dt * n * (n + 1) / 2.0
    else:  # midpoint RK2 and RK4 are exact for constant acceleration
        z = z0 - G * (n * dt) ** 2 / 2.0
    return z, -G * n * dt


@pytest.mark.parametrize("integrator", ["forward_euler", "symplectic_euler", "rk2", "rk4"])
def test_free_particle_falls_by_the_integrators_discrete_formula(integrator):
    z0, dt, n, m = 2.0, 0.01, 50, 1e-3
    with softhap.World(gravity=(0, 0, -G)) as world:
        body = particle(world, z0=z0, mass=m, integrator=integrator)
        assert body.node_count == 1
        assert body.info.element_count == 0
        assert body.info.is_fem is False
        assert body.critical_dt == math.inf  # no spring: no stability limit
        for _ in range(n):
            report = world.step(dt)
        z, vz = expected_fall(integrator, z0, dt, n)
        np.testing.assert_allclose(body.positions, [[0.0, 0.0, z]], rtol=0, atol=1e-12)
        np.testing.assert_allclose(body.velocities, [[0.0, 0.0, vz]], rtol=0, atol=1e-12)
        assert report.substeps == 1
        assert report.kinetic_energy == pytest.approx(0.5 * m * vz * vz, rel=1e-12)
        assert report.potential_energy == pytest.approx(m * G * z, rel=1e-12)  # -m g.x
        assert report.elastic_energy == 0.0
        assert report.unstable_body_count == 0
        assert report.warnings == frozenset() and report.warning_bits == 0


def test_particle_with_horizontal_velocity_follows_a_parabola():
    dt, n = 0.005, 80
    with softhap.World() as world:
        body = particle(world, z0=0.0, integrator="rk4")
        body.velocities = [[1.5, -0.5, 3.0]]
        for _ in range(n):
            world.step(dt)
        t = n * dt
        expected = [1.5 * t, -0.5 * t, 3.0 * t - G * t * t / 2.0]
        np.testing.assert_allclose(body.positions[0], expected, rtol=0, atol=1e-12)


def test_changing_gravity_mid_run():
    with softhap.World() as world:
        body = particle(world, integrator="rk4")
        world.step(0.1)
        world.gravity = (0.0, 0.0, 0.0)
        assert world.gravity == (0.0, 0.0, 0.0)
        v = body.velocities
        x = body.positions
        world.step(0.1)
        np.testing.assert_allclose(body.velocities, v, atol=1e-15)
        np.testing.assert_allclose(body.positions, x + 0.1 * v, atol=1e-14)


def test_external_force_accelerates_particle_and_none_clears_it():
    m, f, dt, n = 0.002, 0.01, 0.01, 30
    with softhap.World(gravity=(0, 0, 0)) as world:
        body = particle(world, z0=0.0, mass=m, integrator="rk4")
        body.set_external_forces([[f, 0.0, 0.0]])
        for _ in range(n):
            world.step(dt)
        t = n * dt
        np.testing.assert_allclose(body.positions[0], [f * t * t / (2 * m), 0, 0], atol=1e-12)
        np.testing.assert_allclose(body.velocities[0], [f * t / m, 0, 0], atol=1e-12)
        body.set_external_forces(None)
        v = body.velocities
        world.step(dt)
        np.testing.assert_allclose(body.velocities, v, atol=1e-15)  # force cleared
        with pytest.raises(ValueError):
            body.set_external_forces([[1.0, 2.0]])


def test_per_node_damping_decays_velocity_exponentially():
    c, dt, n = 3.0, 1e-3, 500
    with softhap.World(gravity=(0, 0, 0)) as world:
        body = particle(world, z0=0.0, integrator="rk4")
        body.velocities = [[1.0, 0.0, 0.0]]
        body.set_node_damping(c)
        for _ in range(n):
            world.step(dt)
        t = n * dt
        assert body.velocities[0, 0] == pytest.approx(math.exp(-c * t), rel=1e-9)
        assert body.positions[0, 0] == pytest.approx((1 - math.exp(-c * t)) / c, rel=1e-9)
        body.set_node_damping(None)
        v = body.velocities
        world.step(dt)
        np.testing.assert_allclose(body.velocities, v, rtol=1e-14)


def test_mass_damping_and_node_damping_add_up():
    alpha, c, dt, n = 2.0, 3.0, 1e-3, 400
    with softhap.World(gravity=(0, 0, 0)) as world:
        body = particle(world, z0=0.0, integrator="rk4", damping_mass=alpha)
        body.velocities = [[0.0, 2.0, 0.0]]
        body.set_node_damping([c])
        for _ in range(n):
            world.step(dt)
        assert body.velocities[0, 1] == pytest.approx(2.0 * math.exp(-(alpha + c) * n * dt), rel=1e-9)


# ------------------------------------------------------------------------------------------
# 1-DOF linear oscillator: node 0 fixed, node 1 of mass m on a spring k along x


def oscillator(world, k, m, length, amplitude, damping=None):
    body = world.add_spring_body(
        [[0.0, 0.0, 0.0], [length, 0.0, 0.0]],
        springs=[[0, 1]],
        law="linear",
        stiffness=k,
        damping=damping,
        mass=m,
        integrator="rk4",
    )
    body.fix_nodes([0])
    body.positions = [[0.0, 0.0, 0.0], [length + amplitude, 0.0, 0.0]]
    return body


def test_linear_oscillator_matches_analytic_solution():
    k, m, length, amplitude = 50.0, 0.02, 0.1, 1e-3
    omega = math.sqrt(k / m)  # 50 rad/s
    dt, n = 1e-4, 1500  # 0.15 s, more than one period
    with softhap.World(gravity=(0, 0, 0)) as world:
        body = oscillator(world, k, m, length, amplitude)
        assert body.info.element_count == 1
        assert body.info.fixed_node_count == 1
        energy = 0.5 * k * amplitude**2
        assert body.elastic_energy() == pytest.approx(energy, rel=1e-12)
        worst = 0.0
        for i in range(1, n + 1):
            report = world.step(dt)
            x = body.positions[1, 0] - length
            worst = max(worst, abs(x - amplitude * math.cos(omega * i * dt)))
            if i % 100 == 0:
                assert report.kinetic_energy + report.elastic_energy == pytest.approx(energy, rel=1e-6)
        assert worst < 1e-6 * amplitude
        np.testing.assert_array_equal(body.positions[0], [0.0, 0.0, 0.0])  # fixed node
        np.testing.assert_array_equal(body.velocities[0], [0.0, 0.0, 0.0])


def test_damped_linear_oscillator_matches_analytic_solution():
    k, m, length, amplitude, zeta = 50.0, 0.02, 0.1, 1e-3, 0.1
    omega = math.sqrt(k / m)
    c = 2.0 * zeta * math.sqrt(k * m)  # spring damping (N s/m) for damping ratio zeta
    omega_d = omega * math.sqrt(1.0 - zeta * zeta)
    dt, n = 1e-4, 1500
    with softhap.World(gravity=(0, 0, 0)) as world:
        body = oscillator(world, k, m, length, amplitude, damping=c)
        worst = 0.0
        for i in range(1, n + 1):
            world.step(dt)
            t = i * dt
            exact = amplitude * math.exp(-zeta * omega * t) * (
                math.cos(omega_d * t) + zeta / math.sqrt(1 - zeta * zeta) * math.sin(omega_d * t)
            )
            worst = max(worst, abs(body.positions[1, 0] - length - exact))
        assert worst < 1e-6 * amplitude


# ------------------------------------------------------------------------------------------
# static spring forces: two free nodes, node 1 at distance l0 (1 + d) along x


def spring_pair(world, strain, l0=0.2, **law):
    body = world.add_spring_body([[0.0, 0.0, 0.0], [l0, 0.0, 0.0]], springs=[[0, 1]], **law)
    body.positions = [[0.0, 0.0, 0.0], [l0 * (1.0 + strain), 0.0, 0.0]]
    return body


def assert_tension(body, tension):
    """Tension T > 0 pulls the two nodes together: node 0 gets +T x, node 1 gets -T x."""
    expected = [[tension, 0.0, 0.0], [-tension, 0.0, 0.0]]
    np.testing.assert_allclose(body.elastic_forces(), expected, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("strain", [0.1, -0.05])
def test_linear_law_force_and_energy(strain):
    k, l0 = 40.0, 0.2
    with softhap.World() as world:
        body = spring_pair(world, strain, l0, law="linear", stiffness=k)
        assert_tension(body, k * l0 * strain)
        assert body.elastic_energy() == pytest.approx(0.5 * k * (l0 * strain) ** 2, rel=1e-12)


@pytest.mark.parametrize("strain", [0.3, -0.2])
def test_cubic_law_force_and_energy(strain):
    l1, l2, l0 = 5.0, 2.0, 0.2
    with softhap.World() as world:
        body = spring_pair(world, strain, l0, law="cubic", lambda1=l1, lambda2=l2)
        assert_tension(body, l1 * strain**3 + l2 * strain)
        # energy = integral of T dl = l0 (lambda1 d^4 / 4 + lambda2 d^2 / 2)
        energy = l0 * (l1 * strain**4 / 4.0 + l2 * strain**2 / 2.0)
        assert body.elastic_energy() == pytest.approx(energy, rel=1e-12)


@pytest.mark.parametrize("strain", [0.5, -0.25])
def test_hyperbolic_law_force(strain):
    a, b, l0 = 2.0, 0.01, 0.2
    dx = l0 * strain
    with softhap.World() as world:
        body = spring_pair(world, strain, l0, law="hyperbolic", a=a, b=b)
        assert_tension(body, dx / (a * abs(dx) + b))


def test_table_law_passes_through_rows_and_reproduces_linear_data():
    rows = [[-0.5, -50.0], [0.0, 0.0], [0.5, 50.0], [1.0, 100.0]]
    with softhap.World() as world:
        for strain, force in [(0.5, 50.0), (0.25, 25.0), (-0.3, -30.0), (0.8, 80.0)]:
            body = spring_pair(world, strain, law="table", table=rows)
            assert_tension(body, force)
    curved = np.array([[0.0, 0.0], [0.1, 1.0], [0.2, 4.0], [0.3, 9.0]])
    with softhap.World() as world:
        assert_tension(spring_pair(world, 0.2, law="table", table=curved), 4.0)
        between = -spring_pair(world, 0.15, law="table", table=curved).elastic_forces()[1, 0]
        assert 1.0 < between < 4.0  # monotone interpolation stays between the rows


def test_table_is_copied_at_creation():
    rows = np.array([[0.0, 0.0], [1.0, 10.0]])
    with softhap.World() as world:
        body = spring_pair(world, 0.5, law="table", table=rows)
        rows[:] = 0.0
        assert_tension(body, 5.0)


def test_parameters_of_another_law_are_rejected():
    with softhap.World() as world:
        with pytest.raises(ValueError, match="lambda1"):
            world.add_spring_body([[0, 0, 0], [1, 0, 0]], [[0, 1]], law="linear", lambda1=1.0)
        with pytest.raises(ValueError, match="stiffness"):
            world.add_spring_body([[0, 0, 0], [1, 0, 0]], [[0, 1]], law="cubic", stiffness=1.0)
        with pytest.raises(ValueError) as info:
            world.add_spring_body([[0, 0, 0], [1, 0, 0]], [[0, 1]], law="quadratic")
        for name in ("linear", "cubic", "hyperbolic", "table"):
            assert name in str(info.value)


# ------------------------------------------------------------------------------------------
# bodies from meshes, masses


def test_spring_body_from_mesh_uses_nodes_and_edges(meshes):
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    with softhap.World() as world:
        body = world.add_spring_body(mesh, mass=2e-3)
        info = body.info
        assert info.node_count == 181
        assert info.element_count == mesh.info.edge_count
        assert info.is_fem is False
        np.testing.assert_array_equal(body.positions, mesh.nodes)
        np.testing.assert_array_equal(body.masses, np.full(181, 2e-3))
        assert info.total_mass == pytest.approx(181 * 2e-3, rel=1e-12)
        # at rest length: no force, no energy
        np.testing.assert_array_equal(body.elastic_forces(), np.zeros((181, 3)))
        assert body.elastic_energy() == 0.0


def test_spring_body_from_mesh_with_explicit_springs(meshes):
    mesh = softhap.Mesh.load(meshes / "single_tetra.msh")
    with softhap.World() as world:
        body = world.add_spring_body(mesh, springs=[[0, 1], [2, 3]])
        assert body.info.element_count == 2
        assert body.node_count == 4


def test_per_node_masses():
    masses = [1e-3, 2e-3, 3e-3]
    with softhap.World() as world:
        body = world.add_spring_body(
            [[0, 0, 0], [1, 0, 0], [0, 1, 0]], springs=[[0, 1], [1, 2]], mass=masses
        )
        np.testing.assert_array_equal(body.masses, masses)
        assert body.info.total_mass == pytest.approx(6e-3)
        with pytest.raises(ValueError):
            world.add_spring_body([[0, 0, 0], [1, 0, 0]], mass=[1e-3, 1e-3, 1e-3])


@pytest.mark.parametrize(
    "nodes, springs, kwargs",
    [
        ([[0, 0, 0], [1, 0, 0]], [[0, 0]], {}),  # repeated node
        ([[0, 0, 0], [0, 0, 0]], [[0, 1]], {}),  # zero rest length
        ([[0, 0, 0], [1, 0, 0]], [[0, 2]], {}),  # index out of range
        ([[0, 0, 0], [1, 0, 0]], [[0, 1]], {"mass": 0.0}),  # non-positive mass
        ([[0, 0, 0], [1, 0, 0]], [[0, 1]], {"mass": [1e-3, -1e-3]}),
        ([[0, 0, 0], [1, 0, 0]], [[0, 1]], {"stiffness": -1.0}),
        ([[0, 0, 0], [1, 0, 0]], [[0, 1]], {"damping": -1.0}),
        ([[0, 0, 0], [1, 0, 0]], [[0, 1]], {"law": "cubic", "lambda1": 1.0, "lambda2": 0.0}),
        ([[0, 0, 0], [1, 0, 0]], [[0, 1]], {"law": "hyperbolic", "a": 1.0, "b": 0.0}),
        ([[0, 0, 0], [1, 0, 0]], [[0, 1]], {"law": "table", "table": [[0.0, 0.0]]}),
        ([[0, 0, 0], [1, 0, 0]], [[0, 1]], {"law": "table", "table": [[0.0, 0.0], [0.0, 1.0]]}),
        ([[0, 0, 0], [1, 0, np.inf]], [[0, 1]], {}),  # not finite
    ],
)
def test_invalid_spring_definitions_are_invalid_argument(nodes, springs, kwargs):
    with softhap.World() as world:
        with pytest.raises(softhap.Error) as info:
            world.add_spring_body(nodes, springs, **kwargs)
        assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT", info.value
        assert info.value.message


def test_spring_body_shape_errors_are_value_errors():
    with softhap.World() as world:
        with pytest.raises(ValueError):
            world.add_spring_body([0.0, 0.0, 0.0])
        with pytest.raises(ValueError):
            world.add_spring_body([[0, 0, 0], [1, 0, 0]], springs=[0, 1])
        with pytest.raises(ValueError):
            world.add_spring_body([[0, 0, 0], [1, 0, 0]], springs=[[0, 1]], law="table", table=[1, 2, 3])


def test_spring_defaults_are_the_documented_c_defaults():
    # sh_spring_body_def_default: linear springs k = 100 N/m, node mass 1 g
    with softhap.World() as world:
        body = spring_pair(world, 0.1, l0=0.2)
        assert_tension(body, 100.0 * 0.02)
        np.testing.assert_array_equal(body.masses, [1e-3, 1e-3])
