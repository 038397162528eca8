"""CDR for any ``rosbags`` type store: encoders and decoders, byte for byte what rosbags writes.

The bus between processes encodes and decodes the robots' messages at every control tick, and a recording
encodes every message of the run on the thread that runs the simulation, so `Codec` does not walk a message
field by field as ``rosbags`` does. Messages with sequences are encoded, and little-endian payloads decoded,
by the C codec (``_cdr_accel.c``, built by ``pip install -e .``): `Codec` compiles each type's program once
(`program`), and the C codec walks a message (or a payload, with the message's class) with it. The generated
Python encoders (`simatch.msgs.cdr_encoders`) encode what the C encoder does not take as it is (a list where
an array is expected, a value of the wrong type: converted, or the canonical error raised) and pack a
fixed-size message, encapsulation header included, with one ``struct`` call. ``Codec(accelerate=False)`` uses
the generated Python encoders only and reads payloads with rosbags' own deserializer: the reference the tests
and the fuzzing targets hold the C codec to (the same bytes, the same messages, the same verdict on broken
payloads). A big-endian payload is read by rosbags too.

Decoding checks what it reads: a payload that is cut short, claims more elements than it holds, holds a bad
string or bytes too many raises `MessageError`, never anything else. Primitive sequences come back as
read-only numpy views of the payload (as rosbags gives them).

With ``memo=True`` (a recorder: messages are read-only once published) it also encodes once what it meets
again in the current or the previous memo period (`forget` starts a new one): a list of sub-messages or of
strings that is the same object (the team list that perception gives every teammate, the model names), and
a message already encoded on its own and met again inside a sequence (the StrategyInfo a robot published
at one control tick is in its team's TeamStrategy at the next). Lists of strings are also kept by value.

The C codec reads numpy arrays by their object layout (`NUMPY_ARRAY`, `NUMPY_DTYPE` below: declared here,
checked on an array at import, and handed to the extension, which checks them against its own structs), and
messages by their slots (`simatch.msgs._with_slots`).

Output: XCDR1 little endian with the 4-byte encapsulation header (`simatch.msgs.cdr_wire`), as ROS 2 and
rosbag2 write it.

    codec = Codec(msgs.typestore)
    data = codec.encode(msg)                     # bytes
    again = codec.decode(msg.__msgtype__, data)  # MessageError if ``data`` is not one
"""

from __future__ import annotations

import ctypes
import sys
from collections.abc import Callable
from typing import Any

import numpy as np
from rosbags.interfaces import Nodetype
from rosbags.typesys.base import normalize_fieldname

from . import MessageError, unbuilt
from .cdr_encoders import PythonEncoders, _as_bytes
from .cdr_wire import _LEN, _U32, _ZEROS, BASE, DTYPE, HEADER, _ident

try:
    from . import _cdr_accel
except ImportError as exc:  # (a checkout where the extension was not built, or was built for another Python)
    raise unbuilt("simatch.msgs._cdr_accel", exc) from exc

if sys.byteorder != "little":  # encoders append numpy buffers as they lie in memory
    raise ImportError("simatch.msgs.cdr needs a little-endian machine")


_MEMO_LIMIT = 4096  # string lists kept by value
#: kinds of the C codec's programs (K_* in _cdr_accel.h)
_KIND = {
    "bool": 1,
    "int8": 2,
    "uint8": 3,
    "byte": 3,
    "char": 3,
    "octet": 3,
    "int16": 4,
    "uint16": 5,
    "int32": 6,
    "uint32": 7,
    "int64": 8,
    "uint64": 9,
    "float32": 10,
    "float64": 11,
}
_K_STR, _K_MSG, _K_PSEQ, _K_SSEQ, _K_MSEQ = 20, 21, 22, 23, 24


class _ArrayHead(ctypes.Structure):
    """The leading fields of numpy's array object (``PyArrayObject_fields``), which the C codec reads: part of
    numpy's ABI, the same in numpy 1 and 2."""

    _fields_ = [
        ("head", ctypes.c_byte * object.__basicsize__),  # PyObject_HEAD
        ("data", ctypes.c_void_p),
        ("nd", ctypes.c_int),
        ("dimensions", ctypes.POINTER(ctypes.c_ssize_t)),
        ("strides", ctypes.POINTER(ctypes.c_ssize_t)),
        ("base", ctypes.c_void_p),
        ("descr", ctypes.c_void_p),
        ("flags", ctypes.c_int),
    ]


