"""Haptic contexts through the bindings: the proxy force against the Hunt-Crossley law by hand,
the buffer force against the full model's static solve, the force contract's clamp and faults,
and the context's options, memory and lifetime."""

import math

import numpy as np
import pytest

import softhap
from test_contact import box_mesh

TOP = 0.01  # the block's top face (m)
RADIUS = 0.005


def pressed_block(damping_mass=40.0, tool_z=TOP + RADIUS + 0.05):
    """A 20 x 20 x 10 mm soft block on a fixed base and a linear sphere tool above its centre."""
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    body = world.add_fem_body(
        box_mesh((0.02, 0.02, TOP), (6, 6, 3)), model="neohookean", young=5e3, poisson=0.3,
        density=1000.0, damping_mass=damping_mass,
    )
    body.fix_nodes(np.flatnonzero(np.abs(body.positions[:, 2]) < 1e-12))
    tool = world.add_tool(
        "sphere", radius=RADIUS, position=(0.01, 0.01, tool_z), stiffness=100.0, exponent=1.0, damping=0.0
    )
    return world, body, tool


def test_proxy_force_is_the_law_at_the_sphere_depth():
    # The tool is far from the block at creation: no buffer, only the proxy plane of the
    # nearest surface point. One Hunt-Crossley point, n = 1, no damping: F = lambda d.
    world, _, tool = pressed_block()
    haptic = world.add_haptic(tool, radius=0.005, ramp_time=0.0, stale_after=100.0)
    result = haptic.step((0.01, 0.01, TOP + RADIUS + 1e-3))
    assert not result.contact and np.all(result.force == 0.0)
    depth = 7e-4
    result = haptic.step((0.01, 0.01, TOP + RADIUS - depth))
    assert result.contact and result.buffer_tets == 0
    assert result.raw_force == pytest.approx([0.0, 0.0, 100.0 * depth], abs=1e-12)
    # The rate limit (2000 N/s default) lets 2 N per 1 ms step through: the whole force.
    assert result.force == pytest.approx(result.raw_force, abs=1e-12)
    assert result.faults == frozenset() and result.fault_bits == 0


def test_whole_block_buffer_settles_on_the_static_solve():
    depth = 0.0015
    pose = (0.01, 0.01, TOP + RADIUS - depth)
    reference, _, reference_tool = pressed_block(damping_mass=0.0)
    reference_tool.set_pose(pose)
    # A linear law with the sphere's triangle terms: Newton converges linearly (README Limits).
    reference.solve_static(tolerance=1e-9, max_iterations=400)
    expected = reference_tool.force

    world, _, tool = pressed_block(tool_z=TOP + RADIUS)
    haptic = world.add_haptic(tool, radius=1.0, max_force_rate=1e6, ramp_time=0.0, stale_after=100.0)
    for i in range(2500):
        s = min(1.0, (i + 1) / 300.0)
        result = haptic.step((0.01, 0.01, TOP + RADIUS - s * depth))
    assert result.buffer_tets == 6 * 6 * 3 * 6
    assert expected[2] > 0.02
    assert result.raw_force == pytest.approx(expected, abs=2e-3 * expected[2])


def test_force_is_clamped_and_faults_are_reported_not_raised():
    world, _, tool = pressed_block(tool_z=TOP + RADIUS)
    haptic = world.add_haptic(tool, radius=0.008, max_force=0.02, ramp_time=0.0, stale_after=100.0)
    for i in range(100):
        result = haptic.step((0.01, 0.01, TOP + RADIUS - 0.003 * min(1.0, (i + 1) / 20.0)))
        assert np.linalg.norm(result.force) <= 0.02 * (1 + 1e-12)
    assert np.linalg.norm(result.raw_force) > 0.02
    assert "SH_WARN_FORCE_CLAMPED" in result.warnings
    assert haptic.warnings["SH_WARN_FORCE_CLAMPED"] > 0
    bad = haptic.step((math.nan, 0.0, 0.0))
    assert bad.faults == {"SH_HAPTIC_FAULT_POSE"}
    assert np.all(np.isfinite(bad.force))
    assert "SH_HAPTIC_FAULT_DT" in haptic.step((0.01, 0.01, TOP), dt=-1.0).faults
    world.close()
    gone = haptic.step((0.01, 0.01, TOP))
    assert "SH_HAPTIC_FAULT_NO_TOOL" in gone.faults
    haptic.close()
    with pytest.raises(softhap.Error) as error:
        haptic.step((0.01, 0.01, TOP))
    assert error.value.status == softhap.Status.SH_ERR_INVALID_HANDLE


