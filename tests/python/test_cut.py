"""Cutting (Body.cut) against values from outside the code: hand-derived counts, areas and
volumes of a structured box bar cut by planes, conservation of mass and rest volume,
topology invariants of the boundary surface (closed, consistently oriented, edge- and
vertex-manifold, Euler characteristic of each piece), the node-parent rules of the header,
connected pieces, a cut piece falling freely under gravity, random cuts of organ meshes
(quality, critical step), mass-spring cuts and cuts that miss. The API surface (shapes, dtypes,
errors) is test_cut_api.py's.

The bar is box_mesh 2 x 2 x 10 cubes of 1 cm (0.02 x 0.02 x 0.1 m), six Kuhn tets per cube
(every edge runs from a corner towards +x, +y and/or +z); its default material is 1000 kg/m^3,
so its volume is 4e-5 m^3 and its mass 0.04 kg. A plane z = 0.055 cuts the middle of the
sixth cube layer: it crosses the 9 vertical edges, the 6 + 6 face diagonals that rise in x or
in y and the 4 body diagonals of that layer (25 edges) half way along.
"""

import numpy as np
import pytest

import softhap
from mesh_checks import (
    boundary_faces,
    canonical_rows,
    components,
    edge_positions,
    edge_problems,
    enclosed_volume,
    euler_characteristic,
    lumped_masses,
    mesh_edges,
    non_manifold_vertices,
    piece_surfaces,
    plane_crossings,
    plane_square,
    rectangle,
    root_nodes,
    tet_volumes,
    triangle_areas,
)
from test_contact import box_mesh
from textbook import G

DENSITY = 1000.0  # kg/m^3, sh_material_default's density (the bodies here keep it)
BAR_SIZE = (0.02, 0.02, 0.1)
BAR_CELLS = (2, 2, 10)
BAR_VOLUME = 0.02 * 0.02 * 0.1  # m^3
CROSS_SECTION = 0.02 * 0.02  # m^2, the bar's section by a plane z = const
SIDE_SECTION = 0.02 * 0.1  # m^2, its section by a plane x = const
REL = 1e-12  # round-off bound for sums over a few hundred tets


@pytest.fixture
def world():
    """An empty world without gravity, closed after the test."""
    with softhap.World(gravity=(0.0, 0.0, 0.0)) as w:
        yield w


def bar(world, **settings):
    """The 2 x 2 x 10 cm bar as an FEM body of world."""
    return world.add_fem_body(box_mesh(BAR_SIZE, BAR_CELLS), **settings)


def across(z):
    """A rectangle in the plane z = const reaching 1 cm past the bar on every side: a cut
    right through its cross-section."""
    return rectangle((-0.01, 0.03), (-0.01, 0.03), z)


def node_plane(body, axis, k):
    """The coordinate of the bar's k-th node plane along axis, as the nodes hold it."""
    return np.unique(body.positions[:, axis])[k]


def tet_quality(positions, tets):
    """6 sqrt(2) V / l_rms^3 of each tet (the header's quality: 1 regular, 0 flat)."""
    x = np.asarray(positions)[np.asarray(tets)]
    squares = [np.sum((x[:, j] - x[:, i]) ** 2, axis=1) for i in range(4) for j in range(i + 1, 4)]
    l_rms = np.sqrt(np.mean(squares, axis=0))
    return 6.0 * np.sqrt(2.0) * tet_volumes(positions, tets) / l_rms**3


def tilted(a, b, z=0.055):
    """The plane z = z0 + a (x - 1 cm) + b (y - 1 cm) through the bar's axis: its point and
    normal."""
    return (0.01, 0.01, z), (-a, -b, 1.0)


# Cuts of the bar, each a function of the body giving the triangles. The comment says what
# the cut crosses; every one is a single cut of the uncut bar.
BAR_CUTS = {
    # through the middle of the sixth cube layer: 25 edges crossed half way
    "mid_layer": lambda body: across(0.055),
    # the same layer, covering only x <= 1 cm (half the cross-section; border inside the bar)
    "partial": lambda body: rectangle((-0.01, 0.01), (-0.01, 0.03), 0.055),
    # exactly through the node plane z = 5 cm (9 nodes, no tet crossed)
    "node_plane_z": lambda body: across(node_plane(body, 2, 5)),
    # exactly through the node plane x = 1 cm along the bar (33 nodes)
    "node_plane_x": lambda body: plane_square((node_plane(body, 0, 1), 0.01, 0.05), (1, 0, 0), 0.2),
    # tilted about y by atan 0.1: the same 25 edges crossed, at 0.4 .. 0.6 of their length
    "tilted": lambda body: plane_square(*tilted(0.1, 0.0), 0.1),
    # tilted about both axes: the same 25 edges, crossed at 0.37 .. 0.63
    "tilted_2": lambda body: plane_square(*tilted(0.08, -0.05), 0.1),
    # tilted by atan 0.2: crossings at 0.3 .. 0.7; the cut goes through some nodes to keep
    # the pieces' critical step (not a quarter rule case, so no exact area is checked)
    "tilted_steep": lambda body: plane_square(*tilted(0.2, 0.0), 0.1),
    # z = 5.21 cm: every crossing is 0.21 of an edge from a node of the plane z = 5 cm
    "near_node_plane": lambda body: across(0.0521),
    # through the bar's axis at an odd angle, passing near many nodes
    "oblique": lambda body: plane_square((0.011, 0.009, 0.05), (1.0, 0.3, 0.2), 0.2),
}


