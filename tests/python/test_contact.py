"""Tools, obstacles and contact (World.add_tool, World.add_obstacle, World.set_body_contact)
against the Hunt-Crossley law and Coulomb friction of the header, Newton's laws (static balance,
sliding to a stop, global equilibrium of an indented body, action and reaction between two
bodies), and the errors for bad definitions and stale ids."""

import ctypes
import math
import subprocess

import numpy as np
import pytest

import softhap
from softhap import _lib

from conftest import compile_c
from textbook import G

needs_ccd = pytest.mark.skipif(
    "SH_FEATURE_CCD" not in softhap.build_features(), reason="library built without libccd"
)


def box_mesh(size, cells, origin=(0.0, 0.0, 0.0)):
    """The library's box mesh (softhap.Mesh.box), under the name the tests share."""
    return softhap.Mesh.box(size, cells, origin)


def grid_mesh(xs, ys, zs):
    """The library's grid mesh (softhap.Mesh.grid), under the name the tests share."""
    return softhap.Mesh.grid(xs, ys, zs)


def fixed_point(world, position):
    """A one-node spring body held at position (its contact force still acts and is felt)."""
    body = world.add_spring_body([position], mass=1.0)
    body.fix_nodes([0])
    return body


def hunt_crossley(stiffness, exponent, damping, depth, rate):
    """F = lambda x^n (1 + 3/2 alpha x') of the header's sh_contact_params comment."""
    return stiffness * depth**exponent * (1.0 + 1.5 * damping * rate)


# ------------------------------------------------------------------------------------------
# struct layout and enum values (the C compiler check is test_structs.py, through _lib.STRUCTS)


def test_new_struct_sizes_computed_by_hand():
    # x86-64/aarch64 SysV layout worked out from the header, independent of any compiler.
    assert ctypes.sizeof(_lib.sh_shape) == 88  # int, pad 4, 5 doubles, pointer, i32, pad, 3 doubles
    assert _lib.sh_shape.normal.offset == 64
    assert ctypes.sizeof(_lib.sh_contact_params) == 64  # u32, pad 4, 6 doubles, i32, pad 4
    assert ctypes.sizeof(_lib.sh_collider_def) == 216  # u32, pad, shape 88, 7 doubles, params
    assert _lib.sh_collider_def.contact.offset == 152
    assert ctypes.sizeof(_lib.sh_contact_state) == 72  # 6 doubles, i32, pad 4, 2 doubles
    # sh_step_report grew by contact_count (i32, pad 4), collision_seconds, contact_substeps
    assert _lib.sh_step_report.contact_count.offset == 112
    assert _lib.sh_step_report.collision_seconds.offset == 120
    assert _lib.sh_step_report.contact_substeps.offset == 128
    # ... and by cut_faces (i32, in contact_substeps' padding) and topology_seconds
    assert _lib.sh_step_report.cut_faces.offset == 132
    assert _lib.sh_step_report.springs_broken.offset == 144
    assert ctypes.sizeof(_lib.sh_step_report) == 152
    new = {"sh_shape", "sh_contact_params", "sh_collider_def", "sh_contact_state"}
    assert new <= set(_lib.STRUCTS)  # so test_structs.py checks them against the C compiler


def test_shape_kinds_match_c(cc, tmp_path):
    lines = ["#include <stdio.h>", '#include "softhap/softhap.h"', "int main(void) {"]
    for name in _lib.SHAPE_KINDS:
        lines.append('    printf("%s %%d\\n", (int)SH_SHAPE_%s);' % (name, name.upper()))
    lines += ["    return 0;", "}"]
    program = compile_c(cc, "\n".join(lines) + "\n", tmp_path / "shapes")
    output = subprocess.run([str(program)], capture_output=True, text=True, check=True).stdout
    from_c = {name: int(value) for name, value in (line.split() for line in output.splitlines())}
    assert from_c == _lib.SHAPE_KINDS


