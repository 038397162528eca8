"""The speed work on nubot keeps what robots decide: the helpers rewritten for speed against the plain
versions they replace, the opponents' array shared within a team, and the kernels the benchmark loads
before timing."""

import math
import random

import numpy as np

import simatch
from simatch.field import FieldGeometry
from simatch.strategy.nubot import ballpath, picture, positions
from simatch.strategy.nubot.geometry import segment_hits_box
from simatch.strategy.nubot.observation import _array
from simatch.strategy.nubot.positions import Areas
from simatch.strategy.nubot.warm import load_kernels


def test_route_skips_only_boxes_the_way_cannot_cross():
    """route's shortcut (both ends beside a box) never skips a box the full test says the way crosses."""
    rng = random.Random(3)
    boxes = [(-14.0, -10.5, 3.6), (10.5, 14.0, 3.6), (-1.0, 1.0, 0.5)]
    for _ in range(50_000):
        x0, x1, hw = rng.choice(boxes)
        px, tx = (rng.choice([x0, x1]) if rng.random() < 0.2 else rng.uniform(-15, 15) for _ in range(2))
        py, ty = (rng.choice([-hw, hw]) if rng.random() < 0.2 else rng.uniform(-8, 8) for _ in range(2))
        beside = (
            (px <= x0 and tx <= x0) or (px >= x1 and tx >= x1) or (py <= -hw and ty <= -hw) or (py >= hw and ty >= hw)
        )
        assert not (beside and segment_hits_box(px, py, tx, ty, x0, x1, hw)), (px, py, tx, ty, x0, x1, hw)


def test_route_goes_round_a_box_in_the_way():
    areas = Areas(FieldGeometry(), 0.4)
    x0, x1, hw = areas.opp_pa
    sx, sy = areas.route(x0 - 2.0, 0.3, x1 + 1.0, 0.0, [areas.opp_pa])
    assert (sx, sy) != (x1 + 1.0, 0.0) and abs(sy) > hw
    assert areas.route(0.0, 0.0, 3.0, 1.0, [areas.own_pa, areas.opp_pa]) == (3.0, 1.0)


def test_small_arrays_hold_the_values_of_np_array():
    rows = [(1.5, -2.0, 0.1, 0.0), (math.pi, 1e-300, -0.0, 7.0)]
    a = _array(rows, 4)
    assert a.shape == (2, 4) and a.dtype == np.float64 and a.flags.c_contiguous
    assert np.array_equal(a, np.array(rows, dtype=float))
    assert _array([], 5).shape == (0, 5)
    assert np.array_equal(_array([(1.0, 2.0, 0.0, 0.0, 3)], 5), np.array([(1.0, 2.0, 0.0, 0.0, 3)], dtype=float))


def _kernels():
    return {"intercepts": ballpath._intercepts, "score_spots": positions._score_spots, "assign": picture._assign}


def test_load_kernels_loads_what_open_play_calls():
    """After `load_kernels`, a match into open play needs no kernel signature it has not loaded yet (the
    benchmark relies on this: nothing compiles or loads while it measures)."""
    load_kernels()
    before = {k: set(map(str, f.signatures)) for k, f in _kernels().items()}
    assert all(before.values())
    with simatch.Simulation("msl_5v5", seed=1) as sim:
        sim.run(seconds=14.0, until_done=False)
        phases = {n.strategy.picture.phase for n in sim.robot_nodes.values() if n.strategy.picture is not None}
        evaluated = sum({id(n.strategy.shared): n.strategy.shared.evaluated for n in sim.robot_nodes.values()}.values())
    after = {k: set(map(str, f.signatures)) for k, f in _kernels().items()}
    assert evaluated > 0 and 4 in phases  # open play (gameflow.Phase.PLAY) was reached
    assert after == before


def test_a_robot_alone_decides_as_in_its_team():
    """Robots that each compute their own team picture (one robot per process in a distributed run) play
    the very same match as a team sharing one picture per tick: the sharing is only a cache."""
    from simatch.config.loader import load_scene

    lone = "simatch.strategy.nubot:NubotRobot"
    digests = []
    for overrides in ({}, {"teams.cyan.strategy": lone, "teams.magenta.strategy": lone}):
        with simatch.Simulation(load_scene("msl_5v5", overrides), seed=3) as sim:
            sim.run(seconds=12.0, until_done=False)
            shared = {id(n.strategy.shared) for n in sim.robot_nodes.values()}
            digests.append((len(shared), sim.state_digest()))
    (team_pictures, team_digest), (lone_pictures, lone_digest) = digests
    assert (team_pictures, lone_pictures) == (2, 10)
    assert team_digest == lone_digest
