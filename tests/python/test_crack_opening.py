"""A cut is a crack: a centre crack of length 2a cut (Body.cut) through a plate under
uniaxial tension opens at its centre by 4 sigma a / E' (Westergaard's solution for an infinite
plate; Tada, Paris & Irwin, The Stress Analysis of Cracks Handbook), and the finite-element
opening converges to it as the mesh is refined.

The plate is 16a x 16a in x and y, one element thick in z, linear elastic with Poisson's ratio
0: then plane stress and plane strain coincide (E' = E) and the one-element thickness carries
no three-dimensional effect. Its bottom edge is clamped, which with nu = 0 does not disturb the
uncracked plate's uniform stress, and the top edge carries the traction sigma. The grid is
uniform (spacing h = a / n) around the crack and grows by 1.5x per cell outwards; the crack
lies on the grid plane y = 0 between the node planes x = -a and x = a, so the cut parts whole
faces there and nothing else.
"""

import numpy as np
import pytest

import softhap
from test_contact import grid_mesh

E = 1e5  # Pa
SIGMA = 1e3  # Pa, the remote tension
A = 0.01  # m, half the crack's length
HALF = 8 * A  # m, half the plate's width and height
# The finite width's effect at a / HALF = 1/8: the stress intensity grows by
# sqrt(sec(pi a / (2 HALF))) = 1.0098 (Feddersen), the opening by about as much.
WIDTH_FACTOR = np.sqrt(1.0 / np.cos(np.pi * A / (2 * HALF)))


def node_planes(fine, h):
    """Node coordinates symmetric about 0: spacing h out to `fine`, then each cell 1.5x the
    last out to HALF."""
    xs = list(np.arange(0.0, fine + h / 2, h))
    while xs[-1] < HALF - 1e-12:
        xs.append(xs[-1] + min(1.5 * (xs[-1] - xs[-2]), HALF - xs[-1]))
    xs = np.array(xs)
    return np.concatenate([-xs[:0:-1], xs])


def loaded_plate(h, crack):
    """The plate with grid spacing h around the centre, cut along the crack if crack, under
    the traction and solved for equilibrium; returns (body, positions before loading)."""
    mesh = grid_mesh(node_planes(1.5 * A, h), node_planes(0.5 * A, h), np.array([0.0, h]))
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    body = world.add_fem_body(mesh, model="linear", young=E, poisson=0.0)
    x = body.positions
    body.fix_nodes(np.where(x[:, 1] < -HALF + 1e-9)[0])
    if crack:
        report = body.cut([[(-A, 0.0, -1.0), (A, 0.0, -1.0), (A, 0.0, 1.0)], [(-A, 0.0, -1.0), (A, 0.0, 1.0), (-A, 0.0, 1.0)]])
        assert report.faces_separated == 2 * round(2 * A / h)  # 2a / h cells along it, 2 faces each
    # the traction on the top face, lumped: each triangle's sigma * area in thirds
    x = body.positions
    forces = np.zeros_like(x)
    for triangle in body.surface_triangles:
        p = x[triangle]
        if np.all(p[:, 1] > HALF - 1e-9):
            forces[triangle, 1] += SIGMA * 0.5 * np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0])) / 3.0
    body.set_external_forces(forces)
    world.solve_static()
    return body, x


def centre_nodes(x):
    """The nodes at the plate's centre (on the crack: the original and its copy)."""
    return np.where(np.all(np.abs(x) < 1e-12, axis=1))[0]


def crack_opening(n):
    """The opening (m) at the centre of the crack with grid spacing a / n around it."""
    body, x = loaded_plate(A / n, crack=True)
    centre = centre_nodes(x)
    assert len(centre) == 2
    uy = body.positions[centre, 1] - x[centre, 1]
    return abs(uy[0] - uy[1])


def test_centre_crack_opening_converges_to_westergaard():
    exact = 4.0 * SIGMA * A / E * WIDTH_FACTOR
    errors = [abs(crack_opening(n) / exact - 1.0) for n in (2, 4, 8, 16)]
    # first-order convergence: each halving of h at least 1.6x closer
    for coarse, fine in zip(errors, errors[1:]):
        assert fine < coarse / 1.6
    assert errors[-1] < 0.05


def test_uncut_plate_does_not_open():
    # Without the cut the centre is one node, and the uniform stress leaves it where the
    # clamped-edge solution puts it: u_y = sigma HALF / E.
    body, x = loaded_plate(A / 2, crack=False)
    centre = centre_nodes(x)
    assert len(centre) == 1
    assert body.positions[centre[0], 1] - x[centre[0], 1] == pytest.approx(SIGMA * HALF / E, rel=1e-6)