class _DtypeHead(ctypes.Structure):
    """The leading fields of a numpy dtype (``PyArray_Descr``), the same in numpy 1 and 2."""

    _fields_ = [
        ("head", ctypes.c_byte * object.__basicsize__),
        ("typeobj", ctypes.c_void_p),
        ("kind", ctypes.c_char),
        ("type", ctypes.c_char),
        ("byteorder", ctypes.c_char),
    ]


#: byte offsets of the fields the C codec reads in numpy's array and dtype objects
NUMPY_ARRAY = {name: getattr(_ArrayHead, name).offset for name, _ in _ArrayHead._fields_[1:]}
NUMPY_DTYPE = {name: getattr(_DtypeHead, name).offset for name, _ in _DtypeHead._fields_[1:]}
_NPY_C_CONTIGUOUS = 0x0001  # numpy's flag of a C-contiguous array (NPY_ARRAY_C_CONTIGUOUS)


def _check_numpy_layout() -> None:
    """Read an array and its dtype through the declared layout and compare with what numpy says of them."""
    sample = np.arange(3.0)
    head = _ArrayHead.from_address(id(sample))
    dtype = _DtypeHead.from_address(id(sample.dtype))
    found = (
        head.data == sample.ctypes.data
        and head.nd == 1
        and head.dimensions[0] == 3
        and head.strides[0] == 8
        and head.descr == id(sample.dtype)
        and head.flags & _NPY_C_CONTIGUOUS
        and dtype.typeobj == id(np.float64)
        and (dtype.kind, dtype.type) == (b"f", b"d")
        and type(sample).__basicsize__ >= ctypes.sizeof(_ArrayHead)
    )
    if not found:
        raise ImportError(
            f"numpy {np.__version__} does not lay out its arrays as simatch.msgs.cdr declares (_ArrayHead, "
            "_DtypeHead), which the C codec reads"
        )


_check_numpy_layout()
_cdr_accel.setup(
    np.ndarray, {k: np.dtype(DTYPE[b]) for b, k in _KIND.items()}, NUMPY_ARRAY, NUMPY_DTYPE, _NPY_C_CONTIGUOUS
)
_cdr_accel.setup_decoding(MessageError)


