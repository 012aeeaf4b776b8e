"""Contact between two deformable bodies solved as one system (World.set_body_contact with
World.solve_static and implicit Euler): a soft cube resting through stiff linear contact on a
smaller block whose base is fixed, held sideways by four frictionless walls (a frictionless
stack has no lateral stiffness of its own). Checked against Newton's laws: the block's base
carries both weights, and stepping settles where the static solve does."""

import numpy as np

import softhap

from test_contact import box_mesh
from textbook import G

SIDE = 0.02  # cube edge (m)


def guided_stack(world, damping_mass=0.0):
    """The cube on the block (meshes placed so that no node lies over an edge of the other
    body's surface), the walls, and the block's fixed base nodes."""
    block_mesh = box_mesh((0.012, 0.012, SIDE), (3, 3, 2), origin=(0.0093, 0.0078, 0.0))
    cube_mesh = box_mesh((SIDE, SIDE, SIDE), (4, 4, 2), origin=(0.005, 0.005, SIDE - 1e-8))
    material = dict(model="linear", young=2e4, poisson=0.3, density=1000.0,
                    integrator="implicit_euler", damping_mass=damping_mass)
    block = world.add_fem_body(block_mesh, **material)
    cube = world.add_fem_body(cube_mesh, **material)
    base = np.flatnonzero(block_mesh.nodes[:, 2] == 0.0)
    block.fix_nodes(base)
    world.set_body_contact(block, cube, stiffness=1e6, exponent=1.0)
    centre = 0.005 + SIDE / 2
    for axis in range(2):
        for sign in (-1.0, 1.0):
            point = np.array([centre, centre, 1.5 * SIDE])
            point[axis] += sign * (SIDE / 2 - 1e-7)  # 0.1 um into the cube
            normal = np.zeros(3)
            normal[axis] = -sign
            world.add_obstacle("plane", position=point, normal=normal, stiffness=100.0, exponent=1.0)
    return block, cube, base


def test_static_stack_base_carries_both_weights():
    with softhap.World() as world:
        block, cube, base = guided_stack(world)
        report = world.solve_static()
        assert report.converged and report.iterations <= 20
        free = np.ones(block.masses.shape, bool)
        free[base] = False
        weights = G * (cube.masses.sum() + block.masses[free].sum())
        support = block.elastic_forces()[base].sum(axis=0)
        np.testing.assert_allclose(-support[2], weights, rtol=1e-6)
        # The cube's weight reaches the block: what the base carries beyond the block's own.
        np.testing.assert_allclose(-support[2] - G * block.masses[free].sum(),
                                   G * cube.masses.sum(), rtol=1e-6)


def test_implicit_steps_settle_where_the_static_solve_does():
    with softhap.World() as stepped, softhap.World() as solved:
        bodies = guided_stack(stepped, damping_mass=5.0)[:2]
        for _ in range(200):
            report = stepped.step(0.01)
        assert report.kinetic_energy < 1e-20
        expected = guided_stack(solved)[:2]
        solved.solve_static()
        for body, reference in zip(bodies, expected):
            np.testing.assert_allclose(body.positions, reference.positions, rtol=0, atol=1e-9)
