"""A cut that changes a few tets updates the body in place (its surface, lumped masses and
element blocks: the changed tets' lanes are emptied and they move to new blocks) instead of
rebuilding them. After every step of a blade advancing one element at a time through an
organ, the body must equal what its tets say: its surface the boundary of its tets
(mesh_checks, numpy), its masses the lumped masses by volume, and its elastic forces and
energy, at a deformation that inverts some tets, and the explicit step from there, those of a
body built afresh from the same tets (the library's whole-body path)."""

import numpy as np
import pytest

import softhap
from mesh_checks import boundary_faces, canonical_rows, lumped_masses, mesh_edges

DENSITY = 1000.0
ORGANS = {"liver2": ("liver2.msh", 0.1), "armadillo": ("Armadillo_Tetra_4406.vtu", 0.01)}


def blade_increments(positions, step):
    """Quads of a blade plane across the body's shortest axis (at 0.47 of it), advancing
    along its longest axis from before the body to past it in increments of step, reaching
    past the body along the third axis."""
    lo, hi = positions.min(axis=0), positions.max(axis=0)
    extent = hi - lo
    shortest, third, longest = np.argsort(extent)
    level = lo[shortest] + 0.47 * extent[shortest]
    across = (lo[third] - 0.1 * extent[third], hi[third] + 0.1 * extent[third])
    ends = np.arange(lo[longest] - step, hi[longest] + 2 * step, step)
    for a, b in zip(ends[:-1], ends[1:]):
        corners = []
        for u, v in ((a, across[0]), (b, across[0]), (b, across[1]), (a, across[1])):
            p = np.zeros(3)
            p[longest], p[third], p[shortest] = u, v, level
            corners.append(p)
        yield np.array([[corners[0], corners[1], corners[2]], [corners[0], corners[2], corners[3]]])


def deformed(rest, edge):
    """A bend of the whole body plus a jitter of 0.4 of an edge per node (seeded): some tets
    invert, the pieces on either side of the cut move apart."""
    centre = rest.mean(axis=0)
    extent = rest.max(axis=0) - rest.min(axis=0)
    u = (rest - centre) / extent
    bend = 0.2 * extent * np.stack([u[:, 1] * u[:, 2], np.sin(2.0 * u[:, 0]), u[:, 0] ** 2], axis=1)
    jitter = np.random.default_rng(5).uniform(-0.4 * edge, 0.4 * edge, rest.shape)
    return rest + bend + jitter


@pytest.mark.parametrize("model", ["corotational", "neohookean"])
@pytest.mark.parametrize("organ", sorted(ORGANS))
def test_blade_advancing_element_by_element_leaves_the_body_as_its_tets_say(meshes, organ, model):
    name, scale = ORGANS[organ]
    with softhap.Mesh.load(meshes / name) as raw:
        mesh = raw.transform(scale)
    material = dict(model=model, young=3e3, poisson=0.45, density=DENSITY)
    with softhap.World(gravity=(0.0, 0.0, 0.0)) as world:
        body = world.add_fem_body(mesh, **material)
        rest = body.positions
        edges = mesh_edges(body.tets)
        edge = np.median(np.linalg.norm(rest[edges[:, 0]] - rest[edges[:, 1]], axis=1))
        cuts = parted = 0
        for triangles in blade_increments(rest, edge):
            report = body.cut(triangles)
            if report.tets_added == 0 and report.nodes_added == 0:
                continue
            cuts += 1
            parted += report.faces_separated
            x, tets = body.positions, body.tets  # at rest: nothing was stepped
            np.testing.assert_array_equal(canonical_rows(body.surface_triangles), boundary_faces(tets))
            total = body.masses.sum()
            np.testing.assert_allclose(body.masses, lumped_masses(x, tets, DENSITY), rtol=0, atol=1e-13 * total)
            if cuts % 4:
                continue  # forces at every fourth cut: the fresh body costs a rebuild each
            moved = deformed(x, edge)
            body.positions = moved
            with softhap.Mesh(x, tets) as cut_mesh, softhap.World(gravity=(0.0, 0.0, 0.0)) as fresh_world:
                fresh = fresh_world.add_fem_body(cut_mesh, **material)
                fresh.positions = moved
                scale_f = np.abs(fresh.elastic_forces()).max()
                assert np.isfinite(body.elastic_forces()).all()
                np.testing.assert_allclose(body.elastic_forces(), fresh.elastic_forces(), rtol=0, atol=1e-9 * scale_f)
                assert body.elastic_energy() == pytest.approx(fresh.elastic_energy(), rel=1e-9)
                # One explicit step from there: the node masses and inverse masses (which the
                # cut updates only where it changed tets) move the nodes as the fresh body's do.
                world.step(1e-5)
                fresh_world.step(1e-5)
                moved_cut, moved_fresh = body.positions - moved, fresh.positions - moved
                assert np.abs(moved_fresh).max() > 0.0
                np.testing.assert_allclose(moved_cut, moved_fresh, rtol=0, atol=1e-9 * np.abs(moved_fresh).max())
            body.positions = x
            body.velocities = np.zeros_like(x)
        assert cuts >= 10  # the blade split tets at most of its increments
        assert parted >= 10  # and separated material
