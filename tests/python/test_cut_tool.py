"""A cutting tool's blade separates what it sweeps through as the world steps."""

import numpy as np
import pytest

import softhap
from mesh_checks import triangle_areas
from test_contact import box_mesh


def components(tets, node_count):
    """Connected pieces of a tet mesh: tets joined through shared nodes (union-find)."""
    parent = np.arange(node_count)

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for tet in tets:
        for k in range(1, 4):
            a, b = find(tet[0]), find(tet[k])
            if a != b:
                parent[a] = b
    return len({find(i) for i in np.unique(tets)})


def scalpel_scene(depth, y=0.017):
    """A 10 x 4 x 2 cm block (1 cm cells) on a fixed base, without gravity, and a scalpel
    whose 3 cm blade reaches from its pose down to `depth` below the block's top (2 cm)."""
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    body = world.add_fem_body(box_mesh((0.1, 0.04, 0.02), (10, 4, 2)))
    body.fix_nodes(np.where(body.positions[:, 2] < 1e-9)[0])
    tool = world.add_tool("sphere", radius=0.0005, position=(-0.01, y, 0.03))
    tool.set_cutting(edge=((0.0, 0.0, -0.01 - depth), (0.0, 0.0, 0.0)))
    return world, body, tool


def drag(world, tool, y, steps, speed, dt=1e-3):
    """Moves the tool along +x at speed (m/s) for steps steps of dt; returns the reports."""
    reports = []
    for i in range(steps):
        tool.set_pose((-0.01 + speed * dt * (i + 1), y, 0.03))
        reports.append(world.step(dt))
    return reports


def test_blade_through_the_block_separates_it_in_two_equal_halves():
    # The blade reaches below the base (depth 2 cm + 1 mm) and travels the whole length at
    # 1 mm per step (a tenth of an element): the block must end in two pieces, their volumes
    # split at y = 1.7 cm (by hand: 0.1 x 0.017 x 0.02 and 0.1 x 0.023 x 0.02 m^3), give or
    # take the quarter element a cut may move to pass through nodes.
    world, body, tool = scalpel_scene(depth=0.021)
    mass = body.masses.sum()
    reports = drag(world, tool, 0.017, 130, speed=1.0)
    assert components(body.tets, body.node_count) == 2
    assert sum(r.cut_faces for r in reports) > 0
    # the steps that cut report time spent on it
    assert all(r.topology_seconds > 0.0 for r in reports if r.cut_faces > 0)
    assert body.masses.sum() == pytest.approx(mass, rel=1e-12)  # cutting conserves mass
    x, tets = body.positions, body.tets
    a, b, c, d = (x[tets[:, i]] for i in range(4))
    volume = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0
    south = (a + b + c + d)[:, 1] / 4.0 < 0.017
    assert volume[south].sum() == pytest.approx(0.1 * 0.017 * 0.02, abs=0.1 * 0.0025 * 0.02)
    assert volume.sum() == pytest.approx(0.1 * 0.04 * 0.02, rel=1e-9)


def test_shallow_blade_cuts_a_groove_and_the_block_stays_one_piece():
    # A blade 1 cm deep into a 2 cm block: a partial cut, so the block stays joined below it,
    # and the new faces add surface (the groove's two walls).
    world, body, tool = scalpel_scene(depth=0.01)
    triangles_before = body.info.surface_triangle_count
    drag(world, tool, 0.017, 130, speed=1.0)
    assert components(body.tets, body.node_count) == 1
    assert body.info.surface_triangle_count > triangles_before
    assert body.topology_version > 0


def test_a_tool_that_stops_cutting_cuts_nothing_more():
    world, body, tool = scalpel_scene(depth=0.021)
    tool.set_cutting(None)
    drag(world, tool, 0.017, 40, speed=1.0)
    assert body.topology_version == 0
    assert components(body.tets, body.node_count) == 1


def test_bad_cutting_definitions_are_refused_and_change_nothing():
    world, body, tool = scalpel_scene(depth=0.01)
    with pytest.raises(softhap.Error, match="coincide"):
        tool.set_cutting(edge=((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))
    with pytest.raises(softhap.Error, match="sharpness"):
        tool.set_cutting(sharpness=0.0)
    with pytest.raises(softhap.Error, match="edge"):
        tool.set_cutting(edge=((np.nan, 0.0, 0.0), (0.0, 0.0, 0.01)))
    with pytest.raises(ValueError):
        tool.set_cutting(criterion="laser")
    # The earlier, valid definition still cuts.
    drag(world, tool, 0.017, 130, speed=1.0)
    assert body.topology_version > 0


def blade_drag(radius, stiffness):
    """scripts/blade_drag.py's scene: an upright capsule of radius (m) with a contact law of
    stiffness (N/m^1.5), blade along its axis from z = 2 to 22 mm, drawn from x = -5 to 35 mm
    through a 4 x 4 x 2 cm corotational block of 15 kPa (bottom fixed, gravity, implicit Euler
    at 60 Hz, cut refined to 5 mm). Returns the world's warnings, the largest Newton iteration
    count and the surface area the cut opened (m^2)."""
    with softhap.World(gravity=(0.0, 0.0, -9.81)) as world:
        mesh = softhap.Mesh.box((0.04, 0.04, 0.02), (6, 6, 3))
        body = world.add_fem_body(mesh, model="corotational", young=15e3, poisson=0.45, integrator="implicit_euler")
        body.fix_nodes(np.flatnonzero(mesh.nodes[:, 2] == 0.0))
        area = triangle_areas(body.positions, body.surface_triangles).sum()
        start = np.array([-0.005, 0.017, 0.012])
        tool = world.add_tool("capsule", radius=radius, half_length=0.01, position=start, stiffness=stiffness)
        tool.set_cutting(edge=((0.0, 0.0, -0.01), (0.0, 0.0, 0.01)), resolution=0.005)
        newton = 0
        for i in range(60):
            tool.set_pose((start[0] + 0.04 * (i + 1) / 60, start[1], start[2]))
            newton = max(newton, world.step(1.0 / 60.0).newton_iterations)
        opened = triangle_areas(body.positions, body.surface_triangles).sum() - area
        return dict(world.warnings), newton, opened


@pytest.mark.parametrize("radius, stiffness", [(0.0005, 1e3), (0.002, 1e2)])
def test_thin_tool_within_the_stiffness_rule_cuts_without_substeps(radius, stiffness):
    """README's rule for a thin rounded tool: its sideways softening of the nodes it pushes,
    up to stiffness sqrt(radius) (22 and 4.5 N/m here), below about half the tissue's E h
    (15 kPa x 5 mm = 75 N/m). Drawn through its own slit, no step then needs a sub-step or
    hits the Newton cap (20 iterations for a body in contact), and the blade cuts the whole
    way: the opening (half the new surface, two walls) is the rectangle it swept inside the
    block, 3.5 x 1.8 cm, short by at most about h = 5 mm along its bottom and its two ends
    (test_cut_refinement's bound; the walls stand a little deformed, so 2 % over)."""
    warnings, newton, opened = blade_drag(radius, stiffness)
    assert warnings["SH_WARN_SUBSTEPPED"] == 0
    assert warnings["SH_WARN_NOT_CONVERGED"] == 0
    assert newton < 20
    length, depth, h = 0.035, 0.018, 0.005
    assert length * depth - h * (length + 2.0 * depth) <= opened / 2.0 <= 1.02 * length * depth
