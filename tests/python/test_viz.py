"""softhap.viz: optional, never imported by `import softhap`; with pyvista, a body becomes a
grid with the right cells and displacements, and renders to a PNG without a display."""

import os
import subprocess
import sys

import numpy as np
import pytest

import softhap
from conftest import BINDINGS_DIR


def test_import_softhap_does_not_import_viewers():
    code = "import softhap, sys; print(sorted(m for m in ('pyvista', 'polyscope', 'softhap.viz', 'meshio') if m in sys.modules))"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(BINDINGS_DIR), os.environ.get("PYTHONPATH")])))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env).stdout
    assert out.strip() == "[]"


def test_pyvista_grid_and_headless_picture(tmp_path):
    pytest.importorskip("pyvista")
    from softhap import viz
    mesh = softhap.Mesh.box((0.02, 0.02, 0.01), (4, 4, 2))
    with softhap.World(gravity=(0.0, 0.0, -9.81)) as world:
        body = world.add_fem_body(mesh, model="corotational", young=3e3, integrator="implicit_euler")
        body.fix_nodes(np.flatnonzero(mesh.nodes[:, 0] < 1e-9))
        for _ in range(10):
            world.step(0.02)
        grid = viz.to_pyvista(body, rest=mesh.nodes)
        assert grid.n_cells == mesh.info["tet_count"] and grid.n_points == mesh.info["node_count"]
        np.testing.assert_allclose(grid.points, body.positions)
        sag = 1e3 * (mesh.nodes[:, 2] - body.positions[:, 2]).max()
        assert grid.point_data["displacement_mm"].max() == pytest.approx(
            1e3 * np.linalg.norm(body.positions - mesh.nodes, axis=1).max())
        assert sag > 0.1   # the free end came down
        viz.screenshot(body, tmp_path / "cantilever.png", rest=mesh.nodes, tool=((0.02, 0.01, 0.02), 0.004))
    png = (tmp_path / "cantilever.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10000
