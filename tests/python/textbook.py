"""Reference values from textbook formulas that several test files check the library against."""

import numpy as np

G = 9.81  # m/s^2, the library's default gravity magnitude
UNIT_TET = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


def lame(young, poisson):
    """Lame parameters (lambda, mu) of an isotropic material."""
    lam = young * poisson / ((1 + poisson) * (1 - 2 * poisson))
    mu = young / (2 * (1 + poisson))
    return lam, mu


def linear_tet_stiffness(nodes, young, poisson):
    """Textbook K = V B^T D B (12 x 12) of one linear tetrahedron: B the 6 x 12
    strain-displacement matrix with engineering shear strains, D the isotropic Voigt elasticity."""
    lam, mu = lame(young, poisson)
    dm = (nodes[1:] - nodes[0]).T
    volume = abs(np.linalg.det(dm)) / 6.0
    grads = np.linalg.inv(dm)  # row a-1 is the gradient of the shape function of node a
    grads = np.vstack([-grads.sum(axis=0), grads])
    b = np.zeros((6, 12))
    for a, (gx, gy, gz) in enumerate(grads):
        b[:, 3 * a:3 * a + 3] = [[gx, 0, 0], [0, gy, 0], [0, 0, gz], [gy, gx, 0], [0, gz, gy], [gz, 0, gx]]
    d = np.zeros((6, 6))
    d[:3, :3] = lam
    d[:3, :3] += 2 * mu * np.eye(3)
    d[3:, 3:] = mu * np.eye(3)
    return volume * b.T @ d @ b
