"""The messages of simatch, defined once as ROS-style ``.msg`` files (package ``simatch_msgs``).

The definitions are loaded at import time into a ``rosbags`` type store, with no build step, so that the
same types serve the in-process bus (plain objects, never serialised), the wire between processes (CDR),
the recordings (rosbag2-compatible MCAP) and any ROS 2 bridge.

Precision: times and the game's numbers are ``float64``; what robots perceive and command (perception,
VelCmd, ActionCmd, StrategyInfo) and the model and link states are ``float32``, as in the original
Simatch's messages — seven significant digits, far finer than any robot senses or drives, at half the
bytes on the wire and in a recording (the exact states are identified by StateFingerprint).
A float32 value is rounded where it is made (`f32`), so the in-process bus carries the very numbers the
wire would: a value that crosses a process boundary comes back bit for bit, which is what lets a
distributed lockstep run reproduce an embedded one exactly.

Usage::

    from simatch import msgs
    cmd = msgs.new(msgs.VelCmd, vx=1.0)          # every field not given gets its zero value
    data = msgs.encode(cmd)                       # CDR bytes
    again = msgs.decode(msgs.VelCmd, data)        # raises msgs.MessageError on a malformed payload
"""

from __future__ import annotations

import dataclasses
import math
import struct
import sys
from collections.abc import Callable
from importlib import resources
from typing import Any

import numpy as np
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.base import Nodetype

PACKAGE = "simatch_msgs"

__all__ = [
    "MessageError",
    "PACKAGE",
    "typestore",
    "msgtype_name",
    "new",
    "fields",
    "positional",
    "encode",
    "decode",
    "definition",
    "names",
    "f32",
    "f32s",
]


class MessageError(ValueError):
    """A payload that does not decode into the expected message type."""


def unbuilt(extension: str, exc: ImportError) -> ImportError:
    """The error to raise when one of simatch's C extensions (built by ``pip install -e .``) cannot be imported."""
    return ImportError(
        f"simatch's C extension {extension} cannot be imported ({exc}): build it with `pip install -e .` "
        "(or `make setup`) in the simatch checkout"
    )


def _load_definitions() -> dict[str, str]:
    folder = resources.files(__package__).joinpath(PACKAGE, "msg")
    texts = {}
    for entry in sorted(folder.iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".msg"):
            texts[f"{PACKAGE}/msg/{entry.name[:-4]}"] = entry.read_text(encoding="utf-8")
    return texts


_TEXTS = _load_definitions()

#: The type store holding the standard ROS 2 (Jazzy) types and every ``simatch_msgs`` type.
typestore = get_typestore(Stores.ROS2_JAZZY)
_defs: dict = {}
for _name, _text in _TEXTS.items():
    _defs.update(get_types_from_msg(_text, _name))
typestore.register(_defs)

#: what `dataclasses` generates in a class, made again for the slotted one
_GENERATED = {
    "__dict__",
    "__weakref__",
    "__init__",
    "__repr__",
    "__eq__",
    "__hash__",
    "__match_args__",
    "__annotations__",
    "__dataclass_fields__",
    "__dataclass_params__",
    "__qualname__",
}


_NUMBER_TYPES = {"float32": float, "float64": float, "bool": lambda v: v.lower() == "true"}


def _defaults(text: str) -> dict[str, Any]:
    """The default values a ``.msg`` text gives its fields (``float32 vz 0.0``), as ROS 2 allows: a field
    appended to a message with a default leaves every constructor that does not name it valid."""
    out = {}
    for line in text.splitlines():
        body = line.split("#", 1)[0].split()
        if len(body) == 3 and "=" not in line.split("#", 1)[0]:
            kind, name, value = body
            out[name] = _NUMBER_TYPES.get(kind, int)(value)
    return out


#: the slotted classes `_with_slots` made (their ``__init__`` stores each argument and nothing else)
_SLOTTED: set[type] = set()


