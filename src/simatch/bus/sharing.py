"""Parts that several messages of one bundle share, shared again once decoded.

In one process the bus hands every subscriber the very object that was published, and publishers share
parts between messages: the simulator gives the five robots of a team the same list of RobotInfo in their
OmniVisionInfo (a team shares its robots' positions). Nodes rely on that identity to do team-wide work once:
nubot's robots build their team's view, and the team picture, once per team and tick when they hold the very
same list, and each robot on its own otherwise. Serialised, each message carries its own copy, and decoding
gives each its own list: a team process then built its view and picture five times per tick where the
embedded run built them once (measured: 2.5 pictures per team and tick against 0.5, the team's decisions
about twice as expensive).

`share_equal_lists` gives that identity back: among messages of one type decoded from one bundle, a list
field that equals, bit for bit, the same field of an earlier message becomes that earlier message's list
object. Only equal values are shared, so no node sees a value it would not have seen, and a node that
compares by identity sees what it sees in one process.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np

#: message type -> the names of its fields that hold lists (sequences of messages or strings; sequences of
#: numbers are numpy arrays), learnt from the first message of that type
_LIST_FIELDS: dict[type, tuple[str, ...]] = {}


def _list_fields(cls: type, msg: Any) -> tuple[str, ...]:
    names = _LIST_FIELDS.get(cls)
    if names is None:
        names = _LIST_FIELDS[cls] = tuple(
            name for name in getattr(cls, "__slots__", ()) if isinstance(getattr(msg, name, None), list)
        )
    return names


def same(a: Any, b: Any) -> bool:
    """Whether two decoded values are equal bit for bit (floats by their bits: -0.0 is not 0.0, a NaN is
    the same NaN; arrays by dtype, shape and bytes; messages field by field)."""
    if a is b:
        return True
    cls = type(a)
    if cls is not type(b):
        return False
    if cls is float:
        if a != b:
            return a != a and b != b and math.copysign(1.0, a) == math.copysign(1.0, b)  # NaNs
        return a != 0.0 or math.copysign(1.0, a) == math.copysign(1.0, b)
    if cls is list or cls is tuple:
        return len(a) == len(b) and all(map(same, a, b))
    if cls is np.ndarray:
        return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    if cls is int or cls is bool or cls is str or cls is bytes:
        return a == b
    slots = getattr(cls, "__slots__", None)
    if slots is None:
        return False  # something else: never shared
    return all(same(getattr(a, name), getattr(b, name)) for name in slots)


def share_equal_lists(messages: Iterable[Any]) -> int:
    """Make equal list fields of messages of the same type one object (see the module); returns how many
    fields now share an earlier message's list."""
    first: dict[type, Any] = {}
    shared = 0
    for msg in messages:
        cls = type(msg)
        earlier = first.get(cls)
        if earlier is None:
            first[cls] = msg
            continue
        for name in _list_fields(cls, msg):
            mine, theirs = getattr(msg, name), getattr(earlier, name)
            if mine is not theirs and mine and same(mine, theirs):
                setattr(msg, name, theirs)
                shared += 1
    return shared
