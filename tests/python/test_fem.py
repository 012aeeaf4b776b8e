"""FEM bodies: lumped masses, forces of a hand-derived uniaxial stretch of one tet, rest state,
rotation invariance, free fall, damping, boundary conditions, materials and stability limits."""

import math

import numpy as np
import pytest

import softhap

from textbook import G, UNIT_TET, lame, linear_tet_stiffness

MODELS = ["linear", "stvk", "corotational", "neohookean"]


def unit_tet_mesh(scale=1.0):
    return softhap.Mesh(UNIT_TET * scale, [[0, 1, 2, 3]])


def tet_volumes(nodes, tets):
    x = nodes[tets]
    edges = np.stack([x[:, 1] - x[:, 0], x[:, 2] - x[:, 0], x[:, 3] - x[:, 0]], axis=1)
    return np.linalg.det(edges) / 6.0


def lumped_masses(nodes, tets, density):
    masses = np.zeros(len(nodes))
    quarter = density * tet_volumes(nodes, tets) / 4.0
    for corner in range(4):
        np.add.at(masses, tets[:, corner], quarter)
    return masses


# ------------------------------------------------------------------------------------------
# masses


def test_lumped_masses_sum_to_density_times_volume(meshes):
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    with softhap.World() as world:
        body = world.add_fem_body(mesh, density=1000.0)
        masses = body.masses
        assert masses.shape == (181,)
        assert masses.sum() == pytest.approx(1000.0 * mesh.info.volume, rel=1e-12)
        np.testing.assert_allclose(masses, lumped_masses(mesh.nodes, mesh.tets, 1000.0), rtol=1e-12)
        info = body.info
        assert info.is_fem is True
        assert (info.node_count, info.element_count) == (181, 596)
        assert info.total_mass == pytest.approx(1000.0 * mesh.info.volume, rel=1e-12)
        assert info.fixed_node_count == 0


def test_orphan_nodes_have_no_mass_and_do_not_move(meshes):
    mesh = softhap.Mesh.load(meshes / "raptorTetra_8418.vtu")
    orphans = np.setdiff1d(np.arange(mesh.node_count), np.unique(mesh.tets))
    assert orphans.size == 3
    with softhap.World() as world:
        body = world.add_fem_body(mesh, young=1e4)
        masses = body.masses
        np.testing.assert_array_equal(masses[orphans], 0.0)
        assert np.all(np.delete(masses, orphans) > 0)
        before = body.positions
        world.step(min(1e-4, body.critical_dt))
        after = body.positions
        np.testing.assert_array_equal(after[orphans], before[orphans])
        assert np.any(after != before)


def test_set_material_recomputes_masses(meshes):
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    nodes, tets = mesh.nodes, mesh.tets
    region = np.arange(0, 596, 2)
    with softhap.World() as world:
        body = world.add_fem_body(mesh, density=1000.0)
        body.set_material(region, model="corotational", young=8000.0, poisson=0.4, density=2500.0)
        densities = np.full(596, 1000.0)
        densities[region] = 2500.0
        expected = np.zeros(181)
        quarter = densities * tet_volumes(nodes, tets) / 4.0
        for corner in range(4):
            np.add.at(expected, tets[:, corner], quarter)
        np.testing.assert_allclose(body.masses, expected, rtol=1e-12)


def test_set_material_errors(meshes):
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    with softhap.World() as world:
        body = world.add_fem_body(mesh)
        for bad in ({"young": -1.0}, {"poisson": 0.5}, {"density": 0.0}, {"young": math.nan}):
            with pytest.raises(softhap.Error) as info:
                body.set_material([0, 1], **bad)
            assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT", bad
        with pytest.raises(softhap.Error) as info:
            body.set_material([596])  # element index out of range
        assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
        with pytest.raises(ValueError, match="neohookean"):
            body.set_material([0], model="mooney")


