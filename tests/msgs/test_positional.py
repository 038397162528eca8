"""Positional construction of messages (hot paths): the field order is checked, so a change of a .msg
file cannot silently swap fields."""

import gc
import sys

import numpy as np
import pytest

from simatch import msgs
from simatch.msgs import _maker


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


# --- the C helper (`simatch.msgs._positional`): the same messages as the classes make -------------------------


def _values(name: str) -> list:
    """One distinct value per field of ``name`` (numbers, text, arrays, nested messages, lists)."""
    out = []
    for k, (field, _) in enumerate(msgs.typestore.fielddefs[name][1]):
        default = msgs.new(name)
        v = getattr(default, field)
        if isinstance(v, bool):
            out.append(k % 2 == 0)
        elif isinstance(v, int):
            out.append(k + 1)
        elif isinstance(v, float):
            out.append(k + 0.5)
        elif isinstance(v, str):
            out.append(f"text{k}")
        elif isinstance(v, np.ndarray):
            out.append(np.arange(3, dtype=v.dtype))
        else:  # a nested message or a list of them
            out.append(v)
    return out


def _as_tuple(msg, fields) -> tuple:
    return tuple(getattr(msg, f) for f in fields)


@pytest.mark.parametrize("name", msgs.names())
def test_the_maker_builds_the_message_the_class_builds(name):
    cls = msgs.typestore.types[name]
    make = msgs.positional(name, " ".join(msgs.fields(name)))
    assert make is not cls and make.cls is cls
    values = _values(name)
    owned = [v for v in values if not isinstance(v, int)]  # (small ints and bools are shared by everybody)
    before = [sys.getrefcount(v) for v in owned]
    for _ in range(100):
        msg = make(*values)
    # compared as tuples of the fields (identity first, so the same array compares equal): the dataclass's own ==
    # compares field by field since Python 3.13, and an array's == is an array, whose truth is an error
    fields = msgs.fields(name)
    assert type(msg) is cls and _as_tuple(msg, fields) == _as_tuple(cls(*values), fields)
    assert all(getattr(msg, f) is v for f, v in zip(fields, values))  # the objects themselves
    assert msgs.encode(msg) == msgs.encode(cls(*values))
    assert gc.is_tracked(msg)  # (its slots hold objects: the cycle collector sees it, as the class's)
    del msg
    assert [sys.getrefcount(v) for v in owned] == before  # each held once while the message lives, then let go


def test_the_maker_takes_defaults_and_hands_other_calls_to_the_class():
    short = msgs.positional(msgs.VelCmd, "stamp tick vx vy w")
    assert short(1.5, 7, 0.5, -0.25, 0.375) == msgs.VelCmd(1.5, 7, 0.5, -0.25, 0.375, 0.0)
    assert short(1.5, 7, 0.5, -0.25, 0.375, 2.0).vz == 2.0  # a defaulted field may still be given
    assert short(1.5, 7, 0.5, -0.25, w=0.375).w == 0.375  # keywords: the class's constructor
    with pytest.raises(TypeError, match="missing"):
        short(1.5, 7)
    with pytest.raises(TypeError, match="positional argument"):
        short(1.5, 7, 0.5, -0.25, 0.375, 2.0, 9.0)


def test_the_maker_refuses_classes_it_cannot_build_exactly():
    class Plain:
        def __init__(self, a):
            self.a = a

    class Slotted:
        __slots__ = ("a",)

    with pytest.raises(TypeError, match="slotted"):
        _maker(Plain, ("a",), ())
    with pytest.raises(TypeError, match="not a slot"):
        _maker(Slotted, ("b",), ())
    with pytest.raises(ValueError, match="defaults"):
        _maker(Slotted, ("a",), (1, 2))