def test_options_memory_and_validation():
    world, _, tool = pressed_block()
    small = world.add_haptic(tool, capacity_tets=100, capacity_nodes=100)
    large = world.add_haptic(tool, capacity_tets=1000, capacity_nodes=1000)
    assert 0 < small.memory_bytes < large.memory_bytes
    # Three exchanged buffers of about 104 bytes per tet in force-kernel blocks, at least.
    assert large.memory_bytes > 3 * 104 * 1000
    assert small.dt == 1e-3 and small.tool is tool
    with pytest.raises(softhap.Error) as error:
        world.add_haptic(tool, radius=-1.0)
    assert error.value.status == softhap.Status.SH_ERR_INVALID_ARGUMENT
    assert "def->radius" in str(error.value)
    with pytest.raises(TypeError):
        world.add_haptic(tool, unknown=1.0)
    tool.destroy()
    with pytest.raises(softhap.Error) as error:
        world.add_haptic(tool)
    assert error.value.status == softhap.Status.SH_ERR_INVALID_HANDLE


def test_sub_steps_follow_the_buffers_own_tets(meshes):
    # The liver's thinnest tet (0.4 mm altitude) sits near its top: a small buffer at its bottom
    # needs fewer explicit sub-steps than the whole organ, whose critical step that tet sets.
    mesh = softhap.Mesh.load(str(meshes / "liver.msh")).transform(0.01)
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    world.add_fem_body(mesh, model="linear", young=15e3, poisson=0.45, density=1000.0)
    device = mesh.nodes[np.argmin(mesh.nodes[:, 2])] - (0.0, 0.0, 0.0098)
    tool = world.add_tool("sphere", radius=0.01, position=device, stiffness=10.0, exponent=1.0)
    substeps = {}
    for radius in (0.01, 1.0):
        haptic = world.add_haptic(tool, radius=radius, ramp_time=0.0, stale_after=100.0)
        result = haptic.step(device)
        substeps[radius] = (result.buffer_tets, result.substeps)
    assert substeps[1.0][0] == mesh.info.tet_count > substeps[0.01][0]
    assert substeps[0.01][1] < substeps[1.0][1]


def test_sliding_flat_tool_feels_coulomb_friction():
    # A box wider than the block presses its whole top 0.2 mm down with its flat bottom (every
    # contact normal vertical, no edge ploughing the surface) and slides at 10 mm/s: once the
    # block has sheared, every contact slides and the tool feels Coulomb's -mu F_z along its
    # motion (mu_s = mu_d: no speed dependence).
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    body = world.add_fem_body(
        box_mesh((0.02, 0.02, TOP), (8, 8, 4)), model="linear", young=5e4, poisson=0.3, density=1000.0,
        damping_mass=40.0,
    )
    body.fix_nodes(np.flatnonzero(np.abs(body.positions[:, 2]) < 1e-12))
    half = np.array([0.05, 0.05, 0.01])
    start = np.array([0.01, 0.01, TOP + half[2] - 2e-4])
    tool = world.add_tool(
        "box", half_extents=half, position=start + (0.0, 0.0, 2e-4), stiffness=200.0, exponent=1.0, damping=0.2,
        friction=0.3,
    )
    haptic = world.add_haptic(tool, radius=1.0, max_force=100.0, max_force_rate=1e6, ramp_time=0.0, stale_after=100.0)
    ratios = []
    for i in range(800):
        t = (i + 1) * 1e-3
        result = haptic.step(start + (0.0 if t < 0.2 else 0.01 * (t - 0.2), 0.0, 0.0))
        if t > 0.5:
            ratios.append(result.raw_force[0] / result.raw_force[2])
    assert result.raw_force[2] > 0.3
    assert np.mean(ratios) == pytest.approx(-0.3, rel=0.02)


def test_rings_grow_the_buffer_to_the_whole_body():
    # Ring k adds the tets that share a node with ring k - 1; the block is connected, so enough
    # rings take every tet (6 per cube of the 6 x 6 x 3 grid).
    world, _, tool = pressed_block(tool_z=TOP + RADIUS)
    counts = []
    for rings in (1, 2, 3, 50):
        haptic = world.add_haptic(tool, rings=rings, radius=1e-6)
        counts.append(haptic.step((0.01, 0.01, TOP + RADIUS + 1e-3)).buffer_tets)
    assert counts[0] < counts[1] < counts[2] < counts[3] == 6 * 6 * 3 * 6
    capped = world.add_haptic(tool, rings=50, capacity_tets=100)
    assert capped.step((0.01, 0.01, TOP + RADIUS + 1e-3)).buffer_tets == 100
    assert capped.warnings["SH_WARN_CAPACITY"] >= 1