def cut_bar(world, name, **settings):
    """A bar of world cut by BAR_CUTS[name]: (body, report, state before the cut as a dict of
    positions, tets, masses, surface and node count)."""
    body = bar(world, **settings)
    before = dict(
        positions=body.positions,
        tets=body.tets,
        masses=body.masses,
        surface=body.surface_triangles,
        node_count=body.node_count,
        version=body.topology_version,
    )
    report = body.cut(BAR_CUTS[name](body))
    return body, report, before


# ------------------------------------------------------------------------------------------
# checks shared by the tests


def piece_count(body):
    """Number of connected pieces of an FEM body (tets sharing a node are one piece)."""
    return components(body.node_count, body.tets)[1]


def assert_conserves(body, volume, mass):
    """Rest volume and mass of body equal volume and mass to round-off, every tet has positive
    rest volume, and each node's mass is its tets' density * V / 4 (mass split by volume)."""
    x, tets = body.positions, body.tets
    volumes = tet_volumes(x, tets)
    assert volumes.min() > 0.0  # the header: tets positively oriented (and none flat)
    assert volumes.sum() == pytest.approx(volume, rel=REL)  # pieces tile the tets they split
    masses = body.masses
    assert masses.sum() == pytest.approx(mass, rel=REL)  # a cut deletes no material
    # lumped mass: each tet's density * V shared by its four nodes
    np.testing.assert_allclose(masses, lumped_masses(x, tets, DENSITY), rtol=0, atol=REL * mass)


def assert_surface_ok(body, allowed_roots=()):
    """The body's surface is the boundary of its tets, closed (each edge in two triangles),
    consistently oriented (each directed edge once), vertex-manifold (except at vertices whose
    original node is in allowed_roots, defects of the uncut mesh), and faces outward: the
    volume it encloses, piece by piece, is the piece's tet volume."""
    x, tets, surface = body.positions, body.tets, body.surface_triangles
    # the boundary of the tet set: faces in one tet only, outward (counter-clockwise)
    np.testing.assert_array_equal(canonical_rows(surface), boundary_faces(tets))
    assert edge_problems(surface) == (0, 0)  # (edges not in 2 triangles, repeated directed edges)
    roots = root_nodes(body.node_parents)
    bad = [v for v in non_manifold_vertices(surface) if roots[v] not in set(allowed_roots)]
    assert bad == []  # every vertex's triangles are one fan
    tet_label, count, _ = components(body.node_count, tets)
    volumes = tet_volumes(x, tets)
    for k, triangles in enumerate(piece_surfaces(body.node_count, tets, surface)):
        # divergence theorem: an outward closed surface encloses its piece's volume
        piece_volume = volumes[tet_label == k].sum()
        assert enclosed_volume(x, triangles) == pytest.approx(piece_volume, rel=1e-9)


def assert_parents_ok(body, before):
    """The header's node rules after one cut of a body whose state was before: old nodes keep
    their index, position and parent; each new node's parent precedes it; a new node is a
    copy (at its parent's position) or lies on an edge of the body before the cut, its parent
    the nearer end, at least a quarter of the edge from either end."""
    n = before["node_count"]
    parents, x = body.node_parents, body.positions
    np.testing.assert_array_equal(x[:n], before["positions"])  # node indices never change
    old_parents = before.get("parents")
    if old_parents is None:
        np.testing.assert_array_equal(parents[:n], -1)  # the body's own nodes
    else:
        np.testing.assert_array_equal(parents[:n], old_parents)
    new = np.arange(n, len(parents))
    assert np.all(parents[new] >= 0)  # made from a node
    assert np.all(parents[new] < new)  # appended after its parent
    copy = np.all(x[new] == x[parents[new]], axis=1)  # a copy sits where its parent is
    made = new[~copy]
    assert np.all(parents[made] < n)  # a node made on an edge has an end of it as its parent
    # on an edge of the body before the cut, nearer its parent (distance <= 1/2), and at least
    # a quarter of the edge from the parent (nearer than that, the cut goes through the node)
    on_edge = edge_positions(x, made, parents[made], mesh_edges(before["tets"]))
    assert np.all(on_edge)


def test_the_checks_catch_defects():
    """The surface and mesh checks above (mesh_checks) fail on hand-made defective inputs, so
    that their passing on cut bodies means something."""
    x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1.0]])
    one = np.array([[0, 1, 2, 3]])
    surface = boundary_faces(one)
    assert len(surface) == 4 and edge_problems(surface) == (0, 0)
    assert enclosed_volume(x, surface) == pytest.approx(1 / 6)  # outward faces: + its volume
    assert edge_problems(surface[1:]) == (3, 0)  # a hole: three edges in one triangle
    flipped = surface.copy()
    flipped[0] = flipped[0, ::-1]
    assert edge_problems(flipped) == (0, 3)  # its three edges each run twice the same way
    assert enclosed_volume(x, surface[:, ::-1]) == pytest.approx(-1 / 6)  # inward
    assert euler_characteristic(surface) == 2  # 4 - 6 + 4
    # two tets sharing only node 0: one piece, and node 0 joins two fans
    bow = np.array([[0, 1, 2, 3], [0, 4, 6, 5]])
    assert tet_volumes(x, bow).min() > 0  # the premise: both positive
    bow_surface = boundary_faces(bow)
    assert list(non_manifold_vertices(bow_surface)) == [0]
    assert euler_characteristic(bow_surface) == 3  # 7 - 12 + 8: not a sphere
    assert components(7, bow)[1] == 1 and components(7, one)[1] == 1
    assert components(8, [[0, 1, 2, 3], [4, 5, 6, 7]])[1] == 2
    # a point on edge 0-1 of the tet a fraction f from node 0, parent 0
    for f, expected in ((0.2, False), (0.3, True), (0.5, True), (0.6, False)):
        y = np.vstack([x, [f, 0, 0]])
        assert edge_positions(y, [7], [0], mesh_edges(one))[0] == expected
    y = np.vstack([x, [0.3, 0.01, 0]])  # off the edge
    assert not edge_positions(y, [7], [0], mesh_edges(one))[0]