# ------------------------------------------------------------------------------------------
# static balance: a particle resting on an obstacle


# Obstacles whose top surface is the plane z = 0 right under the particle at the origin.
RESTING_SURFACES = {
    "plane": dict(position=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0)),
    "box": dict(position=(0.0, 0.0, -0.05), half_extents=(0.1, 0.1, 0.05)),
    "sphere": dict(position=(0.0, 0.0, -0.05), radius=0.05),
    "capsule": dict(position=(0.0, 0.0, -0.08), radius=0.03, half_length=0.05),
    "convex": dict(
        position=(0.0, 0.0, -0.05),
        points=[[x, y, z] for x in (-0.1, 0.1) for y in (-0.1, 0.1) for z in (-0.05, 0.05)],
    ),
}


@pytest.mark.parametrize("kind", sorted(RESTING_SURFACES))
def test_particle_at_rest_on_an_obstacle_balances_its_weight(kind):
    # At rest lambda x^n = m g: the obstacle feels -m g and the depth is (m g / lambda)^(1/n).
    if kind == "convex" and "SH_FEATURE_CCD" not in softhap.build_features():
        pytest.skip("library built without libccd")
    m, stiffness, exponent = 1e-3, 1e4, 1.5
    with softhap.World(gravity=(0, 0, -G)) as world:
        obstacle = world.add_obstacle(
            kind, stiffness=stiffness, exponent=exponent, damping=0.0, friction=0.0,
            **RESTING_SURFACES[kind]
        )
        particle = world.add_spring_body([[0.0, 0.0, 1e-3]], mass=m, damping_mass=300.0)
        for _ in range(3000):
            report = world.step(1e-3)
        state = obstacle.contact_state
        depth = (m * G / stiffness) ** (1.0 / exponent)
        assert isinstance(state, softhap.ContactState)
        assert state.contact_count == obstacle.contacts == 1
        np.testing.assert_allclose(obstacle.force, [0.0, 0.0, -m * G], rtol=1e-6, atol=1e-12)
        assert state.force[2] == pytest.approx(-m * G, rel=1e-6)
        assert obstacle.max_depth == pytest.approx(depth, rel=1e-6)
        assert -particle.positions[0, 2] == pytest.approx(depth, rel=1e-6)
        np.testing.assert_allclose(obstacle.torque, 0.0, atol=1e-12)
        # a particle has no surface area: no penetration volume
        assert obstacle.penetration_volume == 0.0
        assert report.contact_count == 1
        assert report.contact_substeps == 1  # an obstacle never moves
        assert report.collision_seconds >= 0.0


def test_tilted_plane_pushes_along_its_normal():
    # A plane through (0, 0, -0.01) with normal n: a fixed point at distance x behind it feels
    # lambda x^n along n; the plane feels the opposite.
    stiffness, exponent, x = 2e4, 1.2, 2e-4
    normal = np.array([0.3, -0.4, 1.0]) / np.linalg.norm([0.3, -0.4, 1.0])
    origin = np.array([0.0, 0.0, -0.01])
    with softhap.World(gravity=(0, 0, 0)) as world:
        plane = world.add_obstacle("plane", position=origin, normal=normal * 7.0,
                                   stiffness=stiffness, exponent=exponent)
        lateral = np.array([0.01, 0.02, 0.0])
        lateral -= np.dot(lateral, normal) * normal  # along the plane
        fixed_point(world, origin + lateral - x * normal)
        world.step(1e-3)
        np.testing.assert_allclose(plane.force, -stiffness * x**exponent * normal, rtol=1e-9)
        assert plane.max_depth == pytest.approx(x, rel=1e-9)


# ------------------------------------------------------------------------------------------
# Coulomb friction: sliding to a stop


