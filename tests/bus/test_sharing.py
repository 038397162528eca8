"""Equal parts of the messages of one bundle are shared again once decoded (as one process shares them),
and only parts equal bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from simatch import msgs
from simatch.bus import sharing
from simatch.bus.sharing import share_equal_lists


def robot(rid: int, x: float = 1.0, **kw):
    return msgs.new(msgs.RobotInfo, id=rid, x=x, wheel_speeds=np.array([0.5, -0.5, 0.25, 0.0], np.float32), **kw)


def vision(rid: int, robots: list, **kw):
    """A robot's perception as a team process gets it: decoded from its own bytes (with those bytes)."""
    data = msgs.encode(msgs.new(msgs.OmniVisionInfo, robot_id=rid, robots=robots, **kw))
    return msgs.decode(msgs.OmniVisionInfo, data), data


@pytest.fixture(params=["tail", "elements"])
def way(request, monkeypatch):
    """Both ways of comparing: the CDR's tail (a list that is the last field) and the elements' CDR."""
    if request.param == "elements":
        monkeypatch.setitem(
            sharing._LIST_FIELDS, msgs.typestore.types["simatch_msgs/msg/OmniVisionInfo"], (("robots",), False)
        )
    return request.param


def test_equal_team_lists_become_one_object_and_others_stay_apart(way):
    team = [robot(1), robot(2, x=-3.25)]
    obstacles = msgs.new(msgs.ObstaclesInfo, x=np.array([1.0, 2.0], np.float32), y=np.zeros(2, np.float32))
    a, b, c = vision(1, team), vision(2, team, obstacles=obstacles), vision(3, [robot(1), robot(2, x=-3.5)])
    assert a[0].robots is not b[0].robots  # decoding makes a list per message
    assert share_equal_lists([a, b, c]) == 1
    assert b[0].robots is a[0].robots  # equal: shared, as the simulator's one list is in one process
    assert c[0].robots is not a[0].robots and c[0].robots[1].x == -3.5  # not equal: untouched
    assert (a[0].robot_id, b[0].robot_id) == (1, 2) and len(b[0].obstacles.x) == 2  # only that part is shared
    assert msgs.encode(b[0]) == b[1]  # the message is still exactly what was sent


def test_equal_means_equal_bit_for_bit(way):
    a = vision(1, [robot(1, x=0.0)])
    for other in ([robot(1, x=-0.0)], [robot(1, valid=True)], [robot(1), robot(2)], [robot(2, x=0.0)]):
        b = vision(2, other)
        assert share_equal_lists([a, b]) == 0 and b[0].robots is not a[0].robots
    nan = vision(3, [robot(1, x=float("nan"))])
    nan_too = vision(4, [robot(1, x=float("nan"))])
    assert share_equal_lists([nan, nan_too]) == 1  # the same bits


def test_messages_of_other_types_and_empty_lists_are_left_alone():
    a, b = vision(1, []), vision(2, [])
    strategy = msgs.new(msgs.TeamStrategy)
    assert share_equal_lists([a, (strategy, msgs.encode(strategy)), b]) == 0
    assert a[0].robots is not b[0].robots


def test_bytes_that_are_not_what_the_encoder_writes_are_never_shared():
    a, b = vision(1, [robot(1)]), vision(2, [robot(1)])
    forged = (b[0], b[1][:-8] + b"\x01" * 8)  # (bytes that do not match the message: nothing is assumed)
    padded = (b[0], b"\x00\x01\x00\x00" + b[1][4:] + b"\x00")
    assert share_equal_lists([a, forged]) == 0
    assert share_equal_lists([a, padded]) == 0


def test_a_first_message_with_an_empty_list_does_not_stop_later_sharing(monkeypatch):
    """What a list holds is learnt from a message that has some: a team whose first perception lists nobody
    (its robots not on the field yet) still gets its lists shared once they are there."""
    monkeypatch.delitem(sharing._LIST_FIELDS, msgs.typestore.types["simatch_msgs/msg/OmniVisionInfo"], raising=False)
    assert share_equal_lists([vision(1, []), vision(2, [])]) == 0
    team = [robot(1), robot(2)]
    a, b = vision(1, team), vision(2, team)
    assert share_equal_lists([a, b]) == 1 and b[0].robots is a[0].robots