# ------------------------------------------------------------------------------------------
# 1, 2, 5: conservation, surface invariants and node parents for single cuts of the bar


@pytest.mark.parametrize("name", sorted(BAR_CUTS))
def test_bar_cut_conserves_mass_and_rest_volume(world, name):
    """Every kind of single cut conserves the bar's rest volume and mass to round-off."""
    body, report, before = cut_bar(world, name)
    assert report.nodes_added > 0  # each of these cuts does cut
    # hand values: 0.02 x 0.02 x 0.1 m at 1000 kg/m^3
    volume_before = tet_volumes(before["positions"], before["tets"]).sum()
    assert volume_before == pytest.approx(BAR_VOLUME, rel=REL)
    assert_conserves(body, BAR_VOLUME, DENSITY * BAR_VOLUME)


@pytest.mark.parametrize("name", sorted(BAR_CUTS))
def test_bar_cut_surface_is_a_closed_oriented_manifold(world, name):
    """After every kind of single cut the surface bounds the tets, closed, consistently
    oriented, vertex-manifold and outward."""
    body, report, before = cut_bar(world, name)
    assert report.faces_separated > 0
    assert body.info.surface_triangle_count > len(before["surface"])  # the cut faces are added
    assert_surface_ok(body)


@pytest.mark.parametrize("name", sorted(BAR_CUTS))
def test_bar_cut_node_parents_follow_the_header(world, name):
    """Node parents and positions after every kind of single cut follow the header's rules;
    node counts agree with the report and topology_version increases."""
    body, report, before = cut_bar(world, name)
    assert_parents_ok(body, before)
    assert report.nodes_moved == 0  # the old positions are unchanged (checked above)
    assert body.node_count == before["node_count"] + report.nodes_added  # the report's count
    assert body.tet_count == len(before["tets"]) + report.tets_added
    assert body.topology_version > before["version"]  # the header: increases if anything was cut


@pytest.mark.parametrize("name", sorted(BAR_CUTS))
def test_bar_cut_keeps_quality_and_critical_step(world, name):
    """Every kind of single cut reports min_quality >= 0.05, the lowest quality among the
    bar's tets after it, and keeps the explicit critical step >= 0.3 of the uncut bar's."""
    body = bar(world)
    dt_uncut = body.info.dt_critical
    assert 0 < dt_uncut < np.inf  # the premise: an explicit body (symplectic Euler)
    report = body.cut(BAR_CUTS[name](body))
    assert 0.05 <= report.min_quality <= 1.0  # the quality floor the cut keeps
    q = tet_quality(body.positions, body.tets)
    kuhn = np.sqrt(2.0) / (5.0 / 3.0) ** 1.5  # 6 sqrt 2 (1/6) / l_rms^3, l_rms^2 = (1+1+1+2+2+3)/6
    # the report's lowest (of the tets made) is the body's lowest, unless the Kuhn tets are
    assert q.min() == pytest.approx(min(report.min_quality, kuhn), rel=1e-9)
    assert body.info.dt_critical >= 0.3 * dt_uncut


def test_mid_layer_cut_counts_by_hand(world):
    """The plane z = 5.5 cm splits the layer's 24 Kuhn tets as worked out by hand."""
    body, report, _ = cut_bar(world, "mid_layer")
    # 25 crossed edges (module docstring): a point on each, and each point copied once
    assert report.nodes_added == 50
    # per cube, the 4 tets whose z step is first or last have 1 corner apart (a tet + a prism
    # of 3 tets: 4 pieces), the 2 whose z step is in the middle have 2 + 2 (two prisms: 6):
    # 28 pieces for 6 tets, 22 more per cube, 4 cubes
    assert report.tets_added == 88
    # each cube's section: 4 triangles and 2 quadrilaterals of 2 triangles: 8 faces, 4 cubes
    assert report.faces_separated == 32
    assert body.node_count == 99 + 50  # 3 x 3 x 11 nodes before
    assert 0.05 <= report.min_quality <= 1.0  # the quality floor the cut keeps


def test_node_plane_cut_counts_by_hand(world):
    """A cut exactly through the node plane z = 5 cm copies its 9 nodes and splits no tet."""
    body, report, _ = cut_bar(world, "node_plane_z")
    assert report.nodes_added == 9  # 3 x 3 nodes in the plane, each copied once
    assert report.tets_added == 0  # no tet crosses a node plane
    assert report.faces_separated == 8  # 4 cube faces of 2 triangles
    assert report.min_quality == 1.0  # the header: 1 if it made no tet


def test_near_node_plane_cut_goes_through_the_nodes(world):
    """z = 5.21 cm crosses every edge 0.21 of its length from the node plane z = 5 cm: within
    a quarter, so the cut goes through those nodes, as a cut exactly there does."""
    body = bar(world)
    edges = mesh_edges(body.tets)
    t = plane_crossings(body.positions, edges, (0, 0, 0.0521), (0, 0, 1))
    assert len(t) == 25 and np.all(np.minimum(t, 1 - t) < 0.25)  # the premise, checked
    report = body.cut(across(0.0521))
    assert (report.nodes_added, report.tets_added, report.faces_separated) == (9, 0, 8)  # as above