def test_static_solve_hands_its_equilibrium_to_the_haptic_side():
    # The static solve takes the tool to the device pose and the haptic side restarts from the
    # equilibrium as fresh data: its buffer, at equilibrium, renders the solve's force from its
    # first step.
    depth = 0.0015
    pose = (0.01, 0.01, TOP + RADIUS - depth)
    world, _, tool = pressed_block(tool_z=TOP + RADIUS)
    haptic = world.add_haptic(tool, radius=1.0, max_force_rate=1e6, ramp_time=0.0, stale_after=100.0)
    for _ in range(5):
        haptic.step(pose)
    assert haptic.step(pose).data_age > 5e-3
    world.solve_static(tolerance=1e-10, max_iterations=400)  # linear law: see above
    assert tool.pose[0] == pytest.approx(pose)
    result = haptic.step(pose)
    assert result.data_age == pytest.approx(1e-3)
    assert result.raw_force == pytest.approx(tool.force, rel=1e-3, abs=1e-6)


def _sphere_between_nodes(dt):
    """Force on a 1.5 mm sphere pressed 1 mm into the middle of a 1 cm face, undamped."""
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    body = world.add_fem_body(box_mesh((0.04, 0.04, 0.02), (4, 4, 2)), model="linear", young=5e3, poisson=0.3)
    body.fix_nodes(np.flatnonzero(np.abs(body.positions[:, 2]) < 1e-12))
    radius, at = 0.0015, (0.013, 0.007)
    tool = world.add_tool("sphere", radius=radius, position=(*at, 0.02 + radius), stiffness=1e4, exponent=1.0, damping=0.0)
    haptic = world.add_haptic(tool, radius=1.0, ramp_time=0.0, stale_after=100.0, max_force=100.0, max_force_rate=1e6)
    steps = int(round(0.4 / dt))
    forces = [haptic.step((*at, 0.02 + radius - 1e-3 * min(1.0, (i + 1) * dt / 0.1)), dt=dt).raw_force[2] for i in range(steps)]
    return np.array(forces[-steps // 4:])


def test_face_contact_sub_steps_hold_at_the_device_rate():
    # The sphere touches a triangle between its nodes: the sub-steps must count the face
    # contact's stiffness, so that a 1 kHz step gives what a ten times finer step gives.
    coarse, fine = _sphere_between_nodes(1e-3), _sphere_between_nodes(1e-4)
    assert fine.mean() > 0.05
    assert coarse.mean() == pytest.approx(fine.mean(), rel=0.05)
    assert np.abs(coarse).max() < 2.0 * np.abs(fine).max()


def test_buffer_is_cut_where_a_long_tool_touches():
    # A capsule tilted 45 degrees touches with its tip, 4 cm from its centre: the buffer (5 mm
    # radius) must be cut at the tip, and then it renders the full model's force (to 5 %: the
    # capsule pushes the nodes it covers only, and the small buffer around them, held at its
    # boundary, settles a little off the full model).
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    body = world.add_fem_body(
        box_mesh((0.05, 0.04, TOP), (10, 8, 2)), model="linear", young=5e3, poisson=0.3, density=1000.0,
        damping_mass=40.0,
    )
    body.fix_nodes(np.flatnonzero(np.abs(body.positions[:, 2]) < 1e-12))
    half_length, radius = 0.03, 0.002
    q = (math.cos(math.pi / 8), 0.0, math.sin(math.pi / 8), 0.0)  # 45 degrees about y
    axis = np.array([math.sin(math.pi / 4), 0.0, math.cos(math.pi / 4)])

    def centre(depth):
        return np.array([0.01, 0.02, TOP - depth + radius]) + half_length * axis

    tool = world.add_tool(
        "capsule", radius=radius, half_length=half_length, position=centre(-1e-3), orientation=q, stiffness=100.0,
        exponent=1.0, damping=0.0,
    )
    haptic = world.add_haptic(tool, radius=0.005, ramp_time=0.0, stale_after=100.0)
    for i in range(200):
        result = haptic.step(centre(min(1.0, (i + 1) / 100) * 1e-3), q)
        if i % 10 == 9:
            world.step(1e-2)
    assert result.contact and tool.force[2] > 0.01
    assert result.raw_force == pytest.approx(tool.force, rel=0.05, abs=1e-4)


def test_nodes_on_a_table_stay_with_the_full_model():
    # A block resting on a plane obstacle: the buffer models the tool's contact only, so the
    # nodes on the table follow the full model instead of falling through it, and the tool
    # feels what the full model feels (within the table's extra give there: 10 %).
    world = softhap.World(gravity=(0.0, 0.0, -9.81))
    body = world.add_fem_body(
        box_mesh((0.02, 0.02, TOP), (6, 6, 3)), model="linear", young=5e3, poisson=0.3, density=1000.0,
        damping_mass=40.0,
    )
    world.add_obstacle("plane", position=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0), stiffness=1e3, exponent=1.0)
    tool = world.add_tool("sphere", radius=RADIUS, position=(0.01, 0.01, 0.05), stiffness=100.0, exponent=1.0, damping=0.0)
    for _ in range(300):
        world.step(1e-3)
    top = body.positions[:, 2].max()
    pose = (*body.positions.mean(axis=0)[:2], top + RADIUS - 0.002)
    haptic = world.add_haptic(tool, radius=1.0, ramp_time=0.0, stale_after=100.0, max_force_rate=1e6)
    for _ in range(300):
        result = haptic.step(pose)
    tool.set_pose(pose)
    for _ in range(300):
        world.step(1e-3)
    assert result.buffer_tets == 6 * 6 * 3 * 6
    assert tool.force[2] > 0.02
    assert result.raw_force[2] == pytest.approx(tool.force[2], rel=0.1)


def test_result_holds_every_output_field_and_owns_its_arrays():
    """HapticResult is built field by field for speed: it must still carry every field of
    sh_haptic_output under its C name, equal to what the C call wrote (read back through
    ctypes), and its arrays must be its own (the next step does not change them)."""
    from softhap._lib import sh_haptic_output

    world, _, tool = pressed_block()
    haptic = world.add_haptic(tool, radius=0.005, ramp_time=0.0, stale_after=100.0)
    first = haptic.step((0.01, 0.01, TOP + RADIUS - 7e-4))
    raw = haptic._output  # what the C call wrote for this step
    names = {field[0] for field in sh_haptic_output._fields_}
    assert set(first) == names | {"fault_bits", "warning_bits"}
    for name in ("force", "torque", "raw_force"):
        assert list(first[name]) == list(getattr(raw, name))
    for name in ("buffer_tets", "buffer_nodes", "substeps", "data_age"):
        assert first[name] == getattr(raw, name)
    assert first.contact is bool(raw.contact) and first.contact
    assert (first.fault_bits, first.warning_bits) == (raw.faults, raw.warnings)
    kept = first.force.copy()
    second = haptic.step((0.01, 0.01, TOP + RADIUS - 9e-4))
    assert second.raw_force[2] > kept[2]
    assert np.array_equal(first.force, kept)
    faulty = haptic.step((math.nan, 0.0, 0.0))
    assert faulty.faults == frozenset({"SH_HAPTIC_FAULT_POSE"}) and faulty.fault_bits != 0


def _press_scene(stiffness, damping_mass):
    """A 1.5 mm sphere of the given stiffness (n = 1.5) above the middle of a 1 cm face of a
    linear 4 x 4 x 2 cm block: (world, tool, where it touches)."""
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    body = world.add_fem_body(box_mesh((0.04, 0.04, 0.02), (4, 4, 2)), model="linear", young=5e3, poisson=0.3,
                              damping_mass=damping_mass)
    body.fix_nodes(np.flatnonzero(np.abs(body.positions[:, 2]) < 1e-12))
    radius, at = 0.0015, (0.013, 0.007, 0.02 + 0.0015)
    tool = world.add_tool("sphere", radius=radius, position=at, stiffness=stiffness, exponent=1.5, damping=0.0)
    return world, tool, at


def _resting_press(stiffness):
    """The sphere pressed 1 mm in at 1 kHz through a whole-block buffer and held: (the most
    sub-steps of any tick, the force at the end, the full model's static force at that pose)."""
    world, tool, at = _press_scene(stiffness, 20.0)
    haptic = world.add_haptic(tool, radius=1.0, ramp_time=0.0, stale_after=100.0, max_force=100.0, max_force_rate=1e6)
    results = [haptic.step((at[0], at[1], at[2] - 1e-3 * min(1.0, (i + 1) / 100))) for i in range(1500)]
    reference, reference_tool, _ = _press_scene(stiffness, 0.0)
    reference_tool.set_pose((at[0], at[1], at[2] - 1e-3))
    reference.solve_static(tolerance=1e-9, max_iterations=400)
    return max(r.substeps for r in results), results[-1].raw_force[2], reference_tool.force[2]


def test_stiff_tool_needs_no_more_sub_steps_than_a_soft_one():
    # The contact is implicit along each contacted node's push: the sub-steps follow the
    # elements' critical step alone, whatever the tool's stiffness (an explicit contact needs
    # about sqrt(200) = 14 times more sub-steps for a 200 times stiffer law). At rest the force
    # is the full model's static solve's at the same pose (an independent computation: Newton
    # on the whole block's potential), soft or stiff.
    soft_substeps, soft_force, soft_static = _resting_press(1e3)
    stiff_substeps, stiff_force, stiff_static = _resting_press(2e5)
    assert stiff_substeps == soft_substeps
    assert soft_static > 0.005 and stiff_static > 2.0 * soft_static
    assert soft_force == pytest.approx(soft_static, rel=1e-5)
    assert stiff_force == pytest.approx(stiff_static, rel=1e-5)