class Codec(PythonEncoders):
    """Encoders and decoders for every type of a ``rosbags`` type store, generated on first use."""

    def __init__(self, typestore, *, memo: bool = False, accelerate: bool = True):
        self.typestore = typestore
        self.memo = memo
        self.accelerate = accelerate
        self._programs: dict[str, tuple] = {}
        self._compiled_programs: dict[str, Any] = {}
        self._appenders: dict[str, Callable] = {}
        self._memo = ({}, {})  # the C encoder's: this period's, the last one's
        self._whole: dict[str, Callable] = {}  # type -> encode(msg) -> bytes
        self._parts: dict[str, Callable] = {}  # type -> enc(msg, out, pos) -> pos
        self._c_decoders: dict[str, Any] = {}  # type -> the C decoder's compiled program
        self._seqs: dict[int, tuple] = {}  # memo: id(list) -> (list, phase, bytes)
        self._strings: dict[tuple, bytes] = {}
        self._elements = self._element_types()
        self._ns: dict[str, Any] = {
            "_LEN": _LEN,
            "_U32": _U32,
            "_ZEROS": _ZEROS,
            "_asb": _as_bytes,
            "_ndarray": np.ndarray,
            "_np": np,
            "_seqs": self._seqs,
            "_objs": {},
            "_objs_old": {},
            "_strings": self._strings,
            "_LIMIT": _MEMO_LIMIT,
            "_HEADER": HEADER,
            "Error": MessageError,
            "_codec": self,
        }

    # --- public ------------------------------------------------------------------------------------------
    def encode(self, msg, typename: str | None = None) -> bytes:
        """CDR bytes of ``msg`` (with the encapsulation header)."""
        name = typename or msg.__msgtype__
        func = self._whole.get(name)
        if func is None:
            func = self.encoder(name)
        return func(msg)

    __call__ = encode

    def encoder(self, typename: str) -> Callable[[Any], bytes]:
        """The function that encodes a whole ``typename`` message (the fastest path for a known type)."""
        found = self._whole.get(typename)
        if found is None:
            if typename not in self.typestore.fielddefs:
                raise MessageError(f"unknown message type {typename!r}")
            found = self._generate_whole(typename)
        return found

    def appender(self, typename: str) -> Callable[[Any, bytearray], int]:
        """The function ``append(msg, out)`` that appends a ``typename`` message's CDR bytes to the bytearray
        ``out`` and returns their number (a writer that frames messages into one buffer: no bytes object per
        message). On an error nothing is appended."""
        found = self._appenders.get(typename)
        if found is None:
            whole = self.encoder(typename)
            ident = _ident(typename)
            self._ns[f"_WH_{ident}"] = whole
            if self.accelerate and not self._fixed_size(typename):
                args = "_memo, " + str(typename in self._elements) if self.memo else "None, False"
                lines = [
                    f"def into_{ident}(m, out):",
                    f"    n = _accel(_PROG_{ident}, m, {args}, out)",
                    "    if n is None:",
                    f"        d = _PY_{ident}(m)",
                    "        out += d",
                    "        return len(d)",
                    "    return n",
                ]
            else:
                lines = [f"def into_{ident}(m, out):", f"    d = _WH_{ident}(m)", "    out += d", "    return len(d)"]
            found = self._appenders[typename] = self._compile(lines, typename, f"into_{ident}")
        return found

    def program(self, typename: str) -> tuple[tuple, bool]:
        """What the C message log (``Log``, simatch/record/_messagelog.c) needs to encode ``typename``: the C encoder's
        program, and whether a memo should remember each message's body (the type is an element of some
        sequence, so a message published alone may be met again inside another one)."""
        if typename not in self.typestore.fielddefs:
            raise MessageError(f"unknown message type {typename!r}")
        return self._compiled(typename), typename in self._elements

    def decode(self, typename: str, data: bytes | bytearray | memoryview):
        """The ``typename`` message held in ``data``; primitive sequences are read-only numpy views of it.
        Raises `MessageError` if ``data`` is not such a message."""
        if type(data) is not bytes:
            data = bytes(data)
        if self.accelerate and data[:2] == b"\x00\x01":
            program = self._c_decoders.get(typename)
            if program is None:
                program = self._c_decoder(typename)
            try:
                return _cdr_accel.decode(program, data)
            except MessageError as exc:
                raise MessageError(f"malformed {typename} payload ({len(data)} bytes): {exc}") from None
        if typename not in self.typestore.fielddefs:
            raise MessageError(f"unknown message type {typename!r}")
        try:
            return self.typestore.deserialize_cdr(data, typename)
        except Exception as exc:  # (rosbags raises its SerdeError, or what its reads meet: any means malformed)
            raise MessageError(f"malformed {typename} payload ({len(data)} bytes): {exc}") from None

    def forget(self) -> None:
        """Start a new memo period: lists met in the last one are forgotten, messages encoded on their own in
        the period before it too (memo: id(msg) -> (msg, bytes with header), in two generations)."""
        self._seqs.clear()
        self._ns["_objs_old"] = self._ns["_objs"]
        self._ns["_objs"] = {}
        self._memo = ({}, self._memo[0])
        self._ns["_memo"] = self._memo

    # --- analysis ---------------------------------------------------------------------------------------------
    def _element_types(self) -> set[str]:
        """Types that appear as elements of a sequence or array somewhere in the store (memo candidates)."""
        out = set()
        for _, fields in self.typestore.fielddefs.values():
            for _, (kind, info) in fields:
                if kind in (Nodetype.SEQUENCE, Nodetype.ARRAY) and info[0][0] == Nodetype.NAME:
                    out.add(info[0][1])
        return out

    def _fields(self, typename: str):
        return [(normalize_fieldname(f), d) for f, d in self.typestore.fielddefs[typename][1]]

    def _first_alignment(self, typename: str) -> int:
        kind, info = self._fields(typename)[0][1]
        if kind == Nodetype.BASE:
            return 4 if info[0] == "string" else BASE[info[0]][1]
        if kind == Nodetype.NAME:
            return self._first_alignment(info)
        if kind == Nodetype.ARRAY:
            sub_kind, sub_info = info[0]
            if sub_kind == Nodetype.NAME:
                return self._first_alignment(sub_info)
            return 4 if sub_info[0] == "string" else BASE[sub_info[0]][1]
        return 4

    # --- encoders -------------------------------------------------------------------------------------------

    def _generate_whole(self, typename: str) -> Callable:
        func = self._generate_python_whole(typename)
        if self.accelerate and not self._fixed_size(typename):  # one struct call beats C's field walk
            func = self._accelerated(typename, func)
        self._whole[typename] = func
        return func

    def _fixed_size(self, typename: str) -> bool:
        ops: list = []
        self._flatten(typename, "m", ops, [0])
        return all(op[0] in ("scalar", "bind") for op in ops)

    def _accelerated(self, typename: str, python: Callable) -> Callable:
        """The C encoder with its program for ``typename``; what it does not take goes to ``python``."""
        self._ns[f"_PROG_{_ident(typename)}"] = self._compiled(typename)
        self._ns[f"_PY_{_ident(typename)}"] = python
        self._ns["_accel"] = _cdr_accel.encode
        ident = _ident(typename)
        if self.memo:
            self._ns["_memo"] = self._memo
            keep = typename in self._elements
            call = f"_accel(_PROG_{ident}, m, _memo, {keep})"
        else:
            call = f"_accel(_PROG_{ident}, m)"
        lines = [f"def fast_{ident}(m):", f"    data = {call}", f"    return _PY_{ident}(m) if data is None else data"]
        return self._compile(lines, typename, f"fast_{ident}")

    def _compiled(self, typename: str):
        """The C encoder's program of a type, compiled (see _cdr_accel.c)."""
        found = self._compiled_programs.get(typename)
        if found is None:
            found = self._compiled_programs[typename] = _cdr_accel.compile(self._program(typename))
        return found

    def _c_decoder(self, typename: str):
        """The C decoder's compiled program of a type (see _cdr_accel.c)."""
        if typename not in self.typestore.fielddefs:
            raise MessageError(f"unknown message type {typename!r}")
        found = self._c_decoders[typename] = _cdr_accel.compile_decoder(self._decoder_program(typename))
        return found

    def _decoder_program(self, typename: str) -> tuple:
        """The encoder's program with each message's class: (class, ((kind, field, argument), ...))."""
        ops = []
        for (kind, name, arg), (_, (_, info)) in zip(self._program(typename), self._fields(typename)):
            if kind == _K_MSG:
                arg = self._decoder_program(info)
            elif kind == _K_MSEQ:
                arg = (self._decoder_program(info[0][1]), arg[1], arg[2])
            ops.append((kind, name, arg))
        return self.typestore.types[typename], tuple(ops)

    def _program(self, typename: str) -> tuple:
        """The C encoder's program of a type: ((kind, attribute, argument), ...), see _cdr_accel.c."""
        found = self._programs.get(typename)
        if found is not None:
            return found
        ops = []
        for name, (kind, info) in self._fields(typename):
            name = sys.intern(name)
            if kind == Nodetype.BASE:
                ops.append((_K_STR, name, None) if info[0] == "string" else (_KIND[info[0]], name, None))
            elif kind == Nodetype.NAME:
                ops.append((_K_MSG, name, self._program(info)))
            else:
                (sub_kind, sub_info), length = info
                fixed = length if kind == Nodetype.ARRAY else -1
                if sub_kind == Nodetype.NAME:
                    ops.append((_K_MSEQ, name, (self._program(sub_info), fixed, self._first_alignment(sub_info))))
                elif sub_info[0] == "string":
                    ops.append((_K_SSEQ, name, fixed))
                else:
                    ops.append((_K_PSEQ, name, (_KIND[sub_info[0]], fixed)))
        found = self._programs[typename] = tuple(ops)
        return found

    # --- the generated encoders' source ------------------------------------------------------------------------

    def _compile(self, lines: list[str], typename: str, fname: str) -> Callable:
        exec(compile("\n".join(lines) + "\n", f"<cdr {typename}>", "exec"), self._ns)
        return self._ns[fname]