def _with_slots(cls: type, defaults: dict[str, Any]) -> type:
    """The same message class with ``__slots__``: the same fields in the same order, constants and
    ``__msgtype__``, and no per-instance dict.

    Why: the C codec (`simatch.msgs.cdr`, _cdr_accel.c) reads and fills the fields of a slotted instance at
    the offsets its class's member descriptors give (checked against the class's version tag) instead of
    looking each name up in a dict, and a slotted message is smaller. A field cannot be added to a message by
    mistake either (``msg.vz = 1`` on a VelCmd raises AttributeError). The C codec relies on this layout: a
    message class must keep its fields in object slots, created here."""
    # rosbags declares the constants and ``__msgtype__`` as "ClassVar[...]" strings, which dataclasses takes
    # for fields with a default: here they are class attributes only
    fields = [
        (f.name, f.type, dataclasses.field(default=defaults[f.name])) if f.name in defaults else (f.name, f.type)
        for f in dataclasses.fields(cls)
        if not str(f.type).startswith("ClassVar")
    ]
    namespace = {k: v for k, v in vars(cls).items() if k not in _GENERATED}
    slotted = dataclasses.make_dataclass(cls.__name__, fields, namespace=namespace, slots=True)
    slotted.__qualname__ = cls.__qualname__
    _SLOTTED.add(slotted)
    setattr(sys.modules[cls.__module__], cls.__name__, slotted)  # where pickle looks it up
    return slotted


for _name in _TEXTS:
    typestore.types[_name] = _with_slots(typestore.types[_name], _defaults(_TEXTS[_name]))


def names() -> list[str]:
    """Full names (``simatch_msgs/msg/X``) of every simatch message type."""
    return list(_TEXTS)


def msgtype_name(msgtype: Any) -> str:
    """The full type name of a message class, instance or name (short names are completed)."""
    if isinstance(msgtype, str):
        return msgtype if "/" in msgtype else f"{PACKAGE}/msg/{msgtype}"
    return msgtype.__msgtype__


def definition(msgtype: Any) -> str:
    """The ``.msg`` text of a simatch type, as shipped (used for MCAP schemas and ROS bridges)."""
    return _TEXTS[msgtype_name(msgtype)]


# ---------------------------------------------------------------------------------------------------
# Construction with defaults. The generated dataclasses require every field; `new` fills the missing
# ones with zero values (fresh containers for arrays and nested messages).

_ARRAY_DTYPES = {
    "float64": np.float64,
    "float32": np.float32,
    "int8": np.int8,
    "int16": np.int16,
    "int32": np.int32,
    "int64": np.int64,
    "uint8": np.uint8,
    "uint16": np.uint16,
    "uint32": np.uint32,
    "uint64": np.uint64,
}


def _zero(desc) -> Callable[[], Any]:
    kind, info = desc
    if kind == Nodetype.BASE:
        base = info[0]
        if base == "string":
            return str
        if base == "bool":
            return bool
        if base in ("float32", "float64"):
            return float
        return int
    if kind == Nodetype.NAME:
        return lambda: new(info)
    if kind in (Nodetype.SEQUENCE, Nodetype.ARRAY):
        inner, length = info
        if inner[0] == Nodetype.BASE and inner[1][0] in _ARRAY_DTYPES:
            dtype = _ARRAY_DTYPES[inner[1][0]]
            return lambda: np.zeros(length if kind == Nodetype.ARRAY else 0, dtype=dtype)
        if kind == Nodetype.ARRAY:
            make = _zero(inner)
            return lambda: [make() for _ in range(length)]
        return list
    raise TypeError(f"unsupported field description {desc!r}")


_FACTORIES: dict[str, dict[str, Callable[[], Any]]] = {}


def _factories(name: str) -> dict[str, Callable[[], Any]]:
    found = _FACTORIES.get(name)
    if found is None:
        _, fields = typestore.fielddefs[name]
        found = {fname: _zero(desc) for fname, desc in fields}
        _FACTORIES[name] = found
    return found


def new(msgtype: Any, **fields: Any):
    """A message of ``msgtype`` with ``fields`` set and every other field at its zero value."""
    name = msgtype_name(msgtype)
    factories = _factories(name)
    unknown = set(fields) - set(factories)
    if unknown:
        raise TypeError(f"{name} has no field(s) {', '.join(sorted(unknown))}")
    for fname, make in factories.items():
        if fname not in fields:
            fields[fname] = make()
    return typestore.types[name](**fields)


def fields(msgtype: Any) -> tuple[str, ...]:
    """The field names of a message type, in the order of its ``.msg`` file (its constructor's order)."""
    return tuple(fname for fname, _ in typestore.fielddefs[msgtype_name(msgtype)][1])