@pytest.mark.parametrize(
    "kwargs",
    [{"young": -1.0}, {"young": 0.0}, {"poisson": 0.5}, {"poisson": -1.0}, {"density": -5.0},
     {"damping_mass": -1.0}, {"young": math.inf}],
)
def test_invalid_fem_definition_is_invalid_argument(kwargs):
    with softhap.World() as world:
        with pytest.raises(softhap.Error) as info:
            world.add_fem_body(unit_tet_mesh(), **kwargs)
        assert info.value.status == softhap.Status.SH_ERR_INVALID_ARGUMENT
        assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
        assert info.value.message


def test_unknown_names_list_the_valid_ones():
    mesh = unit_tet_mesh()
    with softhap.World() as world:
        cases = [
            ({"model": "hooke"}, ["linear", "stvk", "corotational", "neohookean"]),
            ({"integrator": "leapfrog"}, ["forward_euler", "symplectic_euler", "rk2", "rk4"]),
            ({"on_unstable": "ignore"}, ["reject", "substep"]),
        ]
        for kwargs, names in cases:
            with pytest.raises(ValueError) as info:
                world.add_fem_body(mesh, **kwargs)
            for name in names:
                assert name in str(info.value)


# ------------------------------------------------------------------------------------------
# elastic forces


@pytest.mark.parametrize("model", MODELS)
def test_rest_shape_has_no_force_and_no_energy(meshes, model):
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    with softhap.World() as world:
        young = 3000.0
        body = world.add_fem_body(mesh, model=model, young=young)
        # round-off scales: a stress of E acting on the mesh (force E h^2, energy E V)
        h = mesh.info.volume ** (1.0 / 3.0)
        force_scale, energy_scale = young * h * h, young * mesh.info.volume
        forces = body.elastic_forces()
        assert forces.shape == (181, 3)
        np.testing.assert_allclose(forces, 0.0, atol=1e-12 * force_scale)
        assert body.elastic_energy() == pytest.approx(0.0, abs=1e-14 * energy_scale)
        # a rigid translation is still force free
        body.positions = mesh.nodes + [0.3, -0.2, 1.0]
        np.testing.assert_allclose(body.elastic_forces(), 0.0, atol=1e-12 * force_scale)


def uniaxial_forces(model, young, poisson, strain):
    """Nodal forces on the unit right tet stretched by (1 + strain) along x, from
    H = -V0 P Bm^T with Bm = I, V0 = 1/6 (columns of H are f1..f3, f0 = -(f1+f2+f3))."""
    lam, mu = lame(young, poisson)
    if model in ("linear", "corotational"):  # R = I for a pure stretch: both give P = sigma
        e = strain
        p = np.diag([(lam + 2 * mu) * e, lam * e, lam * e])
        energy = (lam / 2 + mu) * e * e / 6.0
    elif model == "stvk":  # E = (F^T F - I)/2, S = lam tr(E) I + 2 mu E, P = F S
        e = strain + strain * strain / 2.0
        f = np.diag([1.0 + strain, 1.0, 1.0])
        p = f @ np.diag([(lam + 2 * mu) * e, lam * e, lam * e])
        energy = (lam / 2 + mu) * e * e / 6.0
    h = -p / 6.0
    forces = np.zeros((4, 3))
    forces[1:] = h.T
    forces[0] = -forces[1:].sum(axis=0)
    return forces, energy


@pytest.mark.parametrize("model", ["linear", "stvk", "corotational"])
@pytest.mark.parametrize("strain", [0.01, -0.02, 0.2])
def test_uniaxial_stretch_of_one_tet_matches_hand_derivation(model, strain):
    young, poisson = 1.0e4, 0.3
    with softhap.World() as world:
        body = world.add_fem_body(unit_tet_mesh(), model=model, young=young, poisson=poisson)
        stretched = UNIT_TET.copy()
        stretched[:, 0] *= 1.0 + strain
        body.positions = stretched
        expected, energy = uniaxial_forces(model, young, poisson, strain)
        np.testing.assert_allclose(body.elastic_forces(), expected, rtol=1e-10, atol=1e-10)
        assert body.elastic_energy() == pytest.approx(energy, rel=1e-10)