def test_cut_in_parallel_planes_gives_pieces_of_known_volume(world):
    """Three parallel cuts through cube middles make 4 slabs whose volumes, and whose surfaces'
    Euler characteristics (2: a sphere), are known by hand."""
    body = bar(world)
    for z in (0.025, 0.055, 0.085):
        body.cut(across(z))
        assert_surface_ok(body)
    x, tets = body.positions, body.tets
    label, count, _ = components(body.node_count, tets)
    assert count == 4  # three planes across a bar
    volumes = sorted(tet_volumes(x, tets[label == k]).sum() for k in range(count))
    # slabs 2.5, 3, 3 and 1.5 cm thick
    expected = sorted(CROSS_SECTION * h for h in (0.025, 0.03, 0.03, 0.015))
    np.testing.assert_allclose(volumes, expected, rtol=1e-12)
    for triangles in piece_surfaces(body.node_count, tets, body.surface_triangles):
        assert euler_characteristic(triangles) == 2  # each slab's surface is a sphere
    assert_conserves(body, BAR_VOLUME, DENSITY * BAR_VOLUME)


def crossing_cuts(body):
    """Cut body (the bar) across at z = 3.5 and 7.5 cm (cube middles) and then along it by a
    plane through x = 5 mm tilted slightly about z and y, crossing both."""
    body.cut(across(0.035))
    body.cut(across(0.075))
    body.cut(plane_square((0.005, 0.01, 0.05), (1.0, 0.04, 0.02), 0.2))


def test_crossing_cuts_give_pieces_each_a_sphere(world):
    """After two cuts across the bar and one along it, crossing them, every piece is bounded
    by a closed, oriented, manifold surface of Euler characteristic 2; mass and volume are
    conserved."""
    body = bar(world)
    crossing_cuts(body)
    surfaces = piece_surfaces(body.node_count, body.tets, body.surface_triangles)
    assert len(surfaces) >= 6  # at least 3 slabs, each split in two
    assert [euler_characteristic(t) for t in surfaces] == [2] * len(surfaces)  # spheres: V - E + F
    assert_surface_ok(body)
    assert_conserves(body, BAR_VOLUME, DENSITY * BAR_VOLUME)


def test_crossing_cuts_give_six_pieces(world):
    """Two planes across the bar and one along it, crossing both, cut it into 3 x 2 = 6
    pieces."""
    body = bar(world)
    crossing_cuts(body)
    assert piece_count(body) == 6  # 3 slabs, each split in two


def test_second_cut_along_the_same_surface_changes_nothing(world):
    """Cutting again along a surface already cut through separates nothing more."""
    body = bar(world)
    cut = plane_square(*tilted(0.2, 0.0), 0.1)
    body.cut(cut)
    version, tets = body.topology_version, body.tets
    report = body.cut(cut)
    # the material on the surface has already parted
    assert (report.nodes_added, report.tets_added, report.faces_separated) == (0, 0, 0)
    assert body.topology_version == version
    np.testing.assert_array_equal(body.tets, tets)


# ------------------------------------------------------------------------------------------
# 3: connected pieces, partial and progressive cuts


def test_partial_cut_leaves_one_piece(world):
    """A cut covering half the cross-section (x <= 1 cm) leaves the bar in one piece but does
    separate faces."""
    body = bar(world)
    report = body.cut(rectangle((-0.01, 0.01), (-0.01, 0.03), 0.055))
    assert report.faces_separated > 0  # something parted
    assert piece_count(body) == 1  # the header: where its border lies inside, it stays joined


def test_through_cut_gives_two_pieces(world):
    """A cut across the whole cross-section leaves two pieces, of hand-computed volume."""
    body = bar(world)
    body.cut(across(0.055))
    label, count, _ = components(body.node_count, body.tets)
    assert count == 2
    volumes = sorted(tet_volumes(body.positions, body.tets[label == k]).sum() for k in range(2))
    np.testing.assert_allclose(volumes, [CROSS_SECTION * 0.045, CROSS_SECTION * 0.055], rtol=1e-12)


@pytest.mark.parametrize("second", ["rest", "whole"])
def test_progressive_cut_extends_a_partial_cut(world, second):
    """A partial cut (x <= 1 cm) extended by a second cut over the rest of the section (x >= 1
    cm, or the whole section again) cuts the bar in two."""
    body = bar(world)
    body.cut(rectangle((-0.01, 0.01), (-0.01, 0.03), 0.055))
    assert piece_count(body) == 1
    x_from = 0.01 if second == "rest" else -0.01
    body.cut(rectangle((x_from, 0.03), (-0.01, 0.03), 0.055))
    assert piece_count(body) == 2  # the two cuts together cover the cross-section
    assert_surface_ok(body)
    assert_conserves(body, BAR_VOLUME, DENSITY * BAR_VOLUME)


def test_progressive_cut_extends_a_partial_cut_ending_inside_a_cube(world):
    """As above with the first cut's border inside a cube column (x = 1.05 cm) and the second
    covering exactly the rest: the two cuts together cover the section, so two pieces."""
    body = bar(world)
    body.cut(rectangle((-0.01, 0.0105), (-0.01, 0.03), 0.055))
    assert piece_count(body) == 1
    body.cut(rectangle((0.0105, 0.03), (-0.01, 0.03), 0.055))
    assert piece_count(body) == 2  # the header: a later cut extends it


