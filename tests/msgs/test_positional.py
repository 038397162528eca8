"""Positional construction of messages (hot paths): the field order is checked, so a change of a .msg
file cannot silently swap fields."""

import pytest

from simatch import msgs


def test_fields_follow_the_msg_file():
    assert msgs.fields(msgs.VelCmd) == ("stamp", "tick", "vx", "vy", "w", "vz")
    assert msgs.fields("Clock") == ("stamp", "step", "tick")


def test_positional_builds_the_same_message_as_keywords():
    cls = msgs.positional(msgs.VelCmd, "stamp tick vx vy w vz")
    assert cls(1.5, 7, 0.5, -0.25, 0.375, 1.0) == msgs.VelCmd(stamp=1.5, tick=7, vx=0.5, vy=-0.25, w=0.375, vz=1.0)
    msg = cls(1.5, 7, 0.5, -0.25, 0.375, -0.5)
    assert msgs.decode(msgs.VelCmd, msgs.encode(msg)) == msg


def test_a_field_appended_with_a_default_leaves_older_constructions_valid():
    """VelCmd's vz was appended with a default value in its .msg (``float32 vz 0.0``): code written before it
    (by keyword, without vz) still builds the same command, with vz = 0."""
    old = msgs.VelCmd(stamp=1.5, tick=7, vx=0.5, vy=-0.25, w=0.375)
    assert old.vz == 0.0 and old == msgs.new(msgs.VelCmd, stamp=1.5, tick=7, vx=0.5, vy=-0.25, w=0.375)
    assert msgs.RobotInfo.__dataclass_fields__["z"].default == 0.0
    older = msgs.positional(msgs.VelCmd, "stamp tick vx vy w")  # positional code written before it too
    assert older(1.5, 7, 0.5, -0.25, 0.375) == old


@pytest.mark.parametrize("order", ["stamp tick vx vy", "stamp tick vx vy w vz extra", "stamp tick vx vy vz w"])
def test_positional_refuses_another_order(order):
    with pytest.raises(TypeError, match="VelCmd has fields"):
        msgs.positional(msgs.VelCmd, order)
