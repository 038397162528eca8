"""The generated CDR codec (`simatch.msgs.cdr`) writes and reads exactly rosbags' CDR, for every simatch
message and every type of the Foxglove 3D scene, with or without the memo; any malformed payload becomes a
MessageError, never another exception."""

from __future__ import annotations

import math
import struct
import zlib

import numpy as np
import pytest
from rosbags.interfaces import Nodetype

from simatch import msgs
from simatch.msgs.cdr import Codec
from simatch.record import foxglove_msgs as fg

_INTS = {
    "int8": (-128, 127),
    "uint8": (0, 255),
    "byte": (0, 255),
    "char": (0, 255),
    "octet": (0, 255),
    "int16": (-(2**15), 2**15 - 1),
    "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1),
    "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint64": (0, 2**64 - 1),
}
_DTYPES = {
    "float64": np.float64,
    "float32": np.float32,
    "int32": np.int32,
    "uint32": np.uint32,
    "uint8": np.uint8,
    "int8": np.int8,
    "uint64": np.uint64,
    "int64": np.int64,
    "bool": np.bool_,
    "int16": np.int16,
    "uint16": np.uint16,
    "byte": np.uint8,
    "char": np.uint8,
    "octet": np.uint8,
}


#: what encoding a message with a field of the wrong type raises, in simatch's codec as in rosbags'
ENCODING_ERRORS = (struct.error, AttributeError, TypeError, ValueError)


def _scalar(base: str, rng):
    if base == "string":
        return "".join(rng.choice(list("abcXYZ/_é漢 2"), size=int(rng.integers(0, 9))))
    if base == "bool":
        return bool(rng.integers(0, 2))
    if base in ("float64", "float32"):
        v = float(rng.choice([0.0, -1.5, 1 / 3, 1e-300, math.pi, 7.0, 1e12])) * float(rng.normal())
        return float(np.float32(v)) if base == "float32" else v
    lo, hi = _INTS[base]
    if rng.integers(0, 2):
        return [lo, hi, 0, 1][int(rng.integers(0, 4))]  # the extremes of the type
    return int(rng.integers(max(lo, -(2**62)), min(hi, 2**62), endpoint=True))


def _value(store, desc, rng, depth: int):
    kind, info = desc
    if kind == Nodetype.BASE:
        return _scalar(info[0], rng)
    if kind == Nodetype.NAME:
        return random_message(store, info, rng, depth + 1)
    sub, length = info
    n = length if kind == Nodetype.ARRAY else int(rng.integers(0, 4 if depth < 2 else 2))
    if sub[0] == Nodetype.BASE and sub[1][0] != "string":
        return np.array([_scalar(sub[1][0], rng) for _ in range(n)], dtype=_DTYPES[sub[1][0]])
    return [_value(store, sub, rng, depth + 1) for _ in range(n)]


def random_message(store, typename: str, rng, depth: int = 0):
    """A ``typename`` message with random values and random sequence lengths (empty ones included)."""
    fields = store.fielddefs[typename][1]
    return store.types[typename](**{f: _value(store, d, rng, depth) for f, d in fields})


def _rosbags(store, msg) -> bytes:
    return bytes(store.serialize_cdr(msg, msg.__msgtype__))


STORES = [(msgs.typestore, name) for name in msgs.names()] + [
    (fg.typestore, name) for name in sorted(fg.typestore.fielddefs) if name.startswith(fg.PACKAGE)
]


def test_the_c_codec_refuses_a_numpy_layout_other_than_its_own():
    """The numpy fields the C codec reads are declared in simatch.msgs.cdr; the extension checks the declaration
    against its own structs and names the field that differs."""
    from simatch.msgs import _cdr_accel, cdr

    kinds = {k: np.dtype(cdr.DTYPE[b]) for b, k in cdr._KIND.items()}
    moved = dict(cdr.NUMPY_ARRAY, descr=cdr.NUMPY_ARRAY["descr"] + 8)
    with pytest.raises(ImportError, match="array field descr"):
        _cdr_accel.setup(np.ndarray, kinds, moved, cdr.NUMPY_DTYPE, 1)
    with pytest.raises(ImportError, match="does not name"):
        _cdr_accel.setup(np.ndarray, kinds, cdr.NUMPY_ARRAY, {"kind": 24}, 1)
    _cdr_accel.setup(np.ndarray, kinds, cdr.NUMPY_ARRAY, cdr.NUMPY_DTYPE, 1)  # (as at import)