def strips_across(body, z, width=0.004, start=-0.004, end=0.024):
    """Cuts body at the plane z in strips of width across x (each the part swept since the
    last, as a scripted blade would), each narrower than the bar's 1 cm elements; returns the
    faces each separated."""
    edges = np.arange(start, end + 1e-9, width)
    return [body.cut(rectangle((x0, x1), (-0.01, 0.03), z)).faces_separated for x0, x1 in zip(edges[:-1], edges[1:])]


def test_blade_advancing_in_small_increments_cuts_through(world):
    """A blade swept across the bar in 4 mm increments, covering the whole section in the
    end, cuts the bar in two (the header: a body keeps its programmatic cuts, so cuts narrower
    than an element add up): two pieces of the volumes a single cut at z = 5.5 cm gives (2 x 2
    x 5.5 cm and 2 x 2 x 4.5 cm), closed surfaces, mass and volume conserved. The first strip,
    inside the elements at the bar's side, parts nothing yet."""
    body = bar(world)
    faces = strips_across(body, 0.055)
    assert faces[0] == 0
    assert piece_count(body) == 2
    labels, _, _ = components(body.node_count, body.tets)[:3]
    volumes = np.bincount(labels, weights=tet_volumes(body.positions, body.tets))
    assert sorted(volumes) == pytest.approx(sorted([0.02 * 0.02 * 0.045, 0.02 * 0.02 * 0.055]), rel=1e-9)
    assert_surface_ok(body)
    assert_conserves(body, BAR_VOLUME, DENSITY * BAR_VOLUME)


def test_small_increments_stopping_short_leave_the_bar_joined(world):
    """The same strips stopped at x = 1.2 cm (0.8 cm short of the far side, inside its
    elements) leave the bar one piece, and a later strip crossing its far side completes it."""
    body = bar(world)
    strips_across(body, 0.055, end=0.012)
    assert piece_count(body) == 1
    body.cut(rectangle((0.012, 0.024), (-0.01, 0.03), 0.055))
    assert piece_count(body) == 2


def test_partial_cut_with_its_border_inside_a_cube_leaves_one_piece(world):
    """A cut covering x <= 1.6 cm of the 2 cm section leaves the bar joined (the header: where
    its border lies inside the body, the body stays joined)."""
    body = bar(world)
    body.cut(rectangle((-0.01, 0.016), (-0.01, 0.03), 0.055))
    assert piece_count(body) == 1


def test_partial_then_whole_plane_gives_two_pieces(world):
    """A partial cut of the plane z = 5.5 cm and then the whole plane: one plane cuts a bar in
    two pieces, not three."""
    body = bar(world)
    body.cut(rectangle((-0.01, 0.016), (-0.01, 0.03), 0.055))
    body.cut(across(0.055))
    assert piece_count(body) == 2


# ------------------------------------------------------------------------------------------
# 4: new surface area


def cut_area(world, name):
    """The bar's surface area gained by the cut BAR_CUTS[name] (m^2), the cut's report and the
    state before it (cut_bar)."""
    body, report, before = cut_bar(world, name)
    area_before = triangle_areas(before["positions"], before["surface"]).sum()
    area_after = triangle_areas(body.positions, body.surface_triangles).sum()
    return area_after - area_before, report, before


@pytest.mark.parametrize(
    "name, section",
    [
        ("mid_layer", CROSS_SECTION),  # the plane z = const cuts a 2 x 2 cm square
        ("tilted", CROSS_SECTION * np.sqrt(1 + 0.1**2)),  # the square / cos(tilt)
        ("tilted_2", CROSS_SECTION * np.sqrt(1 + 0.08**2 + 0.05**2)),  # / cos of the normal's tilt
    ],
)
def test_planar_cut_through_no_node_adds_twice_the_section(world, name, section):
    """A plane that passes through no node, every crossing between a quarter and three
    quarters of its edge, is followed exactly: the surface grows by both faces of the
    section (hand-computed) within 1e-9, and the split is the mid-layer one."""
    gained, report, before = cut_area(world, name)
    point, normal = {
        "mid_layer": ((0, 0, 0.055), (0, 0, 1)),
        "tilted": tilted(0.1, 0.0),
        "tilted_2": tilted(0.08, -0.05),
    }[name]
    t = plane_crossings(before["positions"], mesh_edges(before["tets"]), point, normal)
    assert len(t) == 25 and np.all((t > 0.25) & (t < 0.75))  # the premise: no snapping allowed
    assert gained == pytest.approx(2 * section, rel=1e-9)  # both sides of the section
    # the plane separates the same corners as mid_layer: the same hand counts
    assert (report.nodes_added, report.tets_added, report.faces_separated) == (50, 88, 32)


@pytest.mark.parametrize(
    "name, section",
    [
        ("node_plane_z", CROSS_SECTION),
        ("node_plane_x", SIDE_SECTION),
        ("near_node_plane", CROSS_SECTION),
    ],
)
def test_cut_through_a_node_plane_adds_exactly_twice_the_section(world, name, section):
    """A cut through a plane of nodes (or within a quarter edge of one) parts the faces in
    that plane: the surface grows by exactly twice that section."""
    gained, _, _ = cut_area(world, name)
    assert gained == pytest.approx(2 * section, rel=REL)  # 2 x 2 cm or 2 x 10 cm, both faces


# ------------------------------------------------------------------------------------------
# 6: a cut piece falls freely


def hanging_bar(world, **settings):
    """The bar with its top nodes (z = 10 cm) fixed."""
    body = bar(world, **settings)
    body.fix_nodes(np.flatnonzero(body.positions[:, 2] > 0.1 - 1e-9))
    return body


def centre_of_mass(body, nodes):
    m = body.masses[nodes]
    return (m @ body.positions[nodes]) / m.sum(), (m @ body.velocities[nodes]) / m.sum()


