"""The chasers' net as pure geometry: the level set lies at the asked distance from the prison, its
stations stay in the arena and close the fence against the walls, and chasers keep their order along it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simatch.field import Area
from simatch.strategy.encirclement.net import Arena, LevelSet, make_net, prison_distance

PRISON = Area("prison", 5.0, -2.0, 8.0, 2.0)  # against the +x wall of encirclement_9v7
ARENA = Arena(7.7, 5.7)  # 16 x 12 m walls minus a 0.3 m clearance


@pytest.mark.parametrize("r", [0.2, 1.0, 3.0, 7.5])
def test_every_point_of_the_level_set_is_r_from_the_prison(r):
    curve = LevelSet(PRISON, r)
    assert curve.perimeter == pytest.approx(2 * (3.0 + 4.0) + 2 * math.pi * r)
    for s in np.linspace(0.0, curve.perimeter, 97)[:-1]:
        x, y = curve.point(float(s))
        assert prison_distance(PRISON, x, y) == pytest.approx(r, abs=1e-9)
        back = curve.param(x, y)  # the inverse: where along the curve
        assert min(abs(back - s), curve.perimeter - abs(back - s)) == pytest.approx(0.0, abs=1e-9)


def test_a_point_off_the_curve_projects_along_the_prison_normal():
    curve = LevelSet(PRISON, 2.0)
    # straight out from the left side of the prison, at any distance: the left side's point at that height
    s = curve.param(-3.0, 0.5)
    assert curve.point(s) == pytest.approx((3.0, 0.5))
    # out from a corner: the same direction from that corner
    s = curve.param(5.0 - 3.0, 2.0 + 3.0)
    x, y = curve.point(s)
    assert 5.0 - x == pytest.approx(y - 2.0) and x < 5.0


@pytest.mark.parametrize("r", [0.5, 2.0, 4.0, 6.0, 10.0])
def test_a_u_net_rests_on_the_walls_and_stays_in_the_arena(r):
    net = make_net(PRISON, ARENA, r, 9)
    assert net is not None and not net.closed and len(net.stations) == 9
    st = net.stations
    assert (np.abs(st[:, 0]) <= ARENA.half_x + 1e-9).all() and (np.abs(st[:, 1]) <= ARENA.half_y + 1e-9).all()
    for x, y in st:
        assert prison_distance(PRISON, x, y) == pytest.approx(r, abs=1e-6)
    # the end stations touch a wall: no gap for a target between the net and the wall
    for x, y in (st[0], st[-1]):
        assert abs(abs(x) - ARENA.half_x) < 1e-6 or abs(abs(y) - ARENA.half_y) < 1e-6
    # stations are spread out: neighbours are at least a robot's width apart
    gaps = np.hypot(*np.diff(st, axis=0).T)
    assert gaps.min() > 0.5


def test_a_far_net_is_shared_between_the_stretches_the_walls_cut_it_into():
    net = make_net(PRISON, ARENA, 13.0, 9)  # only the far corners are that far from the prison
    spans = net.curve.inside(ARENA)
    assert len(spans) == 2
    st = net.stations
    assert (st[:, 0] < -7.0).all()
    assert (st[:, 1] > 0).sum() >= 4 and (st[:, 1] < 0).sum() >= 4  # both corners are fenced


def test_no_net_beyond_the_farthest_point_of_the_arena():
    corner = prison_distance(PRISON, -ARENA.half_x, ARENA.half_y)
    assert make_net(PRISON, ARENA, corner + 0.1, 9) is None


def test_a_prison_in_the_open_gets_a_closed_ring_of_evenly_spaced_stations():
    prison = Area("prison", -1.0, -1.0, 1.0, 1.0)
    net = make_net(prison, ARENA, 2.0, 8)
    assert net.closed
    params = sorted(net.curve.param(x, y) for x, y in net.stations)
    steps = np.diff(params + [params[0] + net.curve.perimeter])
    assert steps == pytest.approx(np.full(8, net.curve.perimeter / 8))


def test_chasers_take_the_stations_in_their_order_along_the_net():
    net = make_net(PRISON, ARENA, 6.0, 5)
    rng = np.random.default_rng(3)
    chasers = np.column_stack((rng.uniform(-7.5, 0.0, 5), rng.uniform(-5.5, 5.5, 5)))
    station = net.assign(chasers)
    assert sorted(station.tolist()) == list(range(5))  # one chaser per station
    order = net.order(chasers)
    assert station[order].tolist() == list(range(5))  # in order: nobody crosses
    # the remembered variant answers the same
    key = tuple(map(tuple, chasers.tolist()))
    for i in range(5):
        assert net.station(key, i) == pytest.approx(tuple(net.stations[station[i]]))


def test_on_a_closed_ring_the_rotation_that_moves_chasers_least_is_taken():
    prison = Area("prison", -1.0, -1.0, 1.0, 1.0)
    net = make_net(prison, ARENA, 2.0, 4)
    # chasers already standing next to the stations, in a rotated numbering
    chasers = np.roll(net.stations, 1, axis=0) * 1.05
    station = net.assign(chasers)
    assert np.hypot(*(net.stations[station] - chasers).T).max() < 0.2
