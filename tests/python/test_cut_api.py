"""The Python surface of cutting and topology queries (Body.cut, tets, springs,
surface_triangles, node_parents, tet_count, topology_version, CutReport): shapes, dtypes, errors
and that the arrays follow the current topology. What a cut does physically is tested
elsewhere."""

import numpy as np
import pytest

import softhap

CUT_REPORT_FIELDS = {
    "faces_separated",
    "nodes_added",
    "tets_added",
    "nodes_moved",
    "min_quality",
    "seconds",
    "springs_cut",
    "reserved",
}


@pytest.fixture
def liver(meshes):
    """The liver mesh (181 nodes, 596 tets)."""
    with softhap.Mesh.load(meshes / "liver.msh") as mesh:
        yield mesh


@pytest.fixture
def world():
    """An empty world, closed after the test."""
    with softhap.World() as w:
        yield w


def slicing_plane(mesh, fraction=0.37):
    """Two triangles, a (2, 3, 3) array (m), spanning the plane x = const at fraction of the
    mesh's x extent, reaching well past the mesh on every side: a cut right through it."""
    lo, hi = np.array(mesh.info.bounds_min), np.array(mesh.info.bounds_max)
    x = lo[0] + fraction * (hi[0] - lo[0])
    margin = hi - lo
    y0, y1 = lo[1] - margin[1], hi[1] + margin[1]
    z0, z1 = lo[2] - margin[2], hi[2] + margin[2]
    a, b, c, d = [x, y0, z0], [x, y1, z0], [x, y1, z1], [x, y0, z1]
    return np.array([[a, b, c], [a, c, d]], dtype=np.float64)


# ------------------------------------------------------------------------------------------
# an uncut body


def test_uncut_fem_body_arrays_are_the_meshs(world, liver):
    body = world.add_fem_body(liver)
    tets = body.tets
    assert tets.dtype == np.int32 and tets.shape == (596, 4)
    np.testing.assert_array_equal(tets, liver.tets)
    assert body.tet_count == 596

    surface = body.surface_triangles
    assert surface.dtype == np.int32
    assert surface.shape == (liver.info.surface_triangle_count, 3)
    np.testing.assert_array_equal(surface, liver.surface_triangles)

    parents = body.node_parents
    assert parents.dtype == np.int32 and parents.shape == (181,)
    np.testing.assert_array_equal(parents, -1)
    assert body.node_count == 181
    assert body.topology_version == 0


def test_body_info_has_the_topology_fields(world, liver):
    info = world.add_fem_body(liver).info
    assert info.surface_triangle_count == liver.info.surface_triangle_count
    assert info.topology_version == 0
    assert info.reserved == 0
    assert isinstance(info, softhap.BodyInfo)


def test_arrays_are_copies(world, liver):
    body = world.add_fem_body(liver)
    body.tets[:] = 0
    body.surface_triangles[:] = 0
    body.node_parents[:] = 7
    np.testing.assert_array_equal(body.tets, liver.tets)
    np.testing.assert_array_equal(body.surface_triangles, liver.surface_triangles)
    np.testing.assert_array_equal(body.node_parents, -1)


def test_spring_body_springs_and_parents(world, meshes):
    with softhap.Mesh.load(meshes / "single_tetra.msh") as mesh:
        body = world.add_spring_body(mesh, springs=[[0, 1], [2, 3]])
    springs = body.springs
    assert springs.dtype == np.int32
    np.testing.assert_array_equal(springs, [[0, 1], [2, 3]])
    np.testing.assert_array_equal(body.node_parents, [-1, -1, -1, -1])
    assert body.topology_version == 0
    assert body.info.surface_triangle_count == 0


# ------------------------------------------------------------------------------------------
# the wrong kind of body


def assert_unsupported(read, needle):
    with pytest.raises(softhap.Error) as caught:
        read()
    assert caught.value.status == softhap.Status.SH_ERR_UNSUPPORTED
    assert needle in caught.value.message


def test_fem_only_properties_refuse_a_spring_body(world):
    body = world.add_spring_body([[0, 0, 0], [0.01, 0, 0]], springs=[[0, 1]])
    assert_unsupported(lambda: body.tets, "mass-spring")
    assert_unsupported(lambda: body.surface_triangles, "mass-spring")
    assert_unsupported(lambda: body.tet_count, "mass-spring")


def test_springs_refuse_an_fem_body(world, liver):
    body = world.add_fem_body(liver)
    assert_unsupported(lambda: body.springs, "FEM")


# ------------------------------------------------------------------------------------------
# Body.cut arguments


@pytest.mark.parametrize(
    "shape", [(3, 3), (9,), (2, 3), (1, 3, 2), (1, 8), (1, 9, 1), (2, 2, 3, 3)]
)
def test_cut_with_a_wrong_shape_is_a_value_error(world, liver, shape):
    body = world.add_fem_body(liver)
    with pytest.raises(ValueError, match="triangles"):
        body.cut(np.zeros(shape))
    assert body.topology_version == 0