@pytest.mark.parametrize("store, name", STORES, ids=[n for _, n in STORES])
def test_the_c_decoder_reads_what_rosbags_reads(store, name):
    """The C decoder against rosbags' own deserializer (``accelerate=False``): the same message (type, every
    field bit for bit, read-only arrays of the wire's dtype), and on broken payloads the same verdict: both
    read it, or both refuse it (MessageError)."""
    rng = np.random.default_rng(zlib.crc32(name.encode()) + 1)
    c, ref = Codec(store), Codec(store, accelerate=False)
    for _ in range(20):
        data = _rosbags(store, random_message(store, name, rng))
        a, b = c.decode(name, data), ref.decode(name, data)
        assert type(a) is type(b) and _rosbags(store, a) == _rosbags(store, b) == data
        _same_arrays(a, b)
    junk = bytearray(data)
    for cut in range(len(data) + 2):
        _same_verdict(c, ref, name, bytes(junk[:cut]))
    for _ in range(300):
        i = int(rng.integers(4, len(junk))) if len(junk) > 4 else 0
        junk[i] = int(rng.integers(0, 256))
        _same_verdict(c, ref, name, bytes(junk))
    _same_verdict(c, ref, name, data + bytes(8))  # bytes too many


def _same_arrays(a, b) -> None:
    for field in getattr(type(b), "__dataclass_fields__", ()):
        x, y = getattr(a, field), getattr(b, field)
        if isinstance(y, np.ndarray):
            assert isinstance(x, np.ndarray) and x.dtype == y.dtype and not x.flags.writeable
            assert x.tobytes() == y.tobytes()
        elif isinstance(y, list) and y and hasattr(y[0], "__dataclass_fields__"):
            for u, v in zip(x, y):
                _same_arrays(u, v)
        elif hasattr(y, "__dataclass_fields__"):
            _same_arrays(x, y)


def _same_verdict(c: Codec, py: Codec, name: str, data: bytes) -> None:
    results = []
    for codec in (c, py):
        try:
            results.append(codec.encode(codec.decode(name, data)))
        except msgs.MessageError:
            results.append(None)
    assert results[0] == results[1], (name, len(data))


@pytest.mark.parametrize("store, name", STORES, ids=[n for _, n in STORES])
def test_same_bytes_as_rosbags_both_ways(store, name):
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    codecs = [Codec(store), Codec(store, accelerate=False), Codec(store, memo=True, accelerate=False)]
    for _ in range(30):
        m = random_message(store, name, rng)
        data = _rosbags(store, m)
        for codec in codecs:
            assert codec.encode(m) == data
            out = bytearray(b"x")
            assert codec.appender(name)(m, out) == len(data) and out == b"x" + data
        back = codecs[0].decode(name, data)
        assert type(back) is type(m)
        assert _rosbags(store, back) == data  # every field, bit for bit
        codecs[2].forget()


def test_values_the_c_encoder_leaves_to_python_are_encoded_as_rosbags_does():
    """Lists instead of arrays, arrays of another dtype or strided, numpy scalars, enums: the same bytes."""
    codec = Codec(msgs.typestore)
    odd = [
        (
            msgs.new(
                msgs.ModelStates,
                stamp=np.float32(0.5),
                step=np.uint64(7),
                name=("a", "b"),
                pose=[1, 2.5, 3],
                twist=np.arange(12.0)[::2],
            ),
            msgs.new(
                msgs.ModelStates,
                stamp=0.5,
                step=7,
                name=["a", "b"],
                pose=np.array([1, 2.5, 3], dtype=np.float32),
                twist=np.arange(0.0, 12.0, 2.0, dtype=np.float32),
            ),
        ),  # float64 into float32[]
        (
            msgs.new(msgs.StrategyInfo, role=np.int64(3), target_num=[1, 2], user=np.arange(3, dtype=np.float32)),
            msgs.new(msgs.StrategyInfo, role=3, target_num=np.array([1, 2], dtype=np.int32), user=np.arange(3.0)),
        ),
        (
            msgs.new(msgs.OmniVisionInfo, robots=(msgs.new(msgs.RobotInfo, wheel_speeds=[0.5, 1]),)),
            msgs.new(
                msgs.OmniVisionInfo,
                robots=[msgs.new(msgs.RobotInfo, wheel_speeds=np.array([0.5, 1.0], dtype=np.float32))],
            ),
        ),
    ]
    for m, same in odd:
        assert codec.encode(m) == _rosbags(msgs.typestore, same)
    for bad in (msgs.new(msgs.VelCmd, vx="fast"), msgs.new(msgs.Clock, step=-1), msgs.new(msgs.GameEvent, type=3)):
        with pytest.raises(ENCODING_ERRORS):
            codec.encode(bad)
        with pytest.raises(ENCODING_ERRORS):
            _rosbags(msgs.typestore, bad)


