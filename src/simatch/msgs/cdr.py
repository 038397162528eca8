"""CDR for any ``rosbags`` type store: generated encoders and decoders, byte for byte what rosbags writes.

The bus between processes encodes every robot's perception at every control tick on the lockstep's
critical path, and a recording encodes some two thousand messages per simulated second on the thread that
runs the simulation. ``rosbags`` walks a message field by field (twice when writing: size, then bytes).
`Codec` compiles, once per type, Python functions that

* flatten nested messages, so that every run of consecutive fixed-size fields (across message
  boundaries) is packed or unpacked by one precompiled ``struct.Struct``, one per alignment phase of its
  start (CDR aligns each primitive to its size, counted from the start of the body);
* pack a whole fixed-size message, encapsulation header included, with a single ``struct`` call;
* append numpy arrays' bytes as they lie in memory, and read primitive sequences back as read-only numpy
  views of the payload (as rosbags does);
* check what they read: a payload that is cut short, claims more elements than it holds, holds a bad
  string or bytes too many raises `MessageError`, never anything else.

With ``memo=True`` (a recorder: messages are read-only once published) it also encodes once what it meets
again in the current or the previous memo period (`forget` starts a new one): a list of sub-messages or of
strings that is the same object (the team list that perception gives every teammate, the model names), and
a message already encoded on its own and met again inside a sequence (the StrategyInfo a robot published
at one control tick is in its team's TeamStrategy at the next). Lists of strings are also kept by value.

Where setup.py could build the C extension (``_cdr_accel.c``), messages with sequences are encoded by it:
`Codec` compiles each type's encoder program once (`program`), and the C encoder walks a message with it
(what it does not take as it is, e.g. a list where an array is expected, goes to the Python encoder).
Little-endian payloads are decoded by it too, with the same program and each message's class (every process
of a distributed run decodes its perception at every control tick, on its critical path: half the time of
the generated decoders, most of what is left being numpy's array constructor). The extension also holds
``Log``, the recorder's message log (`simatch.record.messagelog`). Setting the environment variable
``SIMATCH_CDR_PURE_PYTHON=1`` uses the pure-Python encoders and decoders everywhere, as on a machine without
a C compiler; both write the same bytes and read the same messages (tests compare them).

Output: XCDR1 little endian with the 4-byte encapsulation header, as ROS 2 and rosbag2 write it; a
big-endian payload is handed to rosbags to read.

    codec = Codec(msgs.typestore)
    data = codec.encode(msg)                     # bytes
    again = codec.decode(msg.__msgtype__, data)  # MessageError if ``data`` is not one
"""

from __future__ import annotations

import os
import struct
import sys
from collections.abc import Callable
from typing import Any

import numpy as np
from rosbags.interfaces import Nodetype
from rosbags.typesys.base import normalize_fieldname

from . import MessageError

#: set (to anything but "" or "0") to use the pure-Python encoders even where the C encoder is built: what a
#: machine without a C compiler runs (tests compare both)
PURE_PYTHON_ENV = "SIMATCH_CDR_PURE_PYTHON"

try:  # the C encoder (setup.py builds it where a compiler is at hand)
    if os.environ.get(PURE_PYTHON_ENV, "") not in ("", "0"):
        raise ImportError(f"{PURE_PYTHON_ENV} is set")
    from ._cdr_accel import Log, Tap, pack
    from ._cdr_accel import compile as _accel_compile
    from ._cdr_accel import compile_decoder as _accel_compile_decoder
    from ._cdr_accel import decode as _accel_decode
    from ._cdr_accel import encode as _accel_encode
    from ._cdr_accel import setup as _accel_setup
    from ._cdr_accel import setup_decoding as _accel_setup_decoding
except ImportError:  # a machine without a C compiler
    _accel_encode = _accel_setup = _accel_compile = Log = Tap = pack = None
    _accel_decode = _accel_compile_decoder = _accel_setup_decoding = None

if sys.byteorder != "little":  # encoders append numpy buffers as they lie in memory
    raise ImportError("simatch.msgs.cdr needs a little-endian machine")

HEADER = b"\x00\x01\x00\x00"  # CDR_LE encapsulation