def test_particle_sliding_on_a_plane_stops_after_v0_squared_over_2_mu_g():
    m, stiffness, exponent, mu, v0, dt = 1e-3, 1e6, 1.5, 0.5, 1.0, 1e-4
    depth = (m * G / stiffness) ** (1.0 / exponent)  # start at the static depth: no bounce
    with softhap.World(gravity=(0, 0, -G)) as world:
        plane = world.add_obstacle("plane", stiffness=stiffness, exponent=exponent,
                                   damping=0.0, static_friction=mu, dynamic_friction=mu)
        particle = world.add_spring_body([[0.0, 0.0, -depth]], mass=m)
        particle.velocities = [[v0, 0.0, 0.0]]
        stop_time = v0 / (mu * G)
        for _ in range(int(1.3 * stop_time / dt)):
            world.step(dt)
        distance = particle.positions[0, 0]
        assert distance == pytest.approx(v0 * v0 / (2.0 * mu * G), rel=0.03)
        assert abs(particle.velocities[0, 0]) < 1e-6
        assert particle.positions[0, 1] == 0.0
        # at rest the plane carries the weight and no friction
        np.testing.assert_allclose(plane.force, [0.0, 0.0, -m * G], rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("dt", [1e-2, 1e-3])
def test_implicit_particle_stops_at_the_backward_euler_distance(dt):
    # Implicit Euler with Coulomb friction at constant normal force: while sliding each step
    # takes mu g dt off the speed and then moves by dt times the new speed, v_k = v0 - k mu g dt,
    # so after the N = floor(v0 / (mu g dt)) sliding steps it has gone
    # dt (N v0 - mu g dt N (N + 1) / 2) (v0^2 / (2 mu g) - dt v0 / 2 when N is whole), and the
    # next step sticks. That stopping step is where exact Newton on the regularised law cycles
    # (mu g dt is 0.05 m/s here, fifty times slip_velocity): every step must converge.
    m, stiffness, exponent, mu, v0 = 1e-3, 1e6, 1.5, 0.5, 1.0
    depth = (m * G / stiffness) ** (1.0 / exponent)
    with softhap.World(gravity=(0, 0, -G)) as world:
        plane = world.add_obstacle("plane", stiffness=stiffness, exponent=exponent, damping=0.0,
                                   static_friction=mu, dynamic_friction=mu)
        particle = world.add_spring_body([[0.0, 0.0, -depth]], mass=m, integrator="implicit_euler")
        particle.velocities = [[v0, 0.0, 0.0]]
        most = 0
        for _ in range(int(round(0.3 / dt))):
            most = max(most, world.step(dt).newton_iterations)
        steps = math.floor(v0 / (mu * G * dt))
        distance = dt * (steps * v0 - mu * G * dt * steps * (steps + 1) / 2)
        assert particle.positions[0, 0] == pytest.approx(distance, rel=1e-3)
        assert abs(particle.velocities[0, 0]) < 1e-6
        assert most <= 10  # the stopping step: its line search may shorten an update
        # at rest the plane carries the weight and no friction
        np.testing.assert_allclose(plane.force, [0.0, 0.0, -m * G], rtol=1e-6, atol=1e-9)


# ------------------------------------------------------------------------------------------
# tools: pose, velocity, wrench


def test_tool_velocity_enters_the_damping_and_friction():
    # A fixed point at depth x inside a sphere tool: F = lambda x^n without motion; with the
    # tool moving towards it at u, F = lambda x^n (1 + 3/2 alpha u); spun at w about x, the
    # point slides at w (R - x) and Coulomb friction mu F acts, with torque about the centre.
    stiffness, exponent, alpha, mu, radius, x = 1e4, 1.5, 0.2, 0.5, 0.01, 1e-3
    dt = 1e-4
    with softhap.World(gravity=(0, 0, 0)) as world:
        fixed_point(world, [0.0, 0.0, radius - x])
        tool = world.add_tool("sphere", radius=radius, stiffness=stiffness, exponent=exponent,
                              damping=alpha, friction=mu)
        f = hunt_crossley(stiffness, exponent, alpha, x, 0.0)
        world.step(dt)
        np.testing.assert_allclose(tool.force, [0.0, 0.0, -f], rtol=1e-12)
        np.testing.assert_allclose(tool.torque, 0.0, atol=1e-15)
        assert tool.contacts == 1 and tool.max_depth == pytest.approx(x, rel=1e-12)

        tool.set_velocity((0.0, 0.0, 0.3))
        world.step(dt)
        expected = hunt_crossley(stiffness, exponent, alpha, x, 0.3)
        np.testing.assert_allclose(tool.force, [0.0, 0.0, -expected], rtol=1e-12)

        world.step(dt)  # the given velocity held for one step only
        np.testing.assert_allclose(tool.force, [0.0, 0.0, -f], rtol=1e-12)

        tool.set_velocity((0.0, 0.0, 0.0), angular=(10.0, 0.0, 0.0))
        world.step(dt)
        force, torque = tool.wrench()
        # the tool's surface at the point moves at w x r = -w (R - x) y, so the point slides
        # at +w (R - x) y relative to it: friction on the point is -y, on the tool +y
        np.testing.assert_allclose(force, [0.0, mu * f, -f], rtol=1e-12)
        np.testing.assert_allclose(torque, [-(radius - x) * mu * f, 0.0, 0.0], rtol=1e-12)
        state = tool.contact_state
        np.testing.assert_array_equal(state.force, force)
        np.testing.assert_array_equal(state.torque, torque)


def test_tool_velocity_is_the_pose_difference_over_dt():
    stiffness, exponent, alpha, radius, x, move, dt = 1e4, 1.5, 0.2, 0.01, 1e-3, 2e-5, 1e-3
    with softhap.World(gravity=(0, 0, 0)) as world:
        fixed_point(world, [0.0, 0.0, radius - x])
        tool = world.add_tool("sphere", radius=radius, position=(0.0, 0.0, -move),
                              stiffness=stiffness, exponent=exponent, damping=alpha)
        world.step(dt)
        f0 = hunt_crossley(stiffness, exponent, alpha, x - move, 0.0)
        np.testing.assert_allclose(tool.force, [0.0, 0.0, -f0], rtol=1e-12)
        tool.set_pose((0.0, 0.0, 0.0))
        world.step(dt)  # moved up by `move` in dt: depth rate move / dt at the end depth x
        expected = hunt_crossley(stiffness, exponent, alpha, x, move / dt)
        np.testing.assert_allclose(tool.force, [0.0, 0.0, -expected], rtol=1e-12)
        world.step(dt)  # at rest again
        f = hunt_crossley(stiffness, exponent, alpha, x, 0.0)
        np.testing.assert_allclose(tool.force, [0.0, 0.0, -f], rtol=1e-12)


def test_box_tool_orientation_is_normalised_and_used():
    # A box of half extents (a, b, c) turned 90 degrees about x: its local y is world z, so
    # its top face is at z = b. The quaternion is given unnormalised.
    stiffness, exponent, x = 1e4, 1.0, 1e-4
    a, b, c = 0.02, 0.005, 0.01
    with softhap.World(gravity=(0, 0, 0)) as world:
        fixed_point(world, [0.001, -0.002, b - x])
        s = 3.0 * math.sqrt(0.5)
        tool = world.add_tool("box", half_extents=(a, b, c), orientation=(s, s, 0.0, 0.0),
                              stiffness=stiffness, exponent=exponent, damping=0.0)
        world.step(1e-3)
        np.testing.assert_allclose(tool.force, [0.0, 0.0, -stiffness * x], rtol=1e-9, atol=1e-15)
        assert tool.max_depth == pytest.approx(x, rel=1e-9)
        # torque about the box centre of the reaction at (0.001, -0.002, b - x)
        np.testing.assert_allclose(
            tool.torque, np.cross([0.001, -0.002, b - x], [0.0, 0.0, -stiffness * x]),
            rtol=1e-9, atol=1e-15,
        )


def test_fast_tool_is_sub_stepped_by_half_its_inner_radius():
    radius, travel = 0.01, 0.052
    with softhap.World(gravity=(0, 0, 0)) as world:
        world.add_spring_body([[1.0, 0.0, 0.0]], mass=1e-3)
        tool = world.add_tool("sphere", radius=radius)
        assert world.step(1e-3).contact_substeps == 1
        tool.set_pose((travel, 0.0, 0.0))
        report = world.step(1e-3)
        assert report.contact_substeps == math.ceil(travel / (0.5 * radius))
        assert report.contact_count == 0


# ------------------------------------------------------------------------------------------
# an indented FEM body in static equilibrium


@pytest.mark.parametrize(
    "kind, shape, angle",
    [
        ("box", dict(half_extents=(0.004, 0.003, 0.002)), 0.3),
        ("capsule", dict(radius=0.002, half_length=0.004), 1.4),  # lying, tilted 10 degrees
    ],
)
def test_indented_body_supports_carry_the_tool_force(kind, shape, angle):
    # Gravity 0, bottom nodes fixed: every free node is in balance, and internal elastic forces
    # sum to zero with zero moment (StVK is rotation invariant), so the supports' elastic forces
    # balance the contact: tool force = -sum over fixed nodes of f_el, and the tool's torque
    # about its position p is -sum x_i x f_el_i - p x F.
    size, height = 0.02, 0.01
    mesh = box_mesh((size, size, height), (6, 6, 3))
    with softhap.World(gravity=(0, 0, 0)) as world:
        body = world.add_fem_body(mesh, model="stvk", young=3e3, poisson=0.3)
        bottom = np.flatnonzero(mesh.nodes[:, 2] == 0.0)
        body.fix_nodes(bottom)
        half = angle / 2  # about the axis (0.6, 0.8, 0)
        orientation = (math.cos(half), 0.6 * math.sin(half), 0.8 * math.sin(half), 0.0)
        position = np.array([0.0113, 0.0087, height + 0.0015])
        tool = world.add_tool(kind, position=position, orientation=orientation, **shape)
        # 24 iterations for the box, 38 for the capsule (225 with the couplings between the nodes
        # under it bounded on their diagonals, not in the matrix).
        world.solve_static(max_iterations=60)
        state = tool.contact_state
        assert state.contact_count >= 1 and state.max_depth > 0.0
        assert state.penetration_volume > 0.0
        assert state.force[2] > 0.0  # the body pushes the tool up
        elastic = body.elastic_forces()[bottom]
        x = body.positions[bottom]
        np.testing.assert_allclose(state.force, -elastic.sum(axis=0), rtol=0,
                                   atol=1e-6 * np.linalg.norm(state.force))
        expected_torque = -np.cross(x, elastic).sum(axis=0) - np.cross(position, state.force)
        np.testing.assert_allclose(state.torque, expected_torque, rtol=0,
                                   atol=1e-6 * np.linalg.norm(state.torque))


# ------------------------------------------------------------------------------------------
# contact between two bodies


def overlapping_blocks(world, integrator="implicit_euler", damping_mass=200.0):
    size, height = 0.02, 0.01
    lower_mesh = box_mesh((size, size, height), (3, 3, 1))
    upper_mesh = lower_mesh.transform(1.0, (0.003, 0.002, height - 0.0005))
    lower = world.add_fem_body(lower_mesh, young=3e3, poisson=0.3, integrator=integrator,
                               damping_mass=damping_mass)
    upper = world.add_fem_body(upper_mesh, young=3e3, poisson=0.3, integrator=integrator,
                               damping_mass=damping_mass)
    lower_fixed = np.flatnonzero(lower_mesh.nodes[:, 2] == 0.0)
    upper_fixed = np.flatnonzero(np.isclose(upper_mesh.nodes[:, 2], upper_mesh.nodes[:, 2].max()))
    lower.fix_nodes(lower_fixed)
    upper.fix_nodes(upper_fixed)
    return lower, upper, lower_fixed, upper_fixed


def test_body_contact_is_action_and_reaction_at_rest():
    # Two overlapping blocks held at their far faces settle; then the supports of one carry
    # exactly the opposite of the other's.
    with softhap.World(gravity=(0, 0, 0)) as world:
        lower, upper, lower_fixed, upper_fixed = overlapping_blocks(world)
        world.set_body_contact(lower, upper, stiffness=1e4)
        for _ in range(300):
            report = world.step(1e-3)
        assert report.contact_count > 0
        on_lower = lower.elastic_forces()[lower_fixed].sum(axis=0)
        on_upper = upper.elastic_forces()[upper_fixed].sum(axis=0)
        assert on_lower[2] < 0.0  # pushed down
        np.testing.assert_allclose(on_lower, -on_upper, rtol=0,
                                   atol=1e-6 * np.linalg.norm(on_lower))

        world.clear_body_contact(upper, lower)  # either order
        assert world.step(1e-3).contact_count == 0
        world.clear_body_contact(upper, lower)  # clearing twice is fine


def test_static_solve_balances_body_contact():
    # Bodies in contact are solved for their joint equilibrium (sh_world_set_body_contact).
    with softhap.World(gravity=(0, 0, 0)) as world:
        lower, upper, lower_fixed, upper_fixed = overlapping_blocks(world)
        world.set_body_contact(lower, upper, stiffness=1e4)
        world.solve_static()
        on_lower = lower.elastic_forces()[lower_fixed].sum(axis=0)
        on_upper = upper.elastic_forces()[upper_fixed].sum(axis=0)
        np.testing.assert_allclose(on_lower, -on_upper, rtol=0,
                                   atol=1e-6 * np.linalg.norm(on_lower))


def test_body_contact_errors():
    with softhap.World(gravity=(0, 0, 0)) as world, softhap.World() as other:
        lower, upper, _, _ = overlapping_blocks(world)
        particle = world.add_spring_body([[0.0, 0.0, 1.0]])
        with pytest.raises(softhap.Error) as info:
            world.set_body_contact(lower, particle)
        assert info.value.status_name == "SH_ERR_UNSUPPORTED"
        with pytest.raises(softhap.Error) as info:
            world.set_body_contact(lower, lower)
        assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
        with pytest.raises(softhap.Error) as info:
            world.set_body_contact(lower, upper, stiffness=-1.0)
        assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
        assert "params.stiffness" in info.value.message
        with pytest.raises(ValueError):
            other.set_body_contact(lower, upper)
        with pytest.raises(TypeError):
            world.set_body_contact(lower.id, upper)
        world.remove_body(upper)
        with pytest.raises(softhap.Error) as info:
            world.set_body_contact(lower, upper)
        assert info.value.status_name == "SH_ERR_INVALID_HANDLE"


# ------------------------------------------------------------------------------------------
# arguments, errors and lifetimes


def test_plane_tool_is_rejected_naming_the_plane():
    with softhap.World() as world:
        with pytest.raises(softhap.Error) as info:
            world.add_tool("plane")
        assert info.value.status == softhap.Status.SH_ERR_INVALID_ARGUMENT
        assert info.value.function == "sh_tool_create"
        assert "plane" in info.value.message.lower()


@pytest.mark.parametrize(
    "kind, shape, field",
    [
        ("sphere", dict(radius=0.0), "shape.radius"),
        ("capsule", dict(radius=0.01, half_length=-1.0), "shape.half_length"),
        ("capsule", dict(radius=1e-4, half_length=0.2), "shape.half_length"),  # 2000 radii
        ("box", dict(half_extents=(0.01, math.nan, 0.01)), "shape.half_extents[1]"),
        ("sphere", dict(stiffness=0.0), "contact.stiffness"),
        ("sphere", dict(exponent=0.5), "contact.exponent"),
        ("sphere", dict(static_friction=0.1, dynamic_friction=0.2), "contact.static_friction"),
        ("sphere", dict(capacity=0), "contact.capacity"),
    ],
)
def test_bad_shapes_and_laws_are_rejected_naming_the_field(kind, shape, field):
    with softhap.World() as world:
        for add in (world.add_tool, world.add_obstacle):
            with pytest.raises(softhap.Error) as info:
                add(kind, **shape)
            assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
            assert field in info.value.message


def test_defaults_are_the_c_defaults():
    # Unspecified keywords keep sh_collider_def_default: sphere of radius 5 mm, lambda = 1e4,
    # n = 1.5: a fixed point 1 mm inside the default sphere feels 1e4 (1e-3)^1.5.
    with softhap.World(gravity=(0, 0, 0)) as world:
        fixed_point(world, [0.0, 0.0, 0.004])
        tool = world.add_tool("sphere")
        world.step(1e-3)
        assert tool.force[2] == pytest.approx(-1e4 * 1e-3**1.5, rel=1e-12)


@needs_ccd
def test_convex_tool_needs_volume():
    with softhap.World() as world:
        square = [[0.0, 0.0, 0.0], [0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.01, 0.01, 0.0]]
        with pytest.raises(softhap.Error) as info:
            world.add_tool("convex", points=square)
        assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
        assert "plane" in info.value.message
        with pytest.raises(softhap.Error) as info:
            world.add_tool("convex", points=square[:3])
        assert "shape.point_count" in info.value.message
        with pytest.raises(softhap.Error) as info:
            world.add_tool("convex")
        assert "shape.points" in info.value.message
        tetrahedron = square[:3] + [[0.0, 0.0, 0.01]]
        tool = world.add_tool("convex", points=np.array(tetrahedron))
        assert tool.is_valid


def test_nan_pose_is_rejected_and_the_tool_keeps_its_pose():
    stiffness, exponent, radius, x = 1e4, 1.5, 0.01, 1e-3
    with softhap.World(gravity=(0, 0, 0)) as world:
        fixed_point(world, [0.0, 0.0, radius - x])
        tool = world.add_tool("sphere", radius=radius, stiffness=stiffness, exponent=exponent)
        for position, orientation in [((math.nan, 0.0, 0.0), (1, 0, 0, 0)),
                                      ((0.0, 0.0, math.inf), (1, 0, 0, 0)),
                                      ((0.0, 0.0, 0.0), (0, 0, 0, 0)),
                                      ((0.0, 0.0, 0.0), (1, math.nan, 0, 0))]:
            with pytest.raises(softhap.Error) as info:
                tool.set_pose(position, orientation)
            assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
            assert info.value.function == "sh_tool_set_pose"
        with pytest.raises(softhap.Error) as info:
            tool.set_velocity((math.nan, 0.0, 0.0))
        assert "linear" in info.value.message
        world.step(1e-3)
        np.testing.assert_allclose(tool.force, [0.0, 0.0, -stiffness * x**exponent], rtol=1e-12)
        tool.set_pose((0.0, 0.0, 1.0))  # still poseable: moved away, no contact
        world.step(1e-3)
        assert tool.contacts == 0
        np.testing.assert_array_equal(tool.force, 0.0)


def test_destroyed_tool_and_obstacle_are_stale():
    with softhap.World() as world:
        tool = world.add_tool("sphere")
        other = world.add_tool("sphere")
        plane = world.add_obstacle("plane")
        assert tool.is_valid and tool.valid and plane.is_valid and plane.valid
        assert tool.id != 0 and tool.id != other.id
        tool.destroy()
        plane.destroy()
        assert not tool.is_valid and not tool.valid and not plane.is_valid
        assert other.is_valid
        assert softhap._c_library.sh_tool_is_valid(world._handle, softhap._lib.sh_tool_id(tool.id)) == 0
        uses = [
            lambda: tool.set_pose((0.0, 0.0, 0.0)),
            lambda: tool.set_velocity((0.0, 0.0, 0.0)),
            lambda: tool.force,
            lambda: tool.torque,
            lambda: tool.contact_state,
            tool.destroy,
            lambda: plane.force,
            lambda: plane.contact_state,
            plane.destroy,
        ]
        for use in uses:
            with pytest.raises(softhap.Error) as info:
                use()
            assert info.value.status == softhap.Status.SH_ERR_INVALID_HANDLE
        # a new tool does not revive the stale id, and the world still steps
        again = world.add_tool("sphere")
        assert again.id != tool.id and not tool.is_valid
        world.step(1e-3)


def test_tool_of_a_closed_world_raises_instead_of_crashing():
    world = softhap.World()
    tool = world.add_tool("sphere")
    plane = world.add_obstacle("plane")
    world.close()
    assert not tool.is_valid and not plane.is_valid
    for use in [lambda: tool.set_pose((0, 0, 0)), lambda: tool.force, tool.destroy,
                lambda: plane.contact_state, lambda: world.add_tool("sphere"),
                lambda: world.add_obstacle("plane")]:
        with pytest.raises(softhap.Error) as info:
            use()
        assert info.value.status == softhap.Status.SH_ERR_INVALID_HANDLE


def test_python_side_argument_errors_are_value_errors():
    with softhap.World() as world:
        with pytest.raises(ValueError, match="kind"):
            world.add_tool("cylinder")
        with pytest.raises(ValueError, match="kind"):
            world.add_obstacle(4)
        with pytest.raises(ValueError, match="half_extents"):
            world.add_tool("sphere", half_extents=(1, 1, 1))
        with pytest.raises(ValueError, match="normal"):
            world.add_obstacle("box", half_extents=(1, 1, 1), normal=(0, 0, 1))
        with pytest.raises(ValueError, match="orientation"):
            world.add_obstacle("plane", orientation=(1, 0, 0, 0))  # a plane has only its normal
        for old in ("point", "center"):  # every obstacle is placed with position= since 0.6
            with pytest.raises(TypeError, match=old):
                world.add_obstacle("plane", **{old: (0, 0, 0)})
        with pytest.raises(ValueError, match="friction"):
            world.add_tool("sphere", friction=0.3, static_friction=0.5)
        with pytest.raises(ValueError, match="points"):
            world.add_tool("convex", points=[[0, 0, 0], [1, 0, 0]] * 2 + [[0, 1]])
        with pytest.raises(ValueError, match="position"):
            world.add_tool("sphere", position=(0, 0))
        tool = world.add_tool("sphere")
        with pytest.raises(ValueError, match="orientation"):
            tool.set_pose((0, 0, 0), (1, 0, 0))


def test_step_report_has_the_contact_fields():
    with softhap.World() as world:
        report = world.step(1e-3)
        assert report.contact_count == 0 and report.contact_substeps == 1
        assert report.collision_seconds == 0.0  # no tool or obstacle: no collision work
        world.add_obstacle("plane")
        world.add_spring_body([[0.0, 0.0, -1e-4]], damping_mass=100.0)
        report = world.step(1e-3)
        assert report.contact_count == 1 and report.contact_substeps >= 1
        assert report.collision_seconds >= 0.0
        assert {"contact_count", "collision_seconds", "contact_substeps"} <= set(report)


def test_tool_pose_reads_back_normalised():
    with softhap.World(gravity=(0, 0, 0)) as world:
        tool = world.add_tool("sphere", radius=0.01)
        tool.set_pose((0.1, 0.2, 0.3), (2.0, 0.0, 0.0, 0.0))
        position, orientation = tool.pose
        np.testing.assert_array_equal(position, [0.1, 0.2, 0.3])
        np.testing.assert_array_equal(orientation, [1.0, 0.0, 0.0, 0.0])
