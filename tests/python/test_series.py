"""softhap.Series and softhap.demo(): frames a user can open, and what they hold."""

import xml.etree.ElementTree as ET

import numpy as np
import pytest

import softhap


def test_series_index_lists_every_frame_in_order(tmp_path):
    mesh = softhap.Mesh.box((0.01, 0.01, 0.01), (2, 2, 2))
    with softhap.World(gravity=(0.0, 0.0, -9.81)) as world:
        body = world.add_fem_body(mesh, model="corotational", young=5e3)
        body.fix_nodes(np.flatnonzero(mesh.nodes[:, 2] > 0.01 - 1e-9))
        series = softhap.Series(tmp_path / "out", "cube")
        for i in range(3):
            world.step(1e-3)
            series.add(body, time=(i + 1) * 1e-3)
    root = ET.parse(series.index_path).getroot()
    sets = root.findall("./Collection/DataSet")
    assert [float(s.get("timestep")) for s in sets] == pytest.approx([1e-3, 2e-3, 3e-3])
    for s in sets:
        frame = softhap.Mesh.load(tmp_path / "out" / s.get("file"))
        assert frame.info["tet_count"] == mesh.info["tet_count"]
    # the last frame is the body's shape then: hanging from its top, its base has come down
    lowest = softhap.Mesh.load(tmp_path / "out" / sets[-1].get("file")).info["bounds_min"][2]
    assert lowest < 0.0


def test_demo_block_follows_the_sphere(tmp_path, capsys):
    """At the deepest pose (5 mm) the top centre node lies under the sphere's bottom (less the
    contact's small penetration), and the last frame (sphere lifted off) has sprung back."""
    index = softhap.demo(tmp_path, seconds=1.0, rate=20.0)
    sets = ET.parse(index).getroot().findall("./Collection/DataSet")
    assert len(sets) == 20
    assert "force on it" in capsys.readouterr().out

    def top_centre_z(frame):
        nodes = softhap.Mesh.load(tmp_path / frame.get("file")).nodes
        rest = softhap.Mesh.box((0.04, 0.04, 0.02), (8, 8, 4)).nodes
        centre = np.flatnonzero(np.all(np.isclose(rest, (0.02, 0.02, 0.02)), axis=1))[0]
        return nodes[centre, 2]

    assert 0.02 - 0.005 - 0.002 < top_centre_z(sets[9]) < 0.02 - 0.005 + 0.001
    assert top_centre_z(sets[-1]) > 0.02 - 0.0005
