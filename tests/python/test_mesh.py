"""softhap.Mesh: loading the shared meshes (counts from shared/meshes/README.md), creating from
arrays, topology checked against numpy computations, validation errors, writing .vtu."""

import numpy as np
import pytest

import softhap

UNIT_TET_NODES = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]


def tet_volumes(nodes, tets):
    """Signed volumes det([x1-x0, x2-x0, x3-x0]) / 6 of each tet."""
    x = nodes[tets]
    edges = np.stack([x[:, 1] - x[:, 0], x[:, 2] - x[:, 0], x[:, 3] - x[:, 0]], axis=1)
    return np.linalg.det(edges) / 6.0


def unique_edges(tets):
    pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    edges = np.concatenate([tets[:, [a, b]] for a, b in pairs])
    edges.sort(axis=1)
    return np.unique(edges, axis=0)


def boundary_faces(tets):
    """Faces belonging to exactly one tet, as sorted triples."""
    faces = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]], tets[:, [0, 1, 3]], tets[:, [0, 1, 2]]])
    faces.sort(axis=1)
    unique, counts = np.unique(faces, axis=0, return_counts=True)
    return unique[counts == 1]


@pytest.mark.parametrize(
    "name, nodes, tets",
    [
        ("liver.msh", 181, 596),
        ("liver2.msh", 507, 1493),
        ("Armadillo_Tetra_4406.vtu", 1446, 4406),
        ("raptorTetra_8418.vtu", 2996, 8418),
        ("single_tetra.msh", 4, 1),
        ("6_tetra_bad.msh", 17, 6),
    ],
)
def test_mesh_counts_from_readme(meshes, name, nodes, tets):
    with softhap.Mesh.load(meshes / name) as mesh:
        assert mesh.node_count == nodes
        assert mesh.tet_count == tets
        assert mesh.nodes.shape == (nodes, 3)
        assert mesh.tets.shape == (tets, 4)
        assert mesh.nodes.dtype == np.float64 and mesh.tets.dtype == np.int32


def test_mesh_load_accepts_str_and_pathlike(meshes):
    a = softhap.Mesh.load(str(meshes / "liver.msh"))
    b = softhap.Mesh.load(meshes / "liver.msh")
    np.testing.assert_array_equal(a.nodes, b.nodes)
    np.testing.assert_array_equal(a.tets, b.tets)


def test_liver2_skips_triangles_and_lines(meshes):
    # README: 1493 tets plus 860 triangles and 71 lines
    info = softhap.Mesh.load(meshes / "liver2.msh").info
    assert info["skipped_element_count"] == 860 + 71


def test_inverted_tet_is_reoriented(meshes):
    mesh = softhap.Mesh.load(meshes / "6_tetra_bad.msh")
    assert mesh.info.reoriented_tet_count == 1
    assert np.all(tet_volumes(mesh.nodes, mesh.tets) > 0)


def test_raptor_orphan_nodes(meshes):
    mesh = softhap.Mesh.load(meshes / "raptorTetra_8418.vtu")
    assert mesh.info.orphan_node_count == 3
    used = np.unique(mesh.tets)
    assert mesh.node_count - used.size == 3


def test_broken_armadillo_is_refused_with_parse_error(meshes):
    with pytest.raises(softhap.Error) as info:
        softhap.Mesh.load(meshes / "Armadillo_Tetra_4406_for_test_broken.vtu")
    assert info.value.status == softhap.Status.SH_ERR_PARSE
    assert info.value.status_name == "SH_ERR_PARSE"
    assert info.value.message


def test_missing_file_is_io_error(tmp_path):
    with pytest.raises(softhap.Error) as info:
        softhap.Mesh.load(tmp_path / "none.msh")
    assert info.value.status_name == "SH_ERR_IO"


def test_liver_topology_matches_numpy(meshes):
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    nodes, tets = mesh.nodes, mesh.tets
    info = mesh.info
    volumes = tet_volumes(nodes, tets)
    assert np.all(volumes > 0)  # reoriented to positive volume
    assert info.volume == pytest.approx(volumes.sum(), rel=1e-12)
    assert info.bounds_min == pytest.approx(tuple(nodes.min(axis=0)))
    assert info.bounds_max == pytest.approx(tuple(nodes.max(axis=0)))

    edges = mesh.edges
    assert edges.shape == (info.edge_count, 2)
    np.testing.assert_array_equal(edges, unique_edges(tets))  # smaller first, sorted

    triangles = mesh.surface_triangles
    assert triangles.shape == (info.surface_triangle_count, 3)
    np.testing.assert_array_equal(
        np.unique(np.sort(triangles, axis=1), axis=0), boundary_faces(tets)
    )
    # Outward orientation: by the divergence theorem, sum over the surface of
    # det(a, b, c) / 6 equals the enclosed volume (positive only if normals point outward).
    x = nodes[triangles]
    enclosed = np.einsum("ij,ij->i", x[:, 0], np.cross(x[:, 1], x[:, 2])).sum() / 6.0
    assert enclosed == pytest.approx(info.volume, rel=1e-9)