@pytest.mark.parametrize("loaded", [False, True], ids=["at_rest", "sagging"])
@pytest.mark.parametrize(
    "integrator, model, dt",
    [
        ("implicit_euler", "corotational", 1e-3),
        ("implicit_euler", "stvk", 5e-3),
        ("symplectic_euler", "corotational", None),  # None: half the cut body's critical step
        ("rk4", "stvk", None),
    ],
)
def test_cut_off_lower_half_of_a_hanging_bar_falls_at_g(integrator, model, dt, loaded):
    """A bar hanging from its top is stepped 5 steps (without gravity, so that it is still at
    rest, or with gravity, so that it sags and moves), then cut through at z = 5.5 cm and
    stepped on for 0.1 s under gravity. The lower piece is free (its internal forces sum to
    zero), so its centre of mass follows the integrator's update of constant acceleration g
    exactly; the upper piece hangs on. The steps after the cut run through the world's
    topology change (workspaces, solver state)."""
    with softhap.World(gravity=(0.0, 0.0, -G if loaded else 0.0)) as world:
        body = hanging_bar(world, model=model, integrator=integrator, on_unstable="reject")
        explicit = integrator != "implicit_euler"
        for _ in range(5):  # the world's solver state and workspaces exist before the cut
            world.step(0.5 * body.info.dt_critical if explicit else dt)
        world.gravity = (0.0, 0.0, -G)
        body.cut(across(0.055))
        if explicit:
            assert body.info.dt_critical < np.inf
            n = int(np.ceil(0.1 / (0.5 * body.info.dt_critical)))
            dt = 0.1 / n  # below the cut body's critical step: "reject" would raise above it
        else:
            n = int(round(0.1 / dt))
        _, count, node_label = components(body.node_count, body.tets)
        assert count == 2
        lower_label = node_label[np.argmin(body.positions[:, 2])]
        lower = np.flatnonzero(node_label == lower_label)
        upper = np.flatnonzero((node_label >= 0) & (node_label != lower_label))
        if not loaded:  # cut at rest: the lower piece is the bar's lowest 5.5 cm
            lower_mass = body.masses[lower].sum()
            assert lower_mass == pytest.approx(DENSITY * CROSS_SECTION * 0.055, rel=REL)
        c0, v0 = centre_of_mass(body, lower)
        u0, _ = centre_of_mass(body, upper)
        for _ in range(n):
            report = world.step(dt)  # raises on any failure
            assert report.substeps == 1
        c, v = centre_of_mass(body, lower)
        u, _ = centre_of_mass(body, upper)
        t = n * dt
        if integrator == "rk4":
            drop = -v0[2] * t + G * t * t / 2  # RK4 is exact for constant acceleration
        else:
            # v_k = v_0 - k g dt and x_{k+1} = x_k + dt v_{k+1} (implicit and symplectic Euler)
            drop = -v0[2] * t + G * dt * dt * n * (n + 1) / 2
        assert c0[2] - c[2] == pytest.approx(drop, rel=1e-9)
        assert v[2] == pytest.approx(v0[2] - G * t, rel=1e-9)  # momentum gains m g t
        # no sideways force: the sideways centre moves at its velocity at the cut
        np.testing.assert_allclose(c[:2], c0[:2] + v0[:2] * t, rtol=0, atol=1e-12)
        if not loaded:  # from rest: g t^2 / 2, within the Euler updates' n (n + 1) / n^2 <= 1.05
            assert c0[2] - c[2] == pytest.approx(G * t * t / 2, rel=0.06)
        assert np.linalg.norm(u - u0) < 0.05 * (c0[2] - c[2])  # the upper piece hangs on
        assert np.all(np.isfinite(body.positions))


# ------------------------------------------------------------------------------------------
# 1, 2, 5, 7: random plane cuts of organ meshes


def random_cuts(rng, body, count=10):
    """count random plane cuts of body, alternately partial and through: each plane passes
    through the centroid of a random tet with a random normal; a partial cut covers the half
    of it on one side of a line through that point. A list of (partial, triangles)."""
    x, tets = body.positions, body.tets
    size = np.linalg.norm(x.max(axis=0) - x.min(axis=0))
    cuts = []
    for k in range(count):
        centre = x[tets[rng.integers(len(tets))]].mean(axis=0)
        normal = rng.normal(size=3)
        partial = k % 2 == 0
        strip = (-2 * size, 0.0) if partial else None
        cuts.append((partial, plane_square(centre, normal, 2 * size, strip)))
    return cuts


ORGANS = {
    # liver2 in cm-ish units scaled to 21 cm, as test_organ_scenes.py loads it
    "liver2": ("liver2.msh", 0.1, 20240611),
    # the armadillo, about 13 units across, scaled to 13 cm
    "armadillo": ("Armadillo_Tetra_4406.vtu", 0.01, 7),
}