def test_cut_with_non_numbers_is_a_value_error(world, liver):
    body = world.add_fem_body(liver)
    with pytest.raises(ValueError, match="triangles"):
        body.cut([["a", "b", "c"]])


def test_cut_with_no_triangle_is_invalid_argument(world, liver):
    body = world.add_fem_body(liver)
    for empty in (np.zeros((0, 3, 3)), np.zeros((0, 9))):
        with pytest.raises(softhap.Error) as caught:
            body.cut(empty)
        assert caught.value.status == softhap.Status.SH_ERR_INVALID_ARGUMENT
        assert "triangle_count" in caught.value.message
        assert caught.value.function == "sh_body_cut"


def test_cut_of_a_removed_body_or_closed_world_is_invalid_handle(liver):
    with softhap.World() as world:
        body = world.add_fem_body(liver)
        world.remove_body(body)
        with pytest.raises(softhap.Error) as caught:
            body.cut(slicing_plane(liver))
        assert caught.value.status == softhap.Status.SH_ERR_INVALID_HANDLE
    with pytest.raises(softhap.Error) as caught:
        body.cut(slicing_plane(liver))
    assert caught.value.status == softhap.Status.SH_ERR_INVALID_HANDLE


def test_cut_with_a_non_finite_corner_is_invalid_argument(world, liver):
    body = world.add_fem_body(liver)
    triangles = slicing_plane(liver)
    triangles[1, 2, 0] = np.nan
    with pytest.raises(softhap.Error) as caught:
        body.cut(triangles)
    assert caught.value.status == softhap.Status.SH_ERR_INVALID_ARGUMENT
    assert body.topology_version == 0
    np.testing.assert_array_equal(body.tets, liver.tets)


# ------------------------------------------------------------------------------------------
# after a cut: the arrays follow the new topology


def test_cut_returns_a_cut_report(world, liver):
    body = world.add_fem_body(liver)
    report = body.cut(slicing_plane(liver))
    assert isinstance(report, softhap.CutReport)
    assert set(report) == CUT_REPORT_FIELDS
    assert report.faces_separated > 0
    assert report.nodes_added > 0
    assert 0.0 < report.min_quality <= 1.0
    assert report.seconds >= 0.0


def test_arrays_follow_the_topology_after_a_cut(world, liver):
    body = world.add_fem_body(liver)
    report = body.cut(slicing_plane(liver))
    assert body.topology_version >= 1
    n = 181 + report.nodes_added
    assert body.node_count == n
    assert body.positions.shape == (n, 3)
    assert body.masses.shape == (n,)
    tets = body.tets
    assert tets.shape == (596 + report.tets_added, 4) and tets.dtype == np.int32
    assert body.tet_count == tets.shape[0]
    assert tets.min() >= 0 and tets.max() < n
    surface = body.surface_triangles
    assert surface.shape == (body.info.surface_triangle_count, 3)
    assert surface.shape[0] > liver.info.surface_triangle_count
    assert surface.max() < n
    parents = body.node_parents
    assert parents.shape == (n,) and parents.dtype == np.int32
    np.testing.assert_array_equal(parents[:181], -1)
    new = np.arange(181, n)
    assert np.all((parents[new] >= 0) & (parents[new] < new))  # appended after its parent


def test_cut_takes_k_by_9_rows_like_k_by_3_by_3(liver):
    triangles = slicing_plane(liver)
    results = []
    for form in (triangles, triangles.reshape(-1, 9), triangles.tolist()):
        with softhap.World() as world:
            body = world.add_fem_body(liver)
            report = body.cut(form)
            results.append((report.nodes_added, report.tets_added, body.tets, body.node_parents))
    for other in results[1:]:
        assert other[:2] == results[0][:2]
        np.testing.assert_array_equal(other[2], results[0][2])
        np.testing.assert_array_equal(other[3], results[0][3])


def test_springs_follow_the_topology_after_a_cut(world):
    body = world.add_spring_body(
        [[0, 0, 0], [0.01, 0, 0], [0.01, 0.01, 0]], springs=[[0, 1], [1, 2]]
    )
    # The plane x = 5 mm crosses spring 0-1 only.
    a, b, c, d = [0.005, -1, -1], [0.005, 1, -1], [0.005, 1, 1], [0.005, -1, 1]
    report = body.cut([a + b + c, a + c + d])
    assert report.springs_cut == 1
    assert body.topology_version >= 1
    np.testing.assert_array_equal(body.springs, [[1, 2]])
    assert body.info.element_count == 1
    assert body.node_count == 3
    np.testing.assert_array_equal(body.node_parents, -1)
