"""Bundles: several samples of one process carried in one Zenoh sample.

Every Zenoh put wakes Zenoh's sending task and writes, and every sample received is a callback that must
take the GIL. A lockstep process sends a handful of small messages per control tick, all at once: carried in
one sample they are one put, one callback and one signature instead of a dozen or more.

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
from collections.abc import Iterable
from typing import NamedTuple

MAGIC = b"SMB1"
_U16 = struct.Struct("<H")
_U32 = struct.Struct("<I")
_MAX_U16 = 0xFFFF


class BundleError(ValueError):
    """A bundle whose framing is broken (it is dropped whole and counted as malformed)."""


class Entry(NamedTuple):
    topic: str
    msgtype: str  # "" for a protocol (raw) sample
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


def size(entry: tuple[str, str, bytes]) -> int:
    """Bytes an entry takes in a bundle."""
    topic, msgtype, payload = entry
    return 8 + len(topic.encode()) + len(msgtype.encode()) + len(payload)


def split(entries: Iterable[tuple[str, str, bytes]], limit: int) -> tuple[list[list], list]:
    """``entries`` cut, in order, into runs whose bundles take at most ``limit`` bytes each, and the entries
    too large for any bundle (which cannot be sent). Sent one after the other on one key, the bundles of
    the runs are opened in order: the same entries in the same order as one bundle."""
    runs: list[list] = []
    too_large = []
    run: list = []
    used = len(MAGIC)
    for entry in entries:
        n = size(entry)
        if len(MAGIC) + n > limit:
            too_large.append(entry)
            continue
        if used + n > limit:
            runs.append(run)
            run, used = [], len(MAGIC)
        run.append(entry)
        used += n
    if run:
        runs.append(run)
    return runs, too_large


#: topic and type names seen in bundles, by their bytes: the same few dozen names come in every tick, so
#: each is decoded once (bounded: a sender that invents names only makes the cache start again)
_NAMES: dict[bytes, str] = {}
_NAMES_MAX = 4096
_new_entry = tuple.__new__


def _name(raw: bytes) -> str:
    text = raw.decode()
    if len(_NAMES) >= _NAMES_MAX:
        _NAMES.clear()
    _NAMES[raw] = text
    return text


def unpack(data: bytes) -> list[Entry]:
    """The entries of a bundle; BundleError if it is not one (nothing of a broken bundle is used).

    Written for speed (a server opens every process's bundle at every tick, on the tick's critical path):
    plain offsets into ``data``, every bound checked before it is used, names decoded once (`_NAMES`)."""
    if data[:4] != MAGIC:
        raise BundleError("not a bundle (no SMB1 header)")
    out = []
    add = out.append
    u16, u32 = _U16.unpack_from, _U32.unpack_from
    names = _NAMES
    n, i = len(data), 4
    try:
        while i < n:
            if i + 2 > n:
                raise BundleError("broken bundle: a topic length runs past its end")
            j = i + 2 + u16(data, i)[0]
            if j + 2 > n:
                raise BundleError("broken bundle: a topic (or the type length after it) runs past its end")
            k = j + 2 + u16(data, j)[0]
            if k + 4 > n:
                raise BundleError("broken bundle: a type name (or the payload length after it) runs past its end")
            end = k + 4 + u32(data, k)[0]
            raw = data[i + 2 : j]
            topic = names.get(raw) or _name(raw)
            if end > n:
                raise BundleError(f"broken bundle: the payload on {topic!r} runs past its end")
            raw = data[j + 2 : k]
            add(_new_entry(Entry, (topic, names.get(raw) or _name(raw) if raw else "", data[k + 4 : end])))
            i = end
    except UnicodeDecodeError as exc:
        raise BundleError(f"broken bundle: {exc}") from None
    return out
