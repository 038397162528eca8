"""Bundles: several samples of one process carried in one Zenoh sample.

Every Zenoh put from Python costs some tens of microseconds when the link is idle (a wake-up of Zenoh's
sending task, a write), and every sample received costs a callback that must take the GIL. A lockstep
process sends a handful of small messages per control tick, all at once: carried in one sample they cost
one put, one callback and one signature instead of a dozen or more.

The format is meant to be easy to write in any language (all integers little-endian)::

    bundle := b"SMB1" entry*
    entry  := u16 topic_len, topic (UTF-8, relative to the run),
              u16 type_len, type (a message's full type name, e.g. "simatch_msgs/msg/VelCmd";
                                  empty for a protocol sample, e.g. a lockstep ack in JSON),
              u32 payload_len, payload (the message's CDR, or the protocol sample's bytes)

A bundle is one sample on its own key, signed as a whole like any sample (see `simatch.distributed`); its
entries are then handled one by one exactly as if each had arrived alone, in the order they were packed.
"""

from __future__ import annotations

import struct
from typing import Iterable, NamedTuple

MAGIC = b"SMB1"
_U16 = struct.Struct("<H")
_U32 = struct.Struct("<I")
_MAX_U16 = 0xFFFF


class BundleError(ValueError):
    """A bundle whose framing is broken (it is dropped whole and counted as malformed)."""


class Entry(NamedTuple):
    topic: str
    msgtype: str          # "" for a protocol (raw) sample
    payload: bytes


def pack(entries: Iterable[tuple[str, str, bytes]]) -> bytes:
    """The bundle of ``(topic, msgtype, payload)`` entries, in this order."""
    parts = [MAGIC]
    add = parts.append
    for topic, msgtype, payload in entries:
        t, m = topic.encode(), msgtype.encode()
        if len(t) > _MAX_U16 or len(m) > _MAX_U16:
            raise ValueError(f"topic or type name too long for a bundle: {topic!r}")
        add(_U16.pack(len(t)))
        add(t)
        add(_U16.pack(len(m)))
        add(m)
        add(_U32.pack(len(payload)))
        add(payload)
    return b"".join(parts)


def unpack(data: bytes) -> list[Entry]:
    """The entries of a bundle; BundleError if it is not one (nothing of a broken bundle is used)."""
    if data[:4] != MAGIC:
        raise BundleError("not a bundle (no SMB1 header)")
    out = []
    view = memoryview(data)
    n, i = len(data), 4

    def take(size: int, what: str) -> memoryview:
        nonlocal i
        if i + size > n:
            raise BundleError(f"broken bundle: {what} runs past its end")
        chunk = view[i:i + size]
        i += size
        return chunk

    try:
        while i < n:
            topic = str(take(_U16.unpack(take(2, "a topic length"))[0], "a topic"), "utf-8")
            msgtype = str(take(_U16.unpack(take(2, "a type length"))[0], "a type name"), "utf-8")
            payload = bytes(take(_U32.unpack(take(4, "a payload length"))[0], f"the payload on {topic!r}"))
            out.append(Entry(topic, msgtype, payload))
    except UnicodeDecodeError as exc:
        raise BundleError(f"broken bundle: {exc}") from None
    return out