def test_mesh_from_arrays_single_tet():
    mesh = softhap.Mesh(UNIT_TET_NODES, [[0, 1, 2, 3]])
    info = mesh.info
    assert (info.node_count, info.tet_count) == (4, 1)
    assert info.surface_triangle_count == 4
    assert info.edge_count == 6
    assert info.volume == pytest.approx(1.0 / 6.0, rel=1e-14)
    assert info.bounds_min == (0.0, 0.0, 0.0) and info.bounds_max == (1.0, 1.0, 1.0)
    np.testing.assert_array_equal(mesh.nodes, UNIT_TET_NODES)
    np.testing.assert_array_equal(
        mesh.edges, [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]
    )
    # every face normal points away from the centroid
    nodes = mesh.nodes
    centroid = nodes.mean(axis=0)
    for a, b, c in mesh.surface_triangles:
        normal = np.cross(nodes[b] - nodes[a], nodes[c] - nodes[a])
        assert np.dot(normal, nodes[a] - centroid) > 0


def test_mesh_from_arrays_reorients_inverted_tet():
    mesh = softhap.Mesh(UNIT_TET_NODES, np.array([[0, 2, 1, 3]], dtype=np.int64))
    assert mesh.info.reoriented_tet_count == 1
    assert tet_volumes(mesh.nodes, mesh.tets)[0] == pytest.approx(1.0 / 6.0)


def test_mesh_from_non_contiguous_arrays():
    nodes = np.asfortranarray(np.array(UNIT_TET_NODES) * 2.0)
    tets = np.array([[3, 0], [2, 0], [1, 0], [0, 0]]).T[:1, ::-1]  # a strided view: [[0,1,2,3]]
    mesh = softhap.Mesh(nodes, tets)
    np.testing.assert_array_equal(mesh.nodes, nodes)
    assert mesh.info.volume == pytest.approx(8.0 / 6.0)


@pytest.mark.parametrize(
    "nodes, tets",
    [
        (UNIT_TET_NODES, [[0, 1, 2, 4]]),  # index out of range
        (UNIT_TET_NODES, [[0, 1, 2, -1]]),  # negative index
        (UNIT_TET_NODES, [[0, 1, 1, 3]]),  # repeated node
        (UNIT_TET_NODES, [[0, 1, 2, 3], [3, 2, 1, 0]]),  # duplicate tet
        ([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], [[0, 1, 2, 3]]),  # zero volume
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, np.nan]], [[0, 1, 2, 3]]),  # not finite
    ],
)
def test_invalid_mesh_data_is_degenerate_mesh_error(nodes, tets):
    with pytest.raises(softhap.Error) as info:
        softhap.Mesh(nodes, tets)
    assert info.value.status_name == "SH_ERR_DEGENERATE_MESH"
    assert info.value.message


def test_empty_mesh_is_refused_by_the_library():
    with pytest.raises(softhap.Error) as info:
        softhap.Mesh(np.zeros((0, 3)), np.zeros((0, 4), dtype=np.int32))
    assert info.value.status in (
        softhap.Status.SH_ERR_INVALID_ARGUMENT,
        softhap.Status.SH_ERR_DEGENERATE_MESH,
    )


@pytest.mark.parametrize(
    "nodes, tets",
    [
        ([[0, 0], [1, 0], [0, 1], [1, 1]], [[0, 1, 2, 3]]),  # nodes not n x 3
        (UNIT_TET_NODES, [0, 1, 2, 3]),  # tets not m x 4
        (UNIT_TET_NODES, [[0, 1, 2]]),
        (UNIT_TET_NODES, [[0.0, 1.0, 2.0, 3.0]]),  # tets must be integers
    ],
)
def test_bad_shapes_are_value_errors(nodes, tets):
    with pytest.raises(ValueError):
        softhap.Mesh(nodes, tets)


