"""The fast CDR encoders write exactly the bytes rosbags writes, for every message type we record."""

from __future__ import annotations

import zlib

import numpy as np
import pytest
from rosbags.interfaces import Nodetype

from simatch import msgs
from simatch.record import foxglove_msgs as fg
from simatch.record.cdr import Encoders


def _random(store, typename: str, rng: np.random.Generator, depth: int = 0):
    """A message of ``typename`` with random values and random sequence lengths (empty ones included)."""
    _, fields = store.fielddefs[typename]
    values = {}
    for name, (kind, info) in fields:
        values[name] = _value(store, kind, info, rng, depth)
    return store.types[typename](**values)


def _scalar(base: str, rng):
    if base == "string":
        return "".join(rng.choice(list("abcXYZ/_é漢 "), size=int(rng.integers(0, 9))))
    if base == "bool":
        return bool(rng.integers(0, 2))
    if base.startswith("float"):
        return float(rng.normal() * 10.0 ** int(rng.integers(-3, 4)))
    lo, hi = {"int8": (-128, 127), "uint8": (0, 255), "int16": (-2**15, 2**15 - 1), "uint16": (0, 2**16 - 1),
              "int32": (-2**31, 2**31 - 1), "uint32": (0, 2**32 - 1), "int64": (-2**62, 2**62),
              "uint64": (0, 2**62)}.get(base, (0, 255))
    return int(rng.integers(lo, hi, endpoint=True))


def _value(store, kind, info, rng, depth):
    if kind == Nodetype.BASE:
        return _scalar(info[0], rng)
    if kind == Nodetype.NAME:
        return _random(store, info, rng, depth + 1)
    (sub_kind, sub_info), length = info
    n = length if kind == Nodetype.ARRAY else int(rng.integers(0, 4 if depth < 2 else 2))
    if sub_kind == Nodetype.BASE and sub_info[0] != "string":
        dtype = {"float64": np.float64, "float32": np.float32, "int32": np.int32, "uint32": np.uint32,
                 "uint8": np.uint8, "int8": np.int8, "uint64": np.uint64, "int64": np.int64, "bool": np.bool_,
                 "int16": np.int16, "uint16": np.uint16}[sub_info[0]]
        return np.array([_scalar(sub_info[0], rng) for _ in range(n)], dtype=dtype)
    return [_value(store, sub_kind, sub_info, rng, depth + 1) for _ in range(n)]


@pytest.mark.parametrize("typename", msgs.names())
def test_simatch_types_encode_like_rosbags(typename):
    rng = np.random.default_rng(zlib.crc32(typename.encode()))
    enc = Encoders(msgs.typestore)
    for _ in range(40):
        msg = _random(msgs.typestore, typename, rng)
        assert enc(msg) == bytes(msgs.typestore.serialize_cdr(msg, typename))


def test_scene_update_encodes_like_rosbags():
    rng = np.random.default_rng(5)
    enc = Encoders(fg.typestore)
    for _ in range(20):
        msg = _random(fg.typestore, fg.SCENE_UPDATE, rng)
        assert enc(msg) == bytes(fg.typestore.serialize_cdr(msg, fg.SCENE_UPDATE))


def test_memo_reuses_a_shared_list_only_while_it_is_the_same_object():
    """Teammates share one list of RobotInfo: with the memo it is encoded once, and the bytes stay right."""
    enc = Encoders(msgs.typestore, memo=True)
    robots = [msgs.new(msgs.RobotInfo, id=i, x=float(i), wheel_speeds=np.arange(4.0)) for i in (1, 2)]
    a = msgs.new(msgs.OmniVisionInfo, robot_id=1, robots=robots)
    b = msgs.new(msgs.OmniVisionInfo, robot_id=2, robots=robots)
    assert enc(a) == bytes(msgs.typestore.serialize_cdr(a, a.__msgtype__))
    assert enc(b) == bytes(msgs.typestore.serialize_cdr(b, b.__msgtype__))
    enc.forget()
    c = msgs.new(msgs.OmniVisionInfo, robot_id=3, robots=[msgs.new(msgs.RobotInfo, id=9)])
    assert enc(c) == bytes(msgs.typestore.serialize_cdr(c, c.__msgtype__))
