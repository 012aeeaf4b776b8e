"""The library's messages arrive on the "softhap" logger (sh_set_log_callback, installed at
import)."""

import logging

import numpy as np

import softhap


def test_substepped_step_and_repaired_mesh_are_logged(caplog):
    caplog.set_level(logging.INFO, logger="softhap")
    nodes = np.array([[0, 0, 0], [0.01, 0, 0], [0, 0.01, 0], [0, 0, 0.01]])
    mesh = softhap.Mesh(nodes, [[0, 2, 1, 3]])              # inverted: reoriented
    assert any("1 inverted tets reoriented" in r.getMessage() for r in caplog.records)
    with softhap.World(gravity=(0.0, 0.0, -9.81)) as world:
        body = world.add_fem_body(mesh)
        report = world.step(10.0 * body.info["dt_critical"])
    assert report.substeps > 1
    step = [r for r in caplog.records if "sub-steps" in r.getMessage()]
    assert len(step) == 1 and step[0].levelno == logging.INFO and step[0].name == "softhap"
    assert ("split into %d sub-steps" % report.substeps) in step[0].getMessage()
