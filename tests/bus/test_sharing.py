"""Equal parts of the messages of one bundle are shared again once decoded (as one process shares them),
and only parts equal bit for bit."""

from __future__ import annotations

import math

import numpy as np

from simatch import msgs
from simatch.bus.sharing import same, share_equal_lists


def robot(rid: int, x: float = 1.0, **kw):
    return msgs.new(msgs.RobotInfo, id=rid, x=x, wheel_speeds=np.array([0.5, -0.5, 0.25, 0.0], np.float32), **kw)


def vision(rid: int, robots: list):
    """A robot's perception as a team process gets it: decoded from its own bytes."""
    return msgs.decode(msgs.OmniVisionInfo, msgs.encode(msgs.new(msgs.OmniVisionInfo, robot_id=rid, robots=robots)))


def test_equal_team_lists_become_one_object_and_others_stay_apart():
    team = [robot(1), robot(2, x=-3.25)]
    a, b, c = vision(1, team), vision(2, team), vision(3, [robot(1), robot(2, x=-3.5)])
    assert a.robots is not b.robots  # decoding makes a list per message
    assert share_equal_lists([a, b, c]) == 1
    assert b.robots is a.robots  # equal: shared, as the simulator's one list is in one process
    assert c.robots is not a.robots and c.robots[1].x == -3.5  # not equal: untouched
    assert a.robot_id == 1 and b.robot_id == 2  # only the equal part is shared


def test_messages_of_other_types_and_empty_lists_are_left_alone():
    a, b = vision(1, []), vision(2, [])
    strategy = msgs.new(msgs.TeamStrategy)
    assert share_equal_lists([a, strategy, b]) == 0
    assert a.robots is not b.robots


def test_equal_means_equal_bit_for_bit():
    assert same(0.0, 0.0) and not same(0.0, -0.0)
    assert same(math.nan, math.nan) and not same(math.nan, 1.0)
    assert not same(1, 1.0) and not same(True, 1)
    assert same(np.array([1, 2], np.float32), np.array([1, 2], np.float32))
    assert not same(np.array([1, 2], np.float32), np.array([1, 2], np.float64))
    assert not same(np.array([0.0], np.float32), np.array([-0.0], np.float32))
    assert same(robot(1), robot(1)) and not same(robot(1), robot(1, valid=True))
    assert not same(robot(1, x=0.0), robot(1, x=-0.0))
    assert not same([robot(1)], [robot(1), robot(2)])
