"""Tearing of mass-spring bodies (sh_spring_params.break_strain): the step at which a spring
pulled at a known rate breaks (by hand), conservation of mass when a node is split, the
split of a node left holding two pieces joined only through it, a stretched bar torn in two,
and bad values refused."""

import numpy as np
import pytest

import softhap
from mesh_checks import connected_labels
from test_contact import box_mesh


def test_a_spring_pulled_at_a_known_rate_breaks_at_the_step_its_strain_passes_the_limit():
    # One spring of rest length 1 cm: node 0 fixed, node 1 prescribed to move away at
    # 1 mm per step. After step n its strain is n * 0.1; a break strain of 0.35 is passed
    # after step 4 (0.4), so the spring breaks at the start of step 5 and never before.
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    body = world.add_spring_body([(0.0, 0.0, 0.0), (0.01, 0.0, 0.0)], springs=[(0, 1)], break_strain=0.35)
    body.fix_nodes([0])
    broken = []
    for n in range(1, 9):
        body.prescribe_positions([1], [(0.01 + 0.001 * n, 0.0, 0.0)])
        broken.append(world.step(1e-3).springs_broken)
    assert broken == [0, 0, 0, 0, 1, 0, 0, 0]
    assert len(body.springs) == 0
    assert body.topology_version == 1


def test_springs_below_their_break_strain_never_break():
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    body = world.add_spring_body([(0.0, 0.0, 0.0), (0.01, 0.0, 0.0)], springs=[(0, 1)], break_strain=0.35)
    body.fix_nodes([0])
    for n in range(1, 4):
        body.prescribe_positions([1], [(0.01 + 0.001 * n, 0.0, 0.0)])
        assert world.step(1e-3).springs_broken == 0
    assert body.topology_version == 0


def pyramid():
    """A square pyramid's edges as springs: apex 0 over the square 1-2-3-4 (1 cm side)."""
    nodes = [(0.0, 0.0, 0.01), (-0.005, -0.005, 0.0), (0.005, -0.005, 0.0), (0.005, 0.005, 0.0), (-0.005, 0.005, 0.0)]
    springs = [(0, 1), (0, 2), (0, 3), (0, 4), (1, 2), (2, 3), (3, 4), (4, 1)]
    return nodes, springs


def test_a_node_left_holding_two_pieces_through_itself_is_split():
    # Move 3 and 4 by 1 cm along y: the square's sides 2-3 and 4-1 double (strain 1), the
    # apex's springs to 3 and 4 go from 1.22 to 1.87 cm (strain 0.53), the rest keep their
    # length. With a break strain of 0.6 only 2-3 and 4-1 break, and the apex's neighbours fall into {1, 2} and
    # {3, 4}, joined only through the apex. It is split: one copy per piece, the mass shared
    # by the rest lengths of each piece's springs (here equal: half each).
    nodes, springs = pyramid()
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    body = world.add_spring_body(nodes, springs=springs, mass=[0.004, 0.001, 0.001, 0.001, 0.001], break_strain=0.6)
    moved = np.array(nodes)
    moved[3, 1] += 0.01
    moved[4, 1] += 0.01
    body.positions = moved
    report = world.step(1e-6)
    assert report.springs_broken == 2
    assert body.node_count == 6
    assert body.node_parents.tolist() == [-1, -1, -1, -1, -1, 0]
    np.testing.assert_allclose(body.masses, [0.002, 0.001, 0.001, 0.001, 0.001, 0.002], rtol=1e-12)
    # the apex (or its copy) joins each piece; no node joins both
    pieces = {frozenset(map(int, s)) for s in body.springs}
    apex_ends = {frozenset({a, b}) - {0, 5} for a, b in map(tuple, body.springs) if {a, b} & {0, 5}}
    assert len(pieces) == 6
    assert {next(iter(e)) for e in apex_ends} == {1, 2, 3, 4}
    assert len(np.unique(connected_labels(body.node_count, body.springs))) == 2


def test_a_chain_node_is_never_split():
    # A chain's middle node joins two neighbours that no spring ever joined: breaking a
    # spring elsewhere does not make it a pinch.
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    nodes = [(0.01 * i, 0.0, 0.0) for i in range(4)]
    body = world.add_spring_body(nodes, springs=[(0, 1), (1, 2), (2, 3)], break_strain=0.5)
    moved = np.array(nodes)
    moved[3, 0] += 0.01  # spring 2-3 to twice its length
    body.positions = moved
    assert world.step(1e-6).springs_broken == 1
    assert body.node_count == 4


def test_a_bar_pulled_apart_tears_in_two_and_keeps_its_mass():
    # A 4 x 1 x 1 cm bar of tet-edge springs, one end fixed and the other pulled at 1 m/s:
    # it stretches, then tears through, leaving two pieces with all of the mass.
    world = softhap.World(gravity=(0.0, 0.0, 0.0))
    mesh = box_mesh((0.04, 0.01, 0.01), (4, 1, 1))
    body = world.add_spring_body(mesh, stiffness=50.0, mass=1e-3, break_strain=0.2, damping_mass=50.0)
    x = body.positions
    left, right = np.where(x[:, 0] < 1e-9)[0], np.where(x[:, 0] > 0.04 - 1e-9)[0]
    body.fix_nodes(left)
    mass = body.masses.sum()
    torn = 0
    for n in range(1, 41):
        body.prescribe_positions(right, x[right] + (0.0005 * n, 0.0, 0.0))
        torn += world.step(1e-4 * 5).springs_broken
    assert torn > 0
    labels = connected_labels(body.node_count, body.springs)
    assert len(np.unique(labels)) == 2
    assert body.masses.sum() == pytest.approx(mass, rel=1e-12)
    # each piece holds one end
    assert len(set(labels[left])) == 1 and len(set(labels[right])) == 1
    assert labels[left[0]] != labels[right[0]]


@pytest.mark.parametrize("bad", [-0.1, np.nan, np.inf])
def test_bad_break_strain_is_refused(bad):
    world = softhap.World()
    with pytest.raises(softhap.Error, match="break_strain"):
        world.add_spring_body([(0.0, 0.0, 0.0), (0.01, 0.0, 0.0)], springs=[(0, 1)], break_strain=bad)