#: ROS base types: struct format character and size (= CDR alignment)
BASE = {
    "bool": ("?", 1),
    "byte": ("B", 1),
    "char": ("B", 1),
    "octet": ("B", 1),
    "int8": ("b", 1),
    "uint8": ("B", 1),
    "int16": ("h", 2),
    "uint16": ("H", 2),
    "int32": ("i", 4),
    "uint32": ("I", 4),
    "int64": ("q", 8),
    "uint64": ("Q", 8),
    "float32": ("f", 4),
    "float64": ("d", 8),
}
_DTYPE = {
    "bool": "<?",
    "byte": "<u1",
    "char": "<u1",
    "octet": "<u1",
    "int8": "<i1",
    "uint8": "<u1",
    "int16": "<i2",
    "uint16": "<u2",
    "int32": "<i4",
    "uint32": "<u4",
    "int64": "<i8",
    "uint64": "<u8",
    "float32": "<f4",
    "float64": "<f8",
}
_U32 = struct.Struct("<I")
_LEN = [struct.Struct(f"<{p}xI") if p else _U32 for p in range(4)]  # by padding needed
_ZEROS = [bytes(p) for p in range(8)]
_MEMO_LIMIT = 4096  # string lists kept by value
#: kinds of the C encoder's programs (see _cdr_accel.c)
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
#: the C encoder is used when it was built
ACCELERATED = _accel_encode is not None
#: ... and reads numpy arrays directly when it recognises their layout (otherwise: the buffer protocol)
DIRECT_ARRAYS = ACCELERATED and _accel_setup(
    np.ndarray, {k: np.dtype(_DTYPE[b]) for b, k in _KIND.items()}, np.arange(3.0)
)
#: little-endian payloads are decoded by the C decoder too (it makes its arrays with the ndarray type above)
C_DECODER = DIRECT_ARRAYS and _accel_decode is not None
if C_DECODER:
    _accel_setup_decoding(MessageError)


def _lenpad(size: int) -> list[struct.Struct]:
    """For a non-empty sequence of ``size``-byte primitives: by start phase (0..7), the struct that packs the
    padding before the length, the length and the padding before the first element."""
    out = []
    for phase in range(8):
        pre = -phase % 4
        post = -(phase + pre + 4) % size
        out.append(struct.Struct(f"<{pre}xI{post}x"))
    return out


def _run_structs(chars: list[tuple[str, int]]) -> list[struct.Struct]:
    """For a run of fixed-size fields: by start phase (0..7), the struct with CDR's padding inside the run."""
    out = []
    for start in range(8):
        fmt, cur = "<", start
        for ch, size in chars:
            pad = -cur % size
            if pad:
                fmt += f"{pad}x"
            fmt += ch
            cur += pad + size
        out.append(struct.Struct(fmt))
    return out


def _as_bytes(value: Any, dtype: np.dtype) -> bytes:
    """Bytes of a primitive sequence that is not already a contiguous array of the wire's dtype."""
    return np.ascontiguousarray(value, dtype=dtype).tobytes()


