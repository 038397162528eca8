"""Positional construction of messages (hot paths): the field order is checked, so a change of a .msg
file cannot silently swap fields."""

import pytest

from simatch import msgs


def test_fields_follow_the_msg_file():
    assert msgs.fields(msgs.VelCmd) == ("stamp", "tick", "vx", "vy", "w")
    assert msgs.fields("Clock") == ("stamp", "step", "tick")


def test_positional_builds_the_same_message_as_keywords():
    cls = msgs.positional(msgs.VelCmd, "stamp tick vx vy w")
    assert cls(1.5, 7, 0.5, -0.25, 0.375) == msgs.VelCmd(stamp=1.5, tick=7, vx=0.5, vy=-0.25, w=0.375)
    assert msgs.decode(msgs.VelCmd, msgs.encode(cls(1.5, 7, 0.5, -0.25, 0.375))) == cls(1.5, 7, 0.5, -0.25, 0.375)


@pytest.mark.parametrize("order", ["stamp tick vy vx w", "stamp tick vx vy", "stamp tick vx vy w extra"])
def test_positional_refuses_another_order(order):
    with pytest.raises(TypeError, match="VelCmd has fields"):
        msgs.positional(msgs.VelCmd, order)
