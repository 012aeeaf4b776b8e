"""The physical breaking criterion (criterion="physical"): a blade dragged through a block at
constant speed cuts it in steady state with a mean force equal to the toughness times the
blade's engaged length (energy balance: the work F dx pays G_c for every crack area L dx,
Griffith; Atkins, The Science and Engineering of Cutting, 2009), with a sawtooth force (the
load builds while the edge holds the material and falls when it breaks; Chanthasopeephan et
al. 2003 measured such profiles on liver). The sharpness divides the toughness; a material of
toughness 0 never breaks.

The block is box_mesh 4 x 1 x 1.5 cm (16 x 4 x 6 cubes of 2.5 mm) on a fixed base, corotational,
implicit, without gravity. The blade's edge reaches 1 cm below the top (the engaged length,
by hand) in the plane y = 5.1 mm and moves along x at 2 cm/s in steps of 10 ms from 3 mm
before the block to 2 mm past it; the tool's own shape (a 0.5 mm sphere) stays 5 mm above the
block, so the only force on the tool is the blade's.
"""

import numpy as np
import pytest

import softhap
from mesh_checks import components
from test_contact import box_mesh

SIZE, CELLS = (0.04, 0.01, 0.015), (16, 4, 6)
DEPTH = 0.01  # m, the blade's engaged length
Y = 0.0051  # m, the blade's plane
SPEED, DT = 0.02, 0.01  # m/s, s
RESOLUTION = 0.0025  # m: the crack advances this far per break


def drag_blade(young=1e5, toughness=20.0, sharpness=1.0):
    """Drags the blade through the block; returns (positions along x, force against the
    motion (N), faces cut per step, the body)."""
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    body = world.add_fem_body(
        box_mesh(SIZE, CELLS), model="corotational", young=young, poisson=0.45, toughness=toughness,
        integrator="implicit_euler", damping_mass=50.0,
    )
    body.fix_nodes(np.where(body.positions[:, 2] < 1e-9)[0])
    top = SIZE[2]
    tool = world.add_tool("sphere", radius=0.0005, position=(-0.003, Y, top + 0.005))
    tool.set_cutting(edge=((0.0, 0.0, -0.005 - DEPTH), (0.0, 0.0, 0.0)), criterion="physical",
                     sharpness=sharpness, resolution=RESOLUTION)
    xs, force, faces = [], [], []
    for i in range(int((SIZE[0] + 0.005) / (SPEED * DT))):
        x = -0.003 + SPEED * DT * (i + 1)
        tool.set_pose((x, Y, top + 0.005))
        report = world.step(DT)
        xs.append(x)
        force.append(-tool.force[0])
        faces.append(report.cut_faces)
    return np.array(xs), np.array(force), np.array(faces), body


def steady_mean(xs, force):
    """Mean force over the steady part: from 1 cm into the block to 0.5 cm before its end."""
    steady = (xs > 0.01) & (xs < SIZE[0] - 0.005)
    return force[steady].mean()


@pytest.mark.parametrize("young, toughness", [(1e5, 20.0), (3e5, 10.0), (3e4, 20.0)])
def test_steady_cutting_force_is_toughness_times_engaged_length(young, toughness):
    xs, force, faces, body = drag_blade(young=young, toughness=toughness)
    assert steady_mean(xs, force) == pytest.approx(toughness * DEPTH, rel=0.25)
    # the blade went through: the block is cut along its whole length but stays one piece
    # (the cut is 1 cm deep in 1.5 cm)
    assert faces.sum() > 0
    assert components(body.node_count, body.tets)[1] == 1


def test_cutting_force_is_a_sawtooth():
    # The force builds while the edge holds the material and drops when it breaks: in the
    # steady part, every break (a step that cut) is followed by a force below half of the
    # peak before it, and there are about as many breaks as resolutions in the length cut.
    xs, force, faces, _ = drag_blade()
    steady = np.where((xs > 0.01) & (xs < SIZE[0] - 0.005))[0]
    breaks = [i for i in steady if faces[i] > 0]
    assert len(breaks) >= 0.5 * (SIZE[0] - 0.015) / RESOLUTION
    for first, second in zip(breaks, breaks[1:]):
        peak = force[first:second].max()
        assert force[first:second].min() < 0.5 * peak
        assert peak > 0.0


def test_sharpness_divides_the_toughness():
    xs, force, _, _ = drag_blade(sharpness=2.0)
    assert steady_mean(xs, force) == pytest.approx(20.0 * DEPTH / 2.0, rel=0.25)


def test_a_material_of_toughness_zero_never_breaks():
    xs, force, faces, body = drag_blade(toughness=0.0)
    assert faces.sum() == 0
    assert body.topology_version == 0
    assert np.abs(force).max() == 0.0  # the blade holds nothing it cannot break


def test_bad_toughness_is_refused():
    world = softhap.World()
    for bad in (-1.0, np.nan, np.inf):
        with pytest.raises(softhap.Error, match="toughness"):
            world.add_fem_body(box_mesh((0.01, 0.01, 0.01), (1, 1, 1)), toughness=bad)