def test_msgs_encode_and_decode_keep_their_contract():
    rng = np.random.default_rng(3)
    for name in msgs.names():
        m = random_message(msgs.typestore, name, rng)
        data = msgs.encode(m)
        assert data == _rosbags(msgs.typestore, m)
        back = msgs.decode(name.rsplit("/", 1)[1], memoryview(data))  # short names, any buffer
        assert _rosbags(msgs.typestore, back) == data
    states = msgs.decode(msgs.ModelStates, msgs.encode(msgs.new(msgs.ModelStates, pose=np.arange(7.0))))
    assert list(states.pose) == list(range(7)) and not states.pose.flags.writeable  # a view, as rosbags'
    with pytest.raises(msgs.MessageError):
        msgs.encode(msgs.VelCmd(stamp=0.0, tick=0, vx="fast", vy=0.0, w=0.0))
    with pytest.raises(msgs.MessageError, match="unknown"):
        msgs.decode("simatch_msgs/msg/Nothing", b"\x00\x01\x00\x00")


def test_big_endian_payloads_are_read_too():
    rng = np.random.default_rng(4)
    for name in ("simatch_msgs/msg/OmniVisionInfo", "simatch_msgs/msg/GameState"):
        m = random_message(msgs.typestore, name, rng)
        big = bytes(msgs.typestore.serialize_cdr(m, name, little_endian=False))
        assert msgs.encode(msgs.decode(name, big)) == msgs.encode(m)


@pytest.mark.parametrize("accelerate", [True, False])
def test_memo_encodes_what_it_meets_again_once_and_right(accelerate):
    """Teammates share one list of RobotInfo; a team's TeamStrategy holds the StrategyInfo its robots published:
    with the memo each is encoded once (until forget), and the bytes stay rosbags'."""
    codec = Codec(msgs.typestore, memo=True, accelerate=accelerate)
    robots = [msgs.new(msgs.RobotInfo, id=i, x=float(i), wheel_speeds=np.arange(4.0, dtype=np.float32)) for i in (1, 2)]
    for rid in (1, 2):
        a = msgs.new(msgs.OmniVisionInfo, robot_id=rid, robots=robots)
        assert codec.encode(a) == _rosbags(msgs.typestore, a)
    assert len(codec._seqs if not accelerate else codec._memo[0]) == 1
    infos = [
        msgs.new(msgs.StrategyInfo, agent_id=i, user=np.arange(float(i)), target_num=np.arange(i, dtype=np.int32))
        for i in range(1, 6)
    ]
    for info in infos:
        assert codec.encode(info) == _rosbags(msgs.typestore, info)
    codec.forget()  # a control tick later: still known
    for stamp in (0.5, 1.0):  # the second TeamStrategy reuses the same objects again
        team = msgs.new(msgs.TeamStrategy, stamp=stamp, tick=3, strategies=list(reversed(infos)))
        assert codec.encode(team) == _rosbags(msgs.typestore, team)
    codec.forget()
    codec.forget()
    assert not codec._seqs and not any(codec._memo)
    for k, info in enumerate(infos):  # forgotten: encoded again, right
        info.agent_id = 10 + k
    team = msgs.new(msgs.TeamStrategy, stamp=2.0, tick=4, strategies=infos)
    assert codec.encode(team) == _rosbags(msgs.typestore, team)
    c = msgs.new(msgs.OmniVisionInfo, robot_id=3, robots=[msgs.new(msgs.RobotInfo, id=9)])
    assert codec.encode(c) == _rosbags(msgs.typestore, c)


