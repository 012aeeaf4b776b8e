"""The mesh on-ramp: meshio both ways (duck-typed), length units and the size warning, binary
files through meshio, rotations in transform, and tetrahedralize from a closed surface."""

import types
import warnings

import numpy as np
import pytest

import softhap


def tet_volume(nodes, tets):
    """Sum of |det| / 6 over the tets (numpy, independent of the library)."""
    e = nodes[tets[:, 1:]] - nodes[tets[:, :1]]
    return float(np.abs(np.einsum("ij,ij->i", e[:, 0], np.cross(e[:, 1], e[:, 2]))).sum() / 6.0)


def enclosed_volume(vertices, triangles):
    """Volume a closed, consistently oriented triangle surface encloses (divergence theorem)."""
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    return abs(float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6.0)


def test_from_duck_typed_meshio_keeps_tets_and_scales_units():
    nodes = np.array([[0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 10], [10, 10, 10]], dtype=float)
    fake = types.SimpleNamespace(points=nodes, cells=[("triangle", np.array([[0, 1, 2]])),
                                                      ("tetra", np.array([[0, 1, 2, 3]]))])
    mesh = softhap.Mesh.from_meshio(fake, units="mm")
    assert mesh.info["tet_count"] == 1
    assert mesh.info["volume"] == pytest.approx(1e-3**3 * 1000.0 / 6.0, rel=1e-12)
    with pytest.raises(ValueError):
        softhap.Mesh.from_meshio(types.SimpleNamespace(points=nodes, cells=[("triangle", np.array([[0, 1, 2]]))]))


def test_units_and_the_size_warning(meshes):
    with pytest.warns(softhap.UnitsWarning, match="units="):
        in_metres = softhap.Mesh.load(meshes / "liver.msh")   # a file in cm read as m: 6.5 m
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        in_cm = softhap.Mesh.load(meshes / "liver.msh", units="cm")
    np.testing.assert_allclose(in_cm.nodes, 0.01 * in_metres.nodes, rtol=1e-15)
    np.testing.assert_allclose(softhap.Mesh.load(meshes / "liver.msh", units=0.01).nodes, in_cm.nodes, rtol=1e-15)
    for bad in ("inch", 0.0, -1.0, float("nan")):
        with pytest.raises(ValueError):
            softhap.Mesh.load(meshes / "liver.msh", units=bad)


def test_rotation_in_transform():
    mesh = softhap.Mesh.box((0.02, 0.01, 0.01), (2, 1, 1))
    quarter = (np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4))          # 90 degrees about z
    turned = mesh.transform(2.0, translation=(1.0, 0.0, 0.0), rotation=quarter)
    expected = 2.0 * mesh.nodes[:, [1, 0, 2]] * (-1.0, 1.0, 1.0) + (1.0, 0.0, 0.0)
    np.testing.assert_allclose(turned.nodes, expected, atol=1e-15)
    matrix = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    np.testing.assert_allclose(mesh.transform(1.0, rotation=matrix).nodes, 0.5 * (expected - (1.0, 0.0, 0.0)),
                               atol=1e-15)
    assert turned.info["volume"] == pytest.approx(8.0 * mesh.info["volume"], rel=1e-12)
    with pytest.raises(ValueError):
        mesh.transform(1.0, rotation=[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]])


def test_meshio_round_trip_and_binary_files(meshes, tmp_path):
    meshio = pytest.importorskip("meshio")
    ascii_mesh = softhap.Mesh.load(meshes / "raptorTetra_8418.vtu", units="mm")
    m = ascii_mesh.to_meshio()
    np.testing.assert_array_equal(m.cells[0].data, ascii_mesh.tets)
    for name, options in [("raptor.vtu", {"binary": True}), ("raptor.msh", {"file_format": "gmsh", "binary": True})]:
        meshio.write(tmp_path / name, m, **options)
        binary = softhap.Mesh.load(tmp_path / name, units="m")
        assert binary.info["tet_count"] == 8418
        np.testing.assert_allclose(binary.nodes, ascii_mesh.nodes, rtol=1e-6)  # float32 in the .msh
        assert binary.info["volume"] == pytest.approx(tet_volume(ascii_mesh.nodes, ascii_mesh.tets), rel=1e-5)


def test_binary_file_without_meshio_is_unsupported(meshes, tmp_path, monkeypatch):
    meshio = pytest.importorskip("meshio")
    meshio.write(tmp_path / "b.vtu", softhap.Mesh.load(meshes / "raptorTetra_8418.vtu", units="mm").to_meshio(),
                 binary=True)
    monkeypatch.setitem(__import__("sys").modules, "meshio", None)   # as if not installed
    with pytest.raises(softhap.Error) as err:
        softhap.Mesh.load(tmp_path / "b.vtu")
    assert err.value.status_name == "SH_ERR_UNSUPPORTED"


def test_tetrahedralize_the_smooth_liver_and_simulate_it(meshes, tmp_path, monkeypatch):
    pytest.importorskip("pytetwild")
    pytest.importorskip("meshio")
    import meshio
    surface = meshio.read(meshes / "liver-smooth.obj")
    vertices = surface.points * 0.01
    triangles = np.concatenate([b.data for b in surface.cells if b.type == "triangle"])
    source = (meshes / "liver-smooth.obj").resolve()
    monkeypatch.chdir(tmp_path)
    liver = softhap.tetrahedralize(source, units="cm", edge_length=0.008)
    assert list(tmp_path.iterdir()) == []  # no scratch file left in the caller's directory
    assert liver.info["reoriented_tet_count"] == 0
    assert liver.info["volume"] == pytest.approx(enclosed_volume(vertices, triangles), rel=0.03)
    with softhap.World(gravity=(0.0, 0.0, -9.81)) as world:
        body = world.add_fem_body(liver, model="corotational", young=5e3, integrator="implicit_euler")
        z = liver.nodes[:, 2]
        body.fix_nodes(np.flatnonzero(z < z.min() + 0.005))
        for _ in range(10):
            world.step(1.0 / 60.0)
        assert np.all(np.isfinite(body.positions))
        assert body.positions[:, 2].max() < z.max()          # it sags under its weight


def test_tetrahedralize_refuses_an_open_surface():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float) * 0.01
    with pytest.raises(ValueError, match="not closed"):
        softhap.tetrahedralize((vertices, np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2]])))