@pytest.fixture(scope="module", params=sorted(ORGANS))
def organ_cuts(request, meshes):
    """An organ mesh cut by 10 random planes (5 partial, 5 through; seeded). Records, for the
    uncut body and after each cut, what the tests below check."""
    name, scale, seed = ORGANS[request.param]
    with softhap.Mesh.load(meshes / name) as raw:
        mesh = raw.transform(scale)
    with softhap.World(gravity=(0.0, 0.0, 0.0)) as world:
        body = world.add_fem_body(mesh, model="corotational", young=3e3, poisson=0.45,
                                  density=DENSITY)
        uncut = dict(
            volume=tet_volumes(body.positions, body.tets).sum(),
            mass=body.masses.sum(),
            dt=body.info.dt_critical,
            non_manifold=set(non_manifold_vertices(body.surface_triangles)),
            quality=tet_quality(body.positions, body.tets).min(),
        )
        steps = []
        for partial, triangles in random_cuts(np.random.default_rng(seed), body):
            before = dict(
                positions=body.positions, tets=body.tets, node_count=body.node_count,
                parents=body.node_parents, version=body.topology_version,
            )
            report = body.cut(triangles)
            failures = []
            for check in (
                lambda: assert_conserves(body, uncut["volume"], uncut["mass"]),
                lambda: assert_surface_ok(body, uncut["non_manifold"]),
                lambda: assert_parents_ok(body, before),
            ):
                try:
                    check()
                except AssertionError as exc:
                    failures.append(str(exc))
            steps.append(dict(
                partial=partial, report=report, before=before, failures=failures,
                version=body.topology_version, dt=body.info.dt_critical,
                quality=tet_quality(body.positions, body.tets),
                tet_count=body.tet_count, node_count=body.node_count,
            ))
        yield request.param, uncut, steps


def test_organ_random_cuts_conserve_and_keep_the_surface(organ_cuts):
    """After each of 10 random cuts: mass and rest volume conserved to round-off, positive
    tets, lumped masses by volume, surface closed, oriented, manifold (no new non-manifold
    vertex), node parents per the header (see assert_conserves, assert_surface_ok,
    assert_parents_ok)."""
    name, _, steps = organ_cuts
    assert [s["failures"] for s in steps] == [[]] * len(steps)
    # the cuts do cut: every through cut and most partial ones change the topology
    through = [s for s in steps if not s["partial"]]
    assert all(s["report"].nodes_added > 0 for s in through)
    assert sum(s["report"].nodes_added > 0 for s in steps) >= 8


def test_organ_random_cuts_keep_quality_and_critical_step(organ_cuts):
    """Each random cut reports min_quality >= 0.05, the lowest quality of the tets it made (no
    tet is below it, but for tets older than the cut), and the cut body's critical step stays
    >= 0.3 of the uncut body's."""
    name, uncut, steps = organ_cuts
    floor = uncut["quality"]  # the lowest quality before the cut
    for s in steps:
        report = s["report"]
        assert report.min_quality >= 0.05  # the quality floor the cut keeps
        q = s["quality"]
        # no tet below both the reported lowest made and the lowest before the cut
        assert q.min() >= min(report.min_quality, floor) - 1e-9
        floor = q.min()
        if report.tets_added > 0:
            # the reported lowest quality is that of a tet of the body
            assert np.min(np.abs(q - report.min_quality)) < 1e-9
        assert s["dt"] >= 0.3 * uncut["dt"]  # critical step kept within 0.3 of the uncut one
        # version moves iff something was cut
        changed = report.nodes_added > 0 or report.tets_added > 0
        assert (s["version"] > s["before"]["version"]) == changed


# ------------------------------------------------------------------------------------------
# 8: mass-spring bodies


def spring_grid():
    """A 4 x 4 grid of nodes 1 cm apart in the plane z = 0, node 4 i + j at (i, j) cm, with
    springs along the rows and columns and both diagonals of every square (42 springs), and
    node masses 1 .. 2 g."""
    nodes = np.array([[0.01 * i, 0.01 * j, 0.0] for i in range(4) for j in range(4)])
    springs = []
    for i in range(4):
        for j in range(4):
            if i < 3:
                springs.append((4 * i + j, 4 * (i + 1) + j))
            if j < 3:
                springs.append((4 * i + j, 4 * i + j + 1))
            if i < 3 and j < 3:
                springs.append((4 * i + j, 4 * (i + 1) + j + 1))
                springs.append((4 * (i + 1) + j, 4 * i + j + 1))
    return nodes, springs, np.linspace(1e-3, 2e-3, 16)


@pytest.mark.parametrize(
    "name, triangles, lost",
    [
        # x = 1.5 cm: the 4 springs from column 1 to 2 and the 6 diagonals of those 3 squares
        ("through", plane_square((0.015, 0.015, 0.0), (1, 0, 0), 0.1),
         {(4, 8), (5, 9), (6, 10), (7, 11), (4, 9), (8, 5), (5, 10), (9, 6), (6, 11), (10, 7)}),
        # x = 1.5 cm for y <= 1.2 cm: rows y = 0, 1 cm and the diagonals crossing at y = 0.5 cm
        ("partial", np.array([[[0.015, -1, -1], [0.015, 0.012, -1], [0.015, 0.012, 1]],
                              [[0.015, -1, -1], [0.015, 0.012, 1], [0.015, -1, 1]]]),
         {(4, 8), (5, 9), (4, 9), (8, 5)}),
    ],
)
def test_spring_cut_removes_exactly_the_crossed_springs(world, name, triangles, lost):
    """A plane cut of a spring grid removes the springs it crosses (counted by hand), keeps
    every node and its mass, and bumps topology_version."""
    nodes, springs, masses = spring_grid()
    body = world.add_spring_body(nodes, springs=springs, mass=masses)
    report = body.cut(triangles)
    assert report.springs_cut == len(lost)  # hand count
    remaining = {tuple(s) for s in body.springs.tolist()}
    assert remaining == set(springs) - lost
    np.testing.assert_array_equal(body.masses, masses)  # springs carry no mass
    np.testing.assert_array_equal(body.positions, nodes)
    np.testing.assert_array_equal(body.node_parents, -1)  # no node made
    assert body.node_count == 16
    assert body.topology_version >= 1
    assert (report.nodes_added, report.tets_added, report.faces_separated) == (0, 0, 0)