def test_neohookean_resists_stretch_and_compression():
    with softhap.World() as world:
        body = world.add_fem_body(unit_tet_mesh(), model="neohookean", young=1e4, poisson=0.3)
        for strain, sign in [(0.05, -1.0), (-0.05, 1.0)]:
            stretched = UNIT_TET.copy()
            stretched[:, 0] *= 1.0 + strain
            body.positions = stretched
            forces = body.elastic_forces()
            assert np.sign(forces[1, 0]) == sign  # node 1 pushed back toward rest
            np.testing.assert_allclose(forces.sum(axis=0), 0.0, atol=1e-9)  # internal forces
            assert body.elastic_energy() > 0


def rotation_z(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@pytest.mark.parametrize("model", ["stvk", "corotational", "neohookean"])
def test_rotation_invariant_models_have_no_force_under_rigid_rotation(model):
    with softhap.World() as world:
        body = world.add_fem_body(unit_tet_mesh(), model=model, young=1e4, poisson=0.3)
        body.positions = UNIT_TET @ rotation_z(math.pi / 2).T
        np.testing.assert_allclose(body.elastic_forces(), 0.0, atol=1e-9)
        assert body.elastic_energy() == pytest.approx(0.0, abs=1e-9)


def rotation_about(axis, angle):
    """Rodrigues' rotation matrix."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * cross + (1.0 - math.cos(angle)) * cross @ cross


def test_corotational_forces_are_frame_indifferent_across_large_turns(meshes):
    # A body keeps its elements' rotations from one force or energy pass to the next as a warm
    # start. Whatever it kept, the law is frame-indifferent: the deformed liver turned by Q has
    # forces Q f and the same energy, through turns of up to 179 degrees between evaluations
    # (where the kept rotations are far from the new ones) and back.
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    with softhap.World() as world:
        body = world.add_fem_body(mesh, model="corotational", young=1e4, poisson=0.45)
        rest = body.positions
        centre = rest.mean(axis=0)
        rng = np.random.default_rng(7)
        strain = np.eye(3) + 0.15 * rng.standard_normal((3, 3))
        deformed = centre + (rest - centre) @ strain.T + 0.002 * rng.standard_normal(rest.shape)
        body.positions = deformed
        reference, energy = body.elastic_forces(), body.elastic_energy()
        scale = np.abs(reference).max()
        for axis, angle in [((0, 0, 1), 0.3), ((1, 2, 0), 1.7), ((1, -1, 3), 3.12), ((0, 1, 0), -2.5), ((0, 0, 1), 0.0)]:
            q = rotation_about(axis, angle)
            body.positions = centre + (deformed - centre) @ q.T
            np.testing.assert_allclose(body.elastic_forces(), reference @ q.T, rtol=0, atol=1e-9 * scale)
            assert body.elastic_energy() == pytest.approx(energy, rel=1e-10)


def test_linear_model_is_not_rotation_invariant():
    # small-strain elasticity sees a 90 degree rotation as strain: F + F^T - 2I = -2 diag(1, 1, 0)
    with softhap.World() as world:
        body = world.add_fem_body(unit_tet_mesh(), model="linear", young=1e4, poisson=0.3)
        body.positions = UNIT_TET @ rotation_z(math.pi / 2).T
        assert np.abs(body.elastic_forces()).max() > 1.0


# ------------------------------------------------------------------------------------------
# dynamics


def test_free_fall_of_a_tet_is_rigid_and_exact_with_rk4():
    dt, n = 1e-3, 200
    with softhap.World() as world:
        body = world.add_fem_body(unit_tet_mesh(0.1), integrator="rk4", young=3000.0)
        start = body.positions
        for _ in range(n):
            report = world.step(dt)
        t = n * dt
        np.testing.assert_allclose(body.positions, start + [0.0, 0.0, -G * t * t / 2], atol=1e-10)
        np.testing.assert_allclose(body.velocities, np.tile([0.0, 0.0, -G * t], (4, 1)), atol=1e-10)
        assert report.elastic_energy == pytest.approx(0.0, abs=1e-12)
        mass = body.info.total_mass
        assert mass == pytest.approx(1000.0 * 0.1**3 / 6.0, rel=1e-12)
        assert report.kinetic_energy == pytest.approx(0.5 * mass * (G * t) ** 2, rel=1e-9)


def test_rayleigh_mass_damping_gives_terminal_velocity_and_stiffness_damping_ignores_translation():
    alpha, dt, n = 2.0, 1e-3, 500
    with softhap.World() as world:
        body = world.add_fem_body(
            unit_tet_mesh(0.1), integrator="rk4", damping_mass=alpha, damping_stiffness=0.01
        )
        for _ in range(n):
            world.step(dt)
        t = n * dt
        vz = -(G / alpha) * (1.0 - math.exp(-alpha * t))  # m v' = -m g - alpha m v
        np.testing.assert_allclose(body.velocities[:, 2], vz, rtol=1e-8)
        np.testing.assert_allclose(body.velocities[:, :2], 0.0, atol=1e-10)


def test_fixed_nodes_do_not_move_and_released_nodes_do(meshes):
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    fixed = np.arange(10)
    with softhap.World() as world:
        body = world.add_fem_body(mesh, model="corotational", young=3000.0)
        body.fix_nodes(fixed)
        assert body.info.fixed_node_count == 10
        start = body.positions
        for _ in range(20):
            world.step(1e-3)
        now = body.positions
        np.testing.assert_array_equal(now[fixed], start[fixed])
        np.testing.assert_array_equal(body.velocities[fixed], 0.0)
        assert now[10:, 2].mean() < start[10:, 2].mean()  # the rest sags

        body.release_nodes(fixed[:5])
        assert body.info.fixed_node_count == 5
        for _ in range(5):
            world.step(1e-3)
        assert np.any(body.positions[:5] != start[:5])
        np.testing.assert_array_equal(body.positions[5:10], start[5:10])


def test_fixed_nodes_keep_zero_velocity_when_velocities_are_set():
    with softhap.World() as world:
        body = world.add_fem_body(unit_tet_mesh())
        body.fix_nodes(0)
        body.velocities = np.ones((4, 3))
        velocities = body.velocities
        np.testing.assert_array_equal(velocities[0], 0.0)
        np.testing.assert_array_equal(velocities[1:], 1.0)


def test_prescribed_position_is_reached_after_one_step_and_held():
    target = np.array([[0.05, 0.02, -0.03]])
    with softhap.World() as world:
        body = world.add_fem_body(unit_tet_mesh(0.1), young=3000.0)
        body.prescribe_positions([0], target)
        assert body.info.fixed_node_count == 1
        world.step(1e-3)
        np.testing.assert_allclose(body.positions[0], target[0], atol=1e-14)
        for _ in range(10):
            world.step(1e-3)
        np.testing.assert_allclose(body.positions[0], target[0], atol=1e-14)
        with pytest.raises(ValueError):
            body.prescribe_positions([1, 2], target)  # 2 indices, 1 position


def test_boundary_condition_errors():
    with softhap.World() as world:
        body = world.add_fem_body(unit_tet_mesh())
        for call in (lambda: body.fix_nodes([4]), lambda: body.fix_nodes([-1]),
                     lambda: body.release_nodes([7]),
                     lambda: body.prescribe_positions([9], [[0.0, 0.0, 0.0]]),
                     lambda: body.prescribe_positions([0], [[0.0, math.nan, 0.0]])):
            with pytest.raises(softhap.Error) as info:
                call()
            assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
        with pytest.raises(ValueError):
            body.fix_nodes([0.5])


def test_state_setters_check_shapes_and_values():
    with softhap.World() as world:
        body = world.add_fem_body(unit_tet_mesh())
        with pytest.raises(ValueError):
            body.positions = np.zeros((3, 3))
        with pytest.raises(ValueError):
            body.velocities = np.zeros(12)
        bad = UNIT_TET.copy()
        bad[2, 1] = math.nan
        with pytest.raises(softhap.Error) as info:
            body.positions = bad
        assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
        with pytest.raises(softhap.Error) as info:
            body.velocities = np.full((4, 3), math.inf)
        assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
        np.testing.assert_array_equal(body.positions, UNIT_TET)  # nothing changed
        # reads are copies
        positions = body.positions
        positions[:] = 5.0
        np.testing.assert_array_equal(body.positions, UNIT_TET)


# ------------------------------------------------------------------------------------------
# critical time step


def test_critical_dt_scales_with_size_and_wave_speed():
    # dt_crit ~ h / c with c = sqrt((lambda + 2 mu) / rho): doubling the size doubles it,
    # quadrupling Young's modulus halves it, quadrupling the density doubles it.
    with softhap.World() as world:
        base = world.add_fem_body(unit_tet_mesh(), young=1e4, poisson=0.3).critical_dt
        assert 0 < base < math.inf
        big = world.add_fem_body(unit_tet_mesh(2.0), young=1e4, poisson=0.3).critical_dt
        stiff = world.add_fem_body(unit_tet_mesh(), young=4e4, poisson=0.3).critical_dt
        heavy = world.add_fem_body(unit_tet_mesh(), young=1e4, poisson=0.3, density=4000.0).critical_dt
        assert big == pytest.approx(2.0 * base, rel=1e-9)
        assert stiff == pytest.approx(0.5 * base, rel=1e-9)
        assert heavy == pytest.approx(2.0 * base, rel=1e-9)


def linear_tet_frequency_max(nodes, young, poisson, density):
    """Largest natural frequency (rad/s) of one linear tetrahedron with the textbook stiffness
    and lumped mass rho V / 4 per node."""
    volume = abs(np.linalg.det((nodes[1:] - nodes[0]).T)) / 6.0
    k = linear_tet_stiffness(nodes, young, poisson)
    return math.sqrt(np.linalg.eigvalsh(k / (density * volume / 4.0)).max())


@pytest.mark.parametrize("scale", [1.0, 0.05])
def test_critical_dt_is_the_leapfrog_limit_of_the_element(scale):
    # The stability limit of symplectic Euler (leapfrog) is dt = 2 / omega_max, and RK4's
    # reaches 2 sqrt(2) / omega_max on the imaginary axis.
    young, poisson, density = 1e4, 0.3, 1000.0
    omega = linear_tet_frequency_max(UNIT_TET * scale, young, poisson, density)
    with softhap.World() as world:
        leapfrog = world.add_fem_body(
            unit_tet_mesh(scale), young=young, poisson=poisson, integrator="symplectic_euler"
        )
        rk4 = world.add_fem_body(unit_tet_mesh(scale), young=young, poisson=poisson, integrator="rk4")
        assert leapfrog.critical_dt == pytest.approx(2.0 / omega, rel=1e-9)
        assert rk4.critical_dt == pytest.approx(2.0 * math.sqrt(2.0) / omega, rel=1e-9)


def test_steps_below_the_critical_dt_stay_bounded():
    with softhap.World(gravity=(0.0, 0.0, 0.0)) as world:
        body = world.add_fem_body(
            unit_tet_mesh(0.1), model="corotational", young=1e4, poisson=0.3,
            integrator="symplectic_euler", on_unstable="reject",
        )
        start = UNIT_TET * 0.1
        perturbed = start.copy()
        perturbed[1, 0] += 1e-4
        body.positions = perturbed
        dt = 0.9 * body.critical_dt
        worst = 0.0
        for _ in range(3000):
            report = world.step(dt)
            assert report.substeps == 1
            worst = max(worst, np.abs(body.positions - start).max())
        assert worst < 1e-2  # bounded oscillation, not exponential growth


def test_neohookean_matches_linear_elasticity_at_small_strain():
    strain = 1e-6
    expected, _ = uniaxial_forces("linear", 1e4, 0.3, strain)
    with softhap.World() as world:
        body = world.add_fem_body(unit_tet_mesh(), model="neohookean", young=1e4, poisson=0.3)
        stretched = UNIT_TET.copy()
        stretched[:, 0] *= 1.0 + strain
        body.positions = stretched
        np.testing.assert_allclose(body.elastic_forces(), expected, rtol=1e-4, atol=1e-6 * np.abs(expected).max())


def test_stiffness_damping_lowers_the_critical_dt():
    # Central differences with damping ratio xi = beta omega / 2 are stable up to
    # dt = 2 / omega (sqrt(1 + xi^2) - xi) (Belytschko, Liu & Moran, Nonlinear FE, 6.3).
    beta = 0.02
    omega = linear_tet_frequency_max(UNIT_TET, 1e4, 0.3, 1000.0)
    xi = beta * omega / 2.0
    with softhap.World() as world:
        body = world.add_fem_body(unit_tet_mesh(), young=1e4, poisson=0.3, damping_stiffness=beta)
        assert body.critical_dt == pytest.approx(2.0 / omega * (math.sqrt(1 + xi * xi) - xi), rel=1e-9)


def total_energy_after(beta, steps=200):
    with softhap.World(gravity=(0.0, 0.0, 0.0)) as world:
        body = world.add_fem_body(
            unit_tet_mesh(), model="corotational", young=1e4, poisson=0.3, damping_stiffness=beta
        )
        stretched = UNIT_TET.copy()
        stretched[1, 0] += 0.01
        body.positions = stretched
        initial = body.elastic_energy()
        dt = 0.5 * body.critical_dt
        for _ in range(steps):
            report = world.step(dt)
        return (report.kinetic_energy + report.elastic_energy) / initial


def test_stiffness_damping_dissipates_vibration():
    assert total_energy_after(0.0) > 0.5  # symplectic Euler: no dissipation
    assert total_energy_after(0.05) < 0.05


def test_inverted_element_raises_a_warning():
    with softhap.World(gravity=(0.0, 0.0, 0.0)) as world:
        body = world.add_fem_body(unit_tet_mesh(), model="neohookean", young=1e4, poisson=0.3)
        inverted = UNIT_TET.copy()
        inverted[3, 2] = -0.2  # node 3 pushed through the opposite face
        body.positions = inverted
        report = world.step(0.1 * body.critical_dt)
        assert "SH_WARN_INVERTED" in report.warnings
        assert report.warning_bits & (1 << softhap.WarningKind.SH_WARN_INVERTED)
        assert world.warnings["SH_WARN_INVERTED"] >= 1
        assert np.all(np.isfinite(body.positions))


def test_defaults_are_the_documented_c_defaults():
    # sh_fem_body_def_default: StVK, E = 3 kPa, nu = 0.45, rho = 1000 kg/m^3, symplectic Euler
    stretched = UNIT_TET.copy()
    stretched[:, 0] *= 1.1
    with softhap.World() as world:
        default = world.add_fem_body(unit_tet_mesh())
        explicit = world.add_fem_body(
            unit_tet_mesh(), model="stvk", young=3000.0, poisson=0.45, density=1000.0,
            integrator="symplectic_euler", on_unstable="substep", damping_mass=0.0,
            damping_stiffness=0.0, runaway_speed=1e4,
        )
        assert default.info.total_mass == pytest.approx(1000.0 / 6.0, rel=1e-14)
        assert default.critical_dt == explicit.critical_dt
        default.positions = stretched
        explicit.positions = stretched
        np.testing.assert_array_equal(default.elastic_forces(), explicit.elastic_forces())
        expected, _ = uniaxial_forces("stvk", 3000.0, 0.45, 0.1)
        np.testing.assert_allclose(default.elastic_forces(), expected, rtol=1e-10)


def test_nearly_incompressible_material_counts_a_locking_warning():
    with softhap.World() as world:
        world.add_fem_body(unit_tet_mesh(), poisson=0.45)
        world.step(1e-3)
        assert world.warnings["SH_WARN_LOCKING"] == 0
        world.add_fem_body(unit_tet_mesh(), poisson=0.49)
        world.step(1e-3)
        assert world.warnings["SH_WARN_LOCKING"] >= 1