class Codec:
    """Encoders and decoders for every type of a ``rosbags`` type store, generated on first use."""

    def __init__(self, typestore, *, memo: bool = False, accelerate: bool = True):
        self.typestore = typestore
        self.memo = memo
        self.accelerate = accelerate and ACCELERATED
        self._programs: dict[str, tuple] = {}
        self._compiled_programs: dict[str, Any] = {}
        self._appenders: dict[str, Callable] = {}
        self._memo = ({}, {})  # the C encoder's: this period's, the last one's
        self._whole: dict[str, Callable] = {}  # type -> encode(msg) -> bytes
        self._parts: dict[str, Callable] = {}  # type -> enc(msg, out, pos) -> pos
        self._decoders: dict[str, Callable] = {}  # type -> decode(body) -> msg
        self._decoders_at: dict[str, Callable] = {}  # type -> dec(body, pos) -> (msg, pos)
        self._c_decoders: dict[str, Any] = {}  # type -> the C decoder's compiled program
        self.c_decoding = self.accelerate and C_DECODER
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
        """What the C message log (``Log``, see _cdr_accel.c) needs to encode ``typename``: the C encoder's
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
        if self.c_decoding and data[:2] == b"\x00\x01":
            program = self._c_decoders.get(typename)
            if program is None:
                program = self._c_decoder(typename)
            try:
                return _accel_decode(program, data)
            except MessageError as exc:
                raise MessageError(f"malformed {typename} payload ({len(data)} bytes): {exc}") from None
        func = self._decoders.get(typename)
        if func is None:
            if typename not in self.typestore.fielddefs:
                raise MessageError(f"unknown message type {typename!r}")
            func = self._generate_decoder(typename)
        if data[:2] != b"\x00\x01":  # not little-endian CDR: rosbags reads it (or refuses)
            try:
                return self.typestore.deserialize_cdr(data, typename)
            except Exception as exc:
                raise MessageError(f"malformed {typename} payload ({len(data)} bytes): {exc}") from None
        try:
            msg, end = func(data)
        except MessageError as exc:
            raise MessageError(f"malformed {typename} payload ({len(data)} bytes): {exc}") from None
        except (struct.error, ValueError, UnicodeDecodeError, IndexError, TypeError) as exc:
            raise MessageError(f"malformed {typename} payload ({len(data)} bytes): {exc}") from None
        if end + 3 < len(data):
            raise MessageError(f"malformed {typename} payload ({len(data)} bytes): {len(data) - end} bytes too many")
        return msg

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

    def _flatten(self, typename: str, expr: str, ops: list, counter: list[int]) -> None:
        """Encoding ops of one message; nested messages are inlined (bound to a local once)."""
        for name, (kind, info) in self._fields(typename):
            e = f"{expr}.{name}"
            if kind == Nodetype.BASE:
                ops.append(("string", e) if info[0] == "string" else ("scalar", e, *BASE[info[0]]))
            elif kind == Nodetype.NAME:
                counter[0] += 1
                local = f"n{counter[0]}"
                ops.append(("bind", local, e))
                self._flatten(info, local, ops, counter)
            else:
                (sub_kind, sub_info), length = info
                fixed = length if kind == Nodetype.ARRAY else None
                if sub_kind == Nodetype.BASE and sub_info[0] == "string":
                    ops.append(("strings", e, fixed))
                elif sub_kind == Nodetype.BASE:
                    ops.append(("numbers", e, sub_info[0], fixed))
                else:
                    ops.append(("messages", e, sub_info, fixed))

    # --- encoders -------------------------------------------------------------------------------------------
    def _parts_of(self, typename: str) -> Callable:
        found = self._parts.get(typename)
        if found is None:
            found = self._generate_parts(typename)
        return found

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
        self._ns["_accel"] = _accel_encode
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
            found = self._compiled_programs[typename] = _accel_compile(self._program(typename))
        return found

    def _c_decoder(self, typename: str):
        """The C decoder's compiled program of a type (see _cdr_accel.c)."""
        if typename not in self.typestore.fielddefs:
            raise MessageError(f"unknown message type {typename!r}")
        found = self._c_decoders[typename] = _accel_compile_decoder(self._decoder_program(typename))
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

    def _generate_python_whole(self, typename: str) -> Callable:
        ops: list = []
        self._flatten(typename, "m", ops, [0])
        ident = _ident(typename)
        if self._fixed_size(typename):  # one struct, header included
            key = f"_W_{ident}"
            scalars = [op for op in ops if op[0] == "scalar"]
            body = _run_structs([(ch, size) for _, _, ch, size in scalars])[0]
            self._ns[key] = struct.Struct("<4s" + body.format[1:])
            lines = [f"def whole_{ident}(m):"]
            lines += [f"    {op[1]} = {op[2]}" for op in ops if op[0] == "bind"]
            lines.append(f"    return {key}.pack(_HEADER, {', '.join(op[1] for op in scalars)})")
        else:
            parts = self._parts_of(typename)
            self._ns[f"_P_{ident}"] = parts
            lines = [
                f"def whole_{ident}(m):",
                "    out = [_HEADER]",
                f"    _P_{ident}(m, out, 0)",
                "    data = b''.join(out)",
            ]
            if self.memo and typename in self._elements:  # may be met again inside a sequence
                lines.append("    _objs[id(m)] = (m, data)")
            lines.append("    return data")
        return self._compile(lines, typename, f"whole_{ident}")

    def _generate_parts(self, typename: str) -> Callable:
        ops: list = []
        self._flatten(typename, "m", ops, [0])
        ident = _ident(typename)
        lines = [f"def enc_{ident}(m, out, pos):", "    app = out.append"]
        run: list = []
        k = [0]

        def name(prefix: str) -> str:
            k[0] += 1
            return f"_{prefix}{ident}_{k[0]}"

        def flush_run() -> None:
            if not run:
                return
            key = name("R")
            self._ns[key] = _run_structs([(ch, size) for _, _, ch, size in run])
            lines.append(f"    st = {key}[pos & 7]")
            lines.append(f"    app(st.pack({', '.join(e for _, e, _, _ in run)}))")
            lines.append("    pos += st.size")
            run.clear()

        for op in ops:
            kind = op[0]
            if kind == "scalar":
                run.append(op)
                continue
            if kind == "bind":
                lines.append(f"    {op[1]} = {op[2]}")
                continue
            flush_run()
            e = op[1]
            if kind == "string":
                lines += [
                    f"    b = {e}.encode()",
                    "    app(_LEN[-pos & 3].pack(len(b) + 1) + b + b'\\x00')",
                    "    pos += (-pos & 3) + 5 + len(b)",
                ]
            elif kind == "strings":
                # a list of names (every model of the run) repeats message after message: kept by value
                length = op[2]
                lines += [f"    v = {e}"]
                if length is not None:
                    lines += [
                        f"    if len(v) != {length}:",
                        f"        raise Error('{e.partition('.')[2]}: expected {length} strings, got %d' % len(v))",
                    ]
                by_value = [
                    "key = (pos & 7, tuple(v))",
                    "hit = _strings.get(key)",
                    "if hit is None:",
                    f"    hit = _encode_strings(v, pos & 7, {length is None})",
                    "    if len(_strings) >= _LIMIT:",
                    "        _strings.clear()",
                    "    _strings[key] = hit",
                ]
                if self.memo:  # the same list again (the simulator's model names): no tuple, no hash
                    lines += [
                        "    hit = _seqs.get(id(v))",
                        "    if hit is None or hit[0] is not v or hit[1] != pos & 7:",
                    ]
                    lines += ["        " + line for line in by_value]
                    lines += ["        _seqs[id(v)] = (v, pos & 7, hit)", "    else:", "        hit = hit[2]"]
                else:
                    lines += ["    " + line for line in by_value]
                lines += ["    app(hit)", "    pos += len(hit)"]
            elif kind == "numbers":
                base, length = op[2], op[3]
                size = BASE[base][1]
                dkey = f"_D_{base}"
                self._ns[dkey] = np.dtype(_DTYPE[base])
                convert = f"b = v.tobytes() if type(v) is _ndarray and v.dtype is {dkey} else _asb(v, {dkey})"
                lines.append(f"    v = {e}")
                if length is None:
                    hkey = f"_H{size}"
                    self._ns[hkey] = _lenpad(size)
                    lines += [
                        "    if len(v):",
                        f"        h = {hkey}[pos & 7]",
                        "        app(h.pack(len(v)))",
                        "        pos += h.size",
                        f"        {convert}",
                        "        app(b)",
                        "        pos += len(b)",
                        "    else:",
                        "        app(_LEN[-pos & 3].pack(0))",
                        "        pos += (-pos & 3) + 4",
                    ]
                else:
                    lines.append(f"    {convert}")
                    lines += [
                        f"    if len(b) != {length * size}:",
                        f"        raise Error('{e.partition('.')[2]}: expected {length} elements, "
                        f"got %d' % (len(b) // {size}))",
                    ]
                    if size > 1:
                        lines += [f"    p = -pos & {size - 1}", "    app(_ZEROS[p])", "    pos += p"]
                    lines += ["    app(b)", "    pos += len(b)"]
            else:
                self._messages_op(op, lines, name)
        flush_run()
        lines.append("    return pos")
        self._ns["_encode_strings"] = _encode_strings
        func = self._compile(lines, typename, f"enc_{ident}")
        self._parts[typename] = func
        return func

    def _messages_op(self, op, lines: list[str], name) -> None:
        """A sequence (or fixed array) of messages; with memo, a list met again and elements encoded on
        their own before are not encoded again."""
        _, e, sub, length = op
        fkey = name("E")
        self._ns[fkey] = _Lazy(self, sub)
        align = self._first_alignment(sub)
        reuse = self.memo and sub in self._elements
        lines.append(f"    v = {e}")
        if length is None:
            lines += ["    app(_LEN[-pos & 3].pack(len(v)))", "    pos += (-pos & 3) + 4"]
        else:
            lines += [
                f"    if len(v) != {length}:",
                f"        raise Error('{e.partition('.')[2]}: expected {length} messages, got %d' % len(v))",
            ]
        body = [f"f = {fkey}.get()", "for it in v:"]
        if reuse:
            body += [
                "    hit = _objs.get(id(it))",
                "    if hit is None:",
                "        hit = _objs_old.get(id(it))",
                "    if hit is not None and hit[0] is it:",
                f"        q = pos + (-pos & {align - 1})",
                "        if not q & 7:",
                "            if q != pos:",
                "                sub.append(_ZEROS[q - pos])",
                "            sub.append(hit[1][4:])",
                "            pos = q + len(hit[1]) - 4",
                "            continue",
            ]
        body.append("    pos = f(it, sub, pos)")
        if not self.memo:
            lines.append("    sub = out")
            lines += ["    " + line for line in body]
            return
        lines += [
            "    hit = _seqs.get(id(v))",
            "    if hit is not None and hit[0] is v and hit[1] == pos & 7:",
            "        app(hit[2])",
            "        pos += len(hit[2])",
            "    else:",
            "        sub = []",
            "        start = pos",
        ]
        lines += ["        " + line for line in body]
        lines += ["        b = b''.join(sub)", "        _seqs[id(v)] = (v, start & 7, b)", "        app(b)"]

    # --- decoders -------------------------------------------------------------------------------------------
    def _decoder_at(self, typename: str) -> Callable:
        found = self._decoders_at.get(typename)
        if found is None:
            found = self._generate_decoder_at(typename)
        return found

    def _generate_decoder(self, typename: str) -> Callable:
        """decode(data) -> (msg, end): the whole payload, header included (alignment counts from byte 4)."""
        ident = _ident(typename)
        at = self._decoder_at(typename)
        self._ns[f"_A_{ident}"] = at
        lines = [
            f"def decode_{ident}(data):",
            "    b = data[4:]",
            f"    msg, pos = _A_{ident}(b, 0)",
            "    return msg, pos + 4",
        ]
        func = self._compile(lines, typename, f"decode_{ident}")
        self._decoders[typename] = func
        return func

    def _generate_decoder_at(self, typename: str) -> Callable:
        ident = _ident(typename)
        self._decoders_at[typename] = None  # type: ignore[assignment]  (recursion guard)
        lines = [f"def dec_{ident}(b, pos):"]
        run: list = []  # (local, char, size)
        k = [0]

        def local() -> str:
            k[0] += 1
            return f"x{k[0]}"

        def flush_run() -> None:
            if not run:
                return
            key = f"_U{ident}_{k[0]}"
            self._ns[key] = _run_structs([(ch, size) for _, ch, size in run])
            lines.append(f"    s = {key}[pos & 7]")
            lines.append(f"    {', '.join(x for x, _, _ in run)}, = s.unpack_from(b, pos)")
            lines.append("    pos += s.size")
            run.clear()

        def read(name: str) -> str:
            """Emit the reads of one message's fields; returns the expression that builds it."""
            ckey = f"_C_{_ident(name)}"
            self._ns[ckey] = self.typestore.types[name]
            args = []
            for fname, (kind, info) in self._fields(name):
                if kind == Nodetype.BASE and info[0] != "string":
                    x = local()
                    run.append((x, *BASE[info[0]]))
                    args.append(x)
                    continue
                if kind == Nodetype.NAME:
                    args.append(read(info))
                    continue
                flush_run()
                x = local()
                if kind == Nodetype.BASE:
                    lines.extend(_read_string("    ", x))
                else:
                    self._read_array(fname, kind, info, x, lines)
                args.append(x)
            return f"{ckey}({', '.join(args)})"

        expr = read(typename)
        flush_run()
        lines.append(f"    return {expr}, pos")
        func = self._compile(lines, typename, f"dec_{ident}")
        self._decoders_at[typename] = func
        return func

    def _read_array(self, fname: str, kind, info, x: str, lines: list[str]) -> None:
        (sub_kind, sub_info), length = info
        if kind == Nodetype.SEQUENCE:
            lines += ["    pos += -pos & 3", "    n, = _U32.unpack_from(b, pos)", "    pos += 4"]
        else:
            lines.append(f"    n = {length}")
        if sub_kind == Nodetype.BASE and sub_info[0] != "string":
            base = sub_info[0]
            size = BASE[base][1]
            dkey = f"_D_{base}"
            self._ns[dkey] = np.dtype(_DTYPE[base])
            if size > 1:
                lines += ["    if n:", f"        pos += -pos & {size - 1}"]
            lines += [
                f"    if pos + n * {size} > len(b):",
                f"        raise Error('{fname}: %d elements do not fit' % n)",
                f"    {x} = _ndarray((n,), {dkey}, b, pos)",
                f"    pos += n * {size}",
            ]
        elif sub_kind == Nodetype.BASE:
            lines += [
                "    if n * 5 > len(b) - pos:",
                f"        raise Error('{fname}: %d strings do not fit' % n)",
                f"    {x} = []",
                "    for _ in range(n):",
            ]
            lines.extend(_read_string("        ", "y"))
            lines.append(f"        {x}.append(y)")
        else:
            dkey = f"_Q_{_ident(sub_info)}"
            self._ns[dkey] = _LazyDecoder(self, sub_info)
            lines += [
                "    if n > len(b) - pos:",
                f"        raise Error('{fname}: %d messages do not fit' % n)",
                f"    d = {dkey}.get()",
                f"    {x} = []",
                "    for _ in range(n):",
                "        y, pos = d(b, pos)",
                f"        {x}.append(y)",
            ]

    def _compile(self, lines: list[str], typename: str, fname: str) -> Callable:
        exec(compile("\n".join(lines) + "\n", f"<cdr {typename}>", "exec"), self._ns)
        return self._ns[fname]