def test_cut_spring_chain_end_falls_at_g():
    """A vertical chain of 6 nodes hanging from its top node, cut between nodes 2 and 3: the
    lower 3 nodes fall freely (implicit Euler's exact discrete fall), the upper part hangs."""
    dt, n = 1e-3, 100
    nodes = [[0.0, 0.0, -0.01 * k] for k in range(6)]
    with softhap.World(gravity=(0.0, 0.0, -G)) as world:
        body = world.add_spring_body(nodes, springs=[[k, k + 1] for k in range(5)],
                                     stiffness=100.0, mass=1e-3, integrator="implicit_euler")
        body.fix_nodes([0])
        world.step(dt)
        report = body.cut(plane_square((0.0, 0.0, -0.025), (0.0, 0.2, 1.0), 0.1))
        assert report.springs_cut == 1  # only spring 2-3 crosses z = -2.5 cm
        x0, v0 = body.positions, body.velocities
        for _ in range(n):
            world.step(dt)
        x = body.positions
        c0, c, cv = x0[3:, 2].mean(), x[3:, 2].mean(), v0[3:, 2].mean()  # equal masses
        # implicit Euler on the free part's centre: x_{k+1} = x_k + dt v_{k+1}, v_k = v_0 - k g dt
        assert c0 - c == pytest.approx(-cv * n * dt + G * dt * dt * n * (n + 1) / 2, rel=1e-9)
        assert abs(x[1:3, 2].mean() - x0[1:3, 2].mean()) < 0.1 * (c0 - c)  # the rest hangs on


# ------------------------------------------------------------------------------------------
# 9: cuts that miss


MISSES = {
    "far away": plane_square((1.0, 1.0, 1.0), (0, 0, 1), 0.1),
    # the plane of the bar's face x = 0: no material on it
    "on a face": plane_square((0.0, 0.01, 0.05), (1, 0, 0), 0.2),
    # x + y = -0.5 mm: inside the bar's bounding box range, outside the bar
    "beside": plane_square((-0.0005, -0.0005, 0.05), (1, 1, 0), 0.2),
    # a small triangle inside one tet, crossing no edge
    "inside a tet": np.array(
        [[[0.0051, 0.0031, 0.0551], [0.0053, 0.0031, 0.0551], [0.0051, 0.0034, 0.0552]]]
    ),
}


@pytest.mark.parametrize("name", sorted(MISSES))
def test_cut_that_separates_nothing_changes_nothing(world, name):
    """A cut that passes through no material (or crosses no edge) leaves the body as it was,
    topology_version included, and reports zeros."""
    body = bar(world)
    before = (body.positions, body.tets, body.surface_triangles, body.masses)
    report = body.cut(MISSES[name])
    assert body.topology_version == 0
    assert body.node_count == 99
    for old, new in zip(before, (body.positions, body.tets, body.surface_triangles, body.masses)):
        np.testing.assert_array_equal(new, old)
    counts = (report.faces_separated, report.nodes_added, report.tets_added, report.nodes_moved,
              report.springs_cut)
    assert counts == (0, 0, 0, 0, 0)
    assert report.min_quality == 1.0  # the header: 1 if it made no tet


def test_spring_cut_that_misses_changes_nothing(world):
    """A plane beside a spring grid removes no spring and keeps topology_version."""
    nodes, springs, masses = spring_grid()
    body = world.add_spring_body(nodes, springs=springs, mass=masses)
    report = body.cut(plane_square((0.035, 0.0, 0.0), (1, 0, 0), 0.1))
    assert report.springs_cut == 0
    assert body.topology_version == 0
    assert {tuple(s) for s in body.springs.tolist()} == set(springs)


# ------------------------------------------------------------------------------------------
# 10: cut, contact and stepping in one scene


def test_cut_box_on_a_plane_under_a_sphere_steps_on():
    """A box resting on a plane obstacle, pressed by a sphere tool, is cut through between
    steps; 20 more implicit steps run without error, both pieces stay on the plane and the
    tool still feels the body."""
    with softhap.World(gravity=(0.0, 0.0, -G)) as world:
        box = box_mesh((0.04, 0.04, 0.02), (4, 4, 2), origin=(-0.02, -0.02, 0.0005))
        body = world.add_fem_body(box, model="corotational", young=3e4, integrator="implicit_euler",
                                  damping_mass=5.0)
        world.add_obstacle("plane", position=(0, 0, 0), normal=(0, 0, 1), stiffness=1e4)
        tool = world.add_tool("sphere", radius=0.01, position=(0.005, 0.003, 0.0305), stiffness=1e3)
        z_tool = 0.0305
        for _ in range(10):
            z_tool -= 2e-4
            tool.set_pose((0.005, 0.003, z_tool))
            world.step(5e-3)
        assert tool.force[2] > 0  # the premise: the tool presses on the box
        report = body.cut(plane_square((0.0051, 0.0003, 0.01), (1.0, 0.05, 0.0), 0.1))
        assert report.nodes_added > 0
        for _ in range(20):
            z_tool -= 1e-4
            tool.set_pose((0.005, 0.003, z_tool))
            step = world.step(5e-3)  # raises on a failed step
        x = body.positions
        assert np.all(np.isfinite(x))
        label, count, node_label = components(body.node_count, body.tets)
        assert count == 2  # the cut went through
        for k in range(count):
            assert x[node_label == k, 2].min() > -2e-3  # each piece is held by the plane
        assert step.contact_count > 0
        assert tool.force[2] > 0  # the tool still pushes on the cut body
        assert_surface_ok(body)
