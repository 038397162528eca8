"""Parts that several messages of one bundle share, shared again once decoded.

In one process the bus hands every subscriber the very object that was published, and publishers share
parts between messages: the simulator gives the five robots of a team the same list of RobotInfo in their
OmniVisionInfo (a team shares its robots' positions). Nodes rely on that identity to do team-wide work once:
nubot's robots build their team's view, and the team picture, once per team and tick when they hold the very
same list, and each robot on its own otherwise. Serialised, each message carries its own copy, and decoding
gives each its own list: a team process would build its view and picture five times per tick where the
embedded run builds them once.

`share_equal_lists` gives that identity back: among messages of one type decoded from one bundle, a list
field whose CDR equals, byte for byte, the same field's of an earlier message becomes that earlier message's
list object. Equal bytes are equal values bit for bit, so no node sees a value it would not have seen, and a
node that compares by identity sees what it sees in one process. To keep the comparison cheap, a list that
is a message's last field (RobotInfo[] in OmniVisionInfo) is the tail of its CDR, found
by encoding the message once with that field emptied; any other list is compared by encoding its elements.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from .. import msgs

#: message type -> (its fields that hold lists of messages, whether the last of them is the message's last
#: field), learnt from the first message of that type
_LIST_FIELDS: dict[type, tuple[tuple[str, ...], bool]] = {}


def _list_fields(cls: type, msg: Any) -> tuple[tuple[str, ...], bool]:
    known = _LIST_FIELDS.get(cls)
    if known is None:
        slots = tuple(getattr(cls, "__slots__", ()))
        names = tuple(
            name
            for name in slots
            if isinstance(value := getattr(msg, name, None), list) and value and hasattr(type(value[0]), "__slots__")
        )
        known = (names, bool(names) and names[-1] == slots[-1])
        # an empty list tells nothing of its elements' type: learn again from a later message
        if not any(isinstance(value := getattr(msg, name, None), list) and not value for name in slots):
            _LIST_FIELDS[cls] = known
    return known


def _tail(msg: Any, name: str, data: bytes) -> bytes | None:
    """The CDR of ``msg``'s last field ``name`` in ``data`` (the message's own CDR), or None if ``data`` is not
    what the encoder writes for ``msg`` up to that field."""
    full = getattr(msg, name)
    setattr(msg, name, [])
    try:
        head = msgs.encode(msg)[:-4]  # an empty sequence ends the CDR with its length (a u32 zero)
    finally:
        setattr(msg, name, full)
    return data[len(head) :] if data.startswith(head) else None


def _elements(values: list) -> bytes:
    return b"".join(map(msgs.encode, values))


def share_equal_lists(messages: Iterable[tuple[Any, bytes]]) -> int:
    """Make equal list fields of messages of the same type one object (see the module); ``messages``: each
    decoded message with its CDR. Returns how many fields now share an earlier message's list."""
    first: dict[type, tuple[Any, dict]] = {}
    shared = 0
    for msg, data in messages:
        cls = type(msg)
        names, last_is_list = _list_fields(cls, msg)
        if not names:
            continue
        earlier = first.get(cls)
        if earlier is None:
            first[cls] = (msg, {"data": data})
            continue
        ref, cache = earlier
        for name in names:
            mine, theirs = getattr(msg, name), getattr(ref, name)
            if mine is theirs or not mine or len(mine) != len(theirs):
                continue
            if last_is_list and name == names[-1]:
                key = ("tail", name)
                if key not in cache:
                    cache[key] = _tail(ref, name, cache["data"])
                want, have = cache[key], _tail(msg, name, data)
                equal = want is not None and have is not None and want == have
            else:
                key = ("elements", name)
                if key not in cache:
                    cache[key] = _elements(theirs)
                equal = cache[key] == _elements(mine)
            if equal:
                setattr(msg, name, theirs)
                shared += 1
    return shared