def _ident(typename: str) -> str:
    return typename.replace("/", "_")


def _read_string(indent: str, x: str) -> list[str]:
    return [
        f"{indent}pos += -pos & 3",
        f"{indent}k, = _U32.unpack_from(b, pos)",
        f"{indent}if k < 1 or pos + 4 + k > len(b) or b[pos + 3 + k] != 0:",
        f"{indent}    raise Error('bad string at byte %d' % pos)",
        f"{indent}{x} = b[pos + 4:pos + 3 + k].decode()",
        f"{indent}pos += 4 + k",
    ]


def _encode_strings(values, start: int, counted: bool) -> bytes:
    """A sequence (or fixed array) of strings starting at phase ``start``, its leading padding included."""
    out, pos = [], start
    if counted:
        out.append(_LEN[-pos & 3].pack(len(values)))
        pos += (-pos & 3) + 4
    for s in values:
        b = s.encode()
        out.append(_LEN[-pos & 3].pack(len(b) + 1) + b + b"\x00")
        pos += (-pos & 3) + 5 + len(b)
    return b"".join(out)


class _Lazy:
    """A nested type's encoder, resolved on first use (types may refer to each other in any order)."""

    __slots__ = ("codec", "typename", "func")

    def __init__(self, codec: Codec, typename: str):
        self.codec, self.typename, self.func = codec, typename, None

    def get(self) -> Callable:
        if self.func is None:
            self.func = self.codec._parts_of(self.typename)
        return self.func


class _LazyDecoder(_Lazy):
    __slots__ = ()

    def get(self) -> Callable:
        if self.func is None:
            self.func = self.codec._decoder_at(self.typename)
        return self.func