def test_write_vtu_round_trip(meshes, tmp_path):
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    path = tmp_path / "liver.vtu"
    mesh.write_vtu(path)
    again = softhap.Mesh.load(path)
    assert (again.node_count, again.tet_count) == (181, 596)
    np.testing.assert_allclose(again.nodes, mesh.nodes, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(again.tets, mesh.tets)


def test_closed_mesh_raises_instead_of_crashing(meshes):
    mesh = softhap.Mesh.load(meshes / "single_tetra.msh")
    mesh.close()
    assert mesh.closed
    for use in (lambda: mesh.nodes, lambda: mesh.info, lambda: mesh.edges):
        with pytest.raises(softhap.Error) as info:
            use()
        assert info.value.status_name == "SH_ERR_INVALID_HANDLE"
    with softhap.World() as world, pytest.raises(softhap.Error):
        world.add_fem_body(mesh)
    assert "closed" in repr(mesh)


def test_gmsh4_unit_cube_has_unit_volume(meshes):
    info = softhap.Mesh.load(meshes / "msh4_cube.msh").info
    assert info.volume == pytest.approx(1.0, rel=1e-9)
    assert info.bounds_min == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    assert info.bounds_max == pytest.approx((1.0, 1.0, 1.0), abs=1e-12)


def test_single_tetra_volume_by_hand(meshes):
    # nodes (5,5,0) (0,5,0) (0,0,0) (2.5,3.5,-3): |det[(-5,0,0), (-5,-5,0), (-2.5,-1.5,-3)]| / 6
    info = softhap.Mesh.load(meshes / "single_tetra.msh").info
    assert info.volume == pytest.approx(75.0 / 6.0, rel=1e-14)


def test_legacy_vtk_and_tetgen_files(tmp_path):
    vtk = tmp_path / "tet.vtk"
    vtk.write_text(
        "# vtk DataFile Version 3.0\none tet\nASCII\nDATASET UNSTRUCTURED_GRID\n"
        "POINTS 4 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
        "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n"
    )
    node = tmp_path / "tet.node"
    node.write_text("4 3 0 0\n1 0 0 0\n2 2 0 0\n3 0 2 0\n4 0 0 2\n")
    (tmp_path / "tet.ele").write_text("1 4 0\n1 1 2 3 4\n")
    for path, volume in [(vtk, 1.0 / 6.0), (node, 8.0 / 6.0), (tmp_path / "tet.ele", 8.0 / 6.0)]:
        info = softhap.Mesh.load(path).info
        assert (info.node_count, info.tet_count) == (4, 1), path
        assert info.volume == pytest.approx(volume, rel=1e-14), path


def test_transform_scales_and_translates(meshes):
    mesh = softhap.Mesh.load(meshes / "liver.msh")
    centimetres = mesh.transform(0.01, (1.0, -2.0, 0.5))
    np.testing.assert_allclose(centimetres.nodes, 0.01 * mesh.nodes + [1.0, -2.0, 0.5], rtol=1e-15, atol=1e-15)
    np.testing.assert_array_equal(centimetres.tets, mesh.tets)
    assert centimetres.info.volume == pytest.approx(1e-6 * mesh.info.volume, rel=1e-12)
    scaled = mesh.transform(2.0)
    np.testing.assert_array_equal(scaled.nodes, 2.0 * mesh.nodes)
    assert mesh.info.volume == pytest.approx(tet_volumes(mesh.nodes, mesh.tets).sum())  # unchanged
    for bad in (0.0, -1.0, np.nan, np.inf):
        with pytest.raises(softhap.Error) as info:
            mesh.transform(bad)
        assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
    with pytest.raises(softhap.Error) as info:
        mesh.transform(1.0, (0.0, np.nan, 0.0))
    assert info.value.status_name == "SH_ERR_INVALID_ARGUMENT"
    with pytest.raises(ValueError):
        mesh.transform(1.0, (0.0, 0.0))


def test_box_is_a_conforming_kuhn_split():
    """Mesh.box((a, b, c), (2, 3, 4)): (2+1)(3+1)(4+1) nodes, six tets per cube, no tet
    reoriented (all built positive), volume abc, and a closed surface of two triangles per
    boundary square (a non-conforming split would leave inner faces on the surface)."""
    size = (0.02, 0.03, 0.04)
    mesh = softhap.Mesh.box(size, (2, 3, 4), origin=(1.0, -1.0, 0.5))
    info = mesh.info
    assert info["node_count"] == 3 * 4 * 5
    assert info["tet_count"] == 6 * 2 * 3 * 4
    assert info["reoriented_tet_count"] == 0
    assert info["volume"] == pytest.approx(np.prod(size), rel=1e-12)
    assert info["surface_triangle_count"] == 2 * 2 * (2 * 3 + 3 * 4 + 2 * 4)
    assert info["bounds_min"] == pytest.approx((1.0, -1.0, 0.5))
    assert info["bounds_max"] == pytest.approx((1.02, -0.97, 0.54))


def test_box_refuses_bad_cells():
    with pytest.raises(ValueError):
        softhap.Mesh.box((0.01, 0.01, 0.01), (1, 0, 1))
