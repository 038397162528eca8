"""The wire codec of the Zenoh bus writes and reads exactly rosbags' CDR, for every simatch message, and
turns any malformed payload into a MessageError."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rosbags.interfaces import Nodetype

from simatch import msgs
from simatch.bus import cdr

_INTS = {"int8": (-128, 127), "uint8": (0, 255), "byte": (0, 255), "char": (0, 255), "int16": (-2**15, 2**15 - 1),
         "uint16": (0, 2**16 - 1), "int32": (-2**31, 2**31 - 1), "uint32": (0, 2**32 - 1),
         "int64": (-2**63, 2**63 - 1), "uint64": (0, 2**64 - 1)}
_DTYPES = {"float64": np.float64, "float32": np.float32, "int32": np.int32, "uint8": np.uint8, "int64": np.int64,
           "uint32": np.uint32, "uint64": np.uint64, "int8": np.int8, "int16": np.int16, "uint16": np.uint16,
           "bool": np.bool_}


def _value(desc, rng):
    kind, info = desc
    if kind == Nodetype.BASE:
        t = info[0]
        if t == "string":
            return "".join(rng.choice(list("abcé/2 ")) for _ in range(rng.integers(0, 7)))
        if t == "bool":
            return bool(rng.integers(0, 2))
        if t in ("float64", "float32"):
            v = float(rng.choice([0.0, -1.5, 1 / 3, 1e-300, math.pi, 7.0])) * float(rng.normal())
            return float(np.float32(v)) if t == "float32" else v
        lo, hi = _INTS[t]
        return [lo, hi, 0, 1][int(rng.integers(0, 4))]
    if kind == Nodetype.NAME:
        return _message(info, rng)
    sub, length = info
    n = length if kind == Nodetype.ARRAY else int(rng.integers(0, 4))
    if sub[0] == Nodetype.BASE and sub[1][0] != "string":
        return np.array([_value(sub, rng) for _ in range(n)], dtype=_DTYPES[sub[1][0]])
    return [_value(sub, rng) for _ in range(n)]


def _message(name, rng):
    fields = msgs.typestore.fielddefs[name][1]
    return msgs.new(name, **{f: _value(d, rng) for f, d in fields})


@pytest.mark.parametrize("name", msgs.names())
def test_same_bytes_as_rosbags_both_ways(name):
    rng = np.random.default_rng(abs(hash(name)) % 2**32)
    for _ in range(30):
        m = _message(name, rng)
        data = msgs.encode(m)
        assert cdr.encode(m) == data
        back = cdr.decode(name, data)
        assert msgs.encode(back) == data                     # every field, bit for bit
        assert type(back) is type(msgs.decode(name, data))


def test_malformed_payloads_raise_message_error_only():
    rng = np.random.default_rng(1)
    sample = _message("simatch_msgs/msg/OmniVisionInfo", rng)
    data = msgs.encode(sample)
    for cut in range(0, len(data), 7):
        with pytest.raises(msgs.MessageError):
            cdr.decode(msgs.OmniVisionInfo, data[:cut])
    junk = bytearray(data)
    for _ in range(300):
        i = int(rng.integers(4, len(junk)))
        junk[i] = int(rng.integers(0, 256))
        try:
            cdr.decode(msgs.OmniVisionInfo, bytes(junk))
        except msgs.MessageError:
            pass
    with pytest.raises(msgs.MessageError, match="too many"):
        cdr.decode(msgs.VelCmd, msgs.encode(msgs.new(msgs.VelCmd)) + bytes(16))
    with pytest.raises(msgs.MessageError):
        cdr.decode(msgs.GameEvent, b"\x00\x01\x00\x00" + b"\xff\xff\xff\x7f" * 4)