def positional(msgtype: Any, order: str) -> Callable[..., Any]:
    """A constructor of ``msgtype`` messages from positional arguments, after checking that its fields are
    exactly ``order`` (space-separated names).

    Hot paths (perception, commands: thousands of messages per simulated second) build messages
    positionally, about three times faster than by keyword. The check, at import, turns a later change of
    a ``.msg`` file into a clear error instead of fields silently swapped; fields appended later with a
    default value in the ``.msg`` (VelCmd's ``vz``) may be left out of ``order``: they take their default.

    The constructor is the C helper's ``Maker`` (`simatch.msgs._positional`): the same instance of the same
    class as the class's own ``__init__`` makes, its slots filled in C without a Python frame. Called with
    anything but ``order``'s arguments (keywords, more or fewer arguments) the Maker hands the call to the
    class, which raises its usual error."""
    want, have = tuple(order.split()), fields(msgtype)
    cls = typestore.types[msgtype_name(msgtype)]
    rest = have[len(want) :]
    defaulted = cls.__dataclass_fields__
    if want != have[: len(want)] or any(defaulted[f].default is dataclasses.MISSING for f in rest):
        raise TypeError(f"{msgtype_name(msgtype)} has fields ({', '.join(have)}), not ({', '.join(want)})")
    if cls not in _SLOTTED or hasattr(cls, "__post_init__"):
        return cls
    # every field: the ones a call gives (at least ``order``'s), then the defaults of those it may leave out
    first_default = next((k for k, f in enumerate(have) if defaulted[f].default is not dataclasses.MISSING), len(have))
    required = max(first_default, len(want))
    if any(defaulted[f].default is dataclasses.MISSING for f in have[required:]):
        return cls  # a default made per instance (a factory): only the class's __init__ makes it
    return _maker(cls, have, tuple(defaulted[f].default for f in have[required:]))


def slot_maker(cls: type, names: tuple[str, ...]) -> Callable[..., Any]:
    """A constructor of ``cls`` instances from positional arguments, one for each slot of ``names`` (in that
    order), filled without running the class's ``__init__``: the C helper's ``Maker`` (see `positional`), for a
    class of the strategies' own built per robot and tick (every slot of ``names`` an object slot of the class
    itself, no instance dict, object's own ``__new__``; TypeError otherwise). Called with exactly
    ``len(names)`` positional arguments."""
    return _maker(cls, tuple(names), ())


try:
    from ._positional import maker as _maker
except ImportError as _exc:
    raise unbuilt("simatch.msgs._positional", _exc) from None


_FLOAT32 = [struct.Struct(f"<{n}f") for n in range(17)]


def f32(value: float) -> float:
    """``value`` rounded to a float32 field's precision (round to nearest, as the wire does). Beyond
    float32's range it becomes an infinity, as in IEEE 754 arithmetic (the wire would refuse it); NaN stays
    NaN. Raises TypeError for what is not a number."""
    try:
        return _FLOAT32[1].unpack(_FLOAT32[1].pack(value))[0]
    except OverflowError:
        return math.copysign(math.inf, value)
    except struct.error:
        raise TypeError(f"not a number: {value!r}") from None


def f32s(*values: float) -> tuple[float, ...]:
    """Several values rounded as `f32` does, in one call (the messages' hot paths round a few at once)."""
    try:
        st = _FLOAT32[len(values)]
        return st.unpack(st.pack(*values))
    except (OverflowError, IndexError, struct.error):  # out of range, many values, or not a number (TypeError)
        return tuple(f32(v) for v in values)


# ---------------------------------------------------------------------------------------------------
# Wire format: CDR (little endian, with the 4-byte encapsulation header), as ROS 2 and rosbag2 use it,
# by the generated codec of `simatch.msgs.cdr` (the same bytes as rosbags, a few times faster).

from .cdr import Codec  # noqa: E402  (needs MessageError above)

_codec = Codec(typestore)


def encode(msg) -> bytes:
    """CDR bytes of a message."""
    try:
        return _codec.encode(msg)
    except MessageError:
        raise
    except Exception as exc:  # a field of the wrong type or size
        raise MessageError(f"cannot encode {getattr(msg, '__msgtype__', type(msg).__name__)}: {exc}") from None


def decode(msgtype: Any, data: bytes | bytearray | memoryview):
    """The message of type ``msgtype`` held in ``data``; ``MessageError`` if it is not one. Primitive
    sequences are read-only numpy arrays viewing the payload."""
    return _codec.decode(msgtype_name(msgtype), data)


def _export_classes() -> None:
    g = globals()
    for full in _TEXTS:
        short = full.rsplit("/", 1)[1]
        g[short] = typestore.types[full]
        __all__.append(short)


_export_classes()