@pytest.mark.parametrize("accelerate", [True, False])
def test_fixed_size_arrays_must_have_their_size(accelerate):
    codec = Codec(fg.typestore, accelerate=accelerate)
    pose = fg.typestore.types["geometry_msgs/msg/PoseWithCovariance"]
    point = fg.typestore.types["geometry_msgs/msg/Point"]
    quat = fg.typestore.types["geometry_msgs/msg/Quaternion"]
    p = fg.typestore.types["geometry_msgs/msg/Pose"](
        position=point(x=1.0, y=2.0, z=3.0), orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0)
    )
    good = pose(pose=p, covariance=np.arange(36.0))
    assert codec.encode(good) == _rosbags(fg.typestore, good)
    with pytest.raises(msgs.MessageError, match="expected 36"):
        codec.encode(pose(pose=p, covariance=np.arange(35.0)))


def test_malformed_payloads_raise_message_error_only():
    rng = np.random.default_rng(1)
    for name in (
        "simatch_msgs/msg/OmniVisionInfo",
        "simatch_msgs/msg/GameState",
        "simatch_msgs/msg/TeamStrategy",
        "simatch_msgs/msg/ModelStates",
    ):
        sample = random_message(msgs.typestore, name, rng)
        while name.endswith("ModelStates") and not len(sample.name):
            sample = random_message(msgs.typestore, name, rng)
        data = msgs.encode(sample)
        for cut in range(0, len(data) - 3):  # cut short anywhere: refused (the last 3 may be padding)
            assert not _decodes(name, data[:cut]), cut
        junk = bytearray(data)
        for _ in range(400):  # flipped bytes: a message or a MessageError
            i = int(rng.integers(4, len(junk)))
            junk[i] = int(rng.integers(0, 256))
            _decodes(name, bytes(junk))
    with pytest.raises(msgs.MessageError, match="too many"):
        msgs.decode(msgs.VelCmd, msgs.encode(msgs.new(msgs.VelCmd)) + bytes(16))
    with pytest.raises(msgs.MessageError, match="do not fit"):
        msgs.decode(msgs.ModelStates, b"\x00\x01\x00\x00" + bytes(16) + b"\xff\xff\xff\x7f")
    with pytest.raises(msgs.MessageError, match="bad string"):
        msgs.decode(msgs.GameEvent, b"\x00\x01\x00\x00" + b"\xff\xff\xff\x7f" * 4)
    with pytest.raises(msgs.MessageError):
        msgs.decode(msgs.VelCmd, b"")


def _decodes(name: str, data: bytes) -> bool:
    try:
        msgs.decode(name, data)
    except msgs.MessageError:
        return False
    return True


def test_messages_are_slotted_and_other_objects_with_their_fields_encode_the_same():
    """Message classes have __slots__ (the C encoder reads a field at its offset, no look-up by name); an
    object of any other class with the same fields is read by name, with the same bytes, and so is a
    message whose class changed after the encoder learnt it."""
    import types

    m = msgs.new(
        msgs.ModelStates,
        stamp=0.5,
        step=3,
        name=["ball", "cyan/1"],
        pose=np.arange(14, dtype=np.float32),
        twist=np.ones(12, dtype=np.float32),
    )
    assert not hasattr(m, "__dict__") and msgs.ModelStates.__slots__ == msgs.fields(msgs.ModelStates)
    with pytest.raises(AttributeError):
        m.names = ["a misspelt field"]
    want = _rosbags(msgs.typestore, m)
    codec = Codec(msgs.typestore)
    assert codec.encode(m) == want
    plain = types.SimpleNamespace(
        **{f: getattr(m, f) for f in msgs.fields(msgs.ModelStates)}, __msgtype__=m.__msgtype__
    )
    assert codec.encode(plain, m.__msgtype__) == want and codec.encode(m) == want

    class Later(msgs.ModelStates):
        __slots__ = ()

    later = Later(0.5, 3, ["ball", "cyan/1"], np.arange(14, dtype=np.float32), np.ones(12, dtype=np.float32))
    assert codec.encode(later) == want
    Later.stamp = property(lambda self: 2.0)  # the class changes: read by name from now on
    assert codec.encode(later) == _rosbags(
        msgs.typestore,
        msgs.new(msgs.ModelStates, stamp=2.0, step=3, name=["ball", "cyan/1"], pose=m.pose, twist=m.twist),
    )
    del Later.stamp
    assert codec.encode(later) == want
