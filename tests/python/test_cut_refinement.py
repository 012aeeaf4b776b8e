"""A cutting tool refines coarse elements around its blade (sh_cut_def.resolution), so that
the opening follows the blade on meshes whose elements are larger than the cut: checked
against the area the blade sweeps (by hand), conservation, the surface's topology and the
locality of the refinement.

The block is box_mesh 2 x 1 x 1 cubes of 4 cm (0.08 x 0.04 x 0.04 m, 12 Kuhn tets, longest
edge the cube's diagonal, 6.9 cm) on a fixed base, without gravity. The scalpel's blade
reaches `depth` below the block's top and is dragged along x at y = 2.1 cm across the whole
block, 1 mm per step: it sweeps a rectangle 8 cm long and `depth` deep inside the block.
"""

import numpy as np
import pytest

import softhap
from mesh_checks import components, tet_volumes, triangle_areas
from test_contact import box_mesh
from test_cut import assert_conserves, assert_surface_ok, tet_quality

SIZE, CELLS = (0.08, 0.04, 0.04), (2, 1, 1)
LENGTH = 0.08  # m, the block's length along the drag
Y = 0.021  # m, the blade's plane
DENSITY = 1000.0  # kg/m^3, the default material's


def drag_scalpel(depth, resolution, steps=100):
    """Drags a blade reaching depth below the top through the coarse block; returns the body
    and the new surface area (m^2) the cut opened."""
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    body = world.add_fem_body(box_mesh(SIZE, CELLS))
    body.fix_nodes(np.where(body.positions[:, 2] < 1e-9)[0])
    top = SIZE[2]
    tool = world.add_tool("sphere", radius=0.0005, position=(-0.01, Y, top + 0.01))
    tool.set_cutting(edge=((0.0, 0.0, -0.01 - depth), (0.0, 0.0, 0.0)), resolution=resolution)
    area = triangle_areas(body.positions, body.surface_triangles).sum()
    for i in range(steps):
        tool.set_pose((-0.01 + 0.001 * (i + 1), Y, top + 0.01))
        world.step(1e-3)
    opened = triangle_areas(body.positions, body.surface_triangles).sum() - area
    return body, opened


def test_without_refinement_a_cut_shallower_than_an_element_opens_nothing():
    # A resolution above the elements' size refines nothing: a cut parts whole tet faces, and
    # no face of a 4 cm cube lies within a 1.3 cm deep sweep.
    body, opened = drag_scalpel(depth=0.013, resolution=1.0)
    assert opened == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("depth", [0.007, 0.013])
def test_refined_cut_opens_the_area_the_blade_swept(depth):
    # Refined to h = 5 mm, the opening (half the new surface: two walls) is the swept
    # rectangle LENGTH x depth, short by at most about h along its bottom and its two ends.
    h = 0.005
    body, opened = drag_scalpel(depth=depth, resolution=h)
    swept = LENGTH * depth
    assert opened / 2.0 <= swept * 1.02
    assert opened / 2.0 >= swept - h * (LENGTH + 2.0 * depth)
    assert components(body.node_count, body.tets)[1] == 1  # a groove: the block stays one piece
    assert_conserves(body, volume=np.prod(SIZE), mass=DENSITY * np.prod(SIZE))
    assert_surface_ok(body)
    # longest-edge bisection keeps shapes in a bounded family: no sliver appears
    assert tet_quality(body.positions, body.tets).min() > 0.03
    # growth in proportion to the swept area over h^2 (the bound the docs give)
    assert body.tet_count - 12 <= 300 * swept / h**2


def test_refinement_stays_near_the_blade():
    # Tets whose every node is farther than two of the block's longest edges (2 x 6.9 cm)
    # from the swept plane cannot exist here, so take a narrower block of cubes: 8 x 1 x 1
    # cells of 1 cm, blade 3 mm deep along the first 2 cm only. The far half of the block
    # (x > 6 cm) keeps its tets as they were.
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    body = world.add_fem_body(box_mesh((0.08, 0.01, 0.01), (8, 1, 1)))
    before = body.tets.copy()
    far = before[(body.positions[before][:, :, 0] > 0.06).all(axis=1)]
    tool = world.add_tool("sphere", radius=0.0005, position=(-0.005, 0.0055, 0.02))
    tool.set_cutting(edge=((0.0, 0.0, -0.013), (0.0, 0.0, 0.0)), resolution=0.002)
    for i in range(25):
        tool.set_pose((-0.005 + 0.001 * (i + 1), 0.0055, 0.02))
        world.step(1e-3)
    assert body.tet_count > len(before)  # it refined
    kept = {tuple(t) for t in body.tets}
    assert all(tuple(t) in kept for t in far)


def test_refined_through_cut_separates_the_block_in_two():
    # The blade reaches below the base: the block parts into two pieces, split at y = 2.1 cm
    # (by hand 0.08 x 0.021 x 0.04 and 0.08 x 0.019 x 0.04 m^3) to within the refinement's
    # reach, 5 mm x the section.
    body, _ = drag_scalpel(depth=0.041, resolution=0.005, steps=100)
    label, count, _ = components(body.node_count, body.tets)
    assert count == 2
    volumes = tet_volumes(body.positions, body.tets)
    centre_y = body.positions[body.tets].mean(axis=1)[:, 1]
    south = volumes[centre_y < Y].sum()
    assert south == pytest.approx(0.08 * 0.021 * 0.04, abs=0.005 * 0.08 * 0.04)
    assert_surface_ok(body)


def test_bad_resolution_is_refused():
    world = softhap.World()
    tool = world.add_tool("sphere", radius=0.001, position=(0.0, 0.0, 0.0))
    for bad in (-0.001, np.nan, np.inf):
        with pytest.raises(softhap.Error, match="resolution"):
            tool.set_cutting(resolution=bad)
