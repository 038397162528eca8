"""The generated Python encoders of `simatch.msgs.cdr.Codec`: for each type, Python source made from its fields and
compiled once, which flattens nested messages so that every run of consecutive fixed-size fields is packed by
one precompiled ``struct.Struct`` (one per alignment phase of its start), appends numpy arrays' bytes as they
lie in memory, and with ``memo`` encodes once a list or message met again. They encode what the C encoder does
not take as it is (and fixed-size messages, in one ``struct`` call)."""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from rosbags.interfaces import Nodetype

from .cdr_wire import _LEN, BASE, DTYPE, _ident, _lenpad, _run_structs

if TYPE_CHECKING:
    from .cdr import Codec


class PythonEncoders:
    """The encoder generation of `Codec` (a base class of it: they share its namespace and caches)."""

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

    def _parts_of(self, typename: str) -> Callable:
        found = self._parts.get(typename)
        if found is None:
            found = self._generate_parts(typename)
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
                self._strings_op(op, lines)
            elif kind == "numbers":
                self._numbers_op(op, lines)
            else:
                self._messages_op(op, lines, name)
        flush_run()
        lines.append("    return pos")
        self._ns["_encode_strings"] = _encode_strings
        func = self._compile(lines, typename, f"enc_{ident}")
        self._parts[typename] = func
        return func

    def _strings_op(self, op, lines: list[str]) -> None:
        """A sequence (or fixed array) of strings; kept by value (and with memo, by identity)."""
        e = op[1]
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

    def _numbers_op(self, op, lines: list[str]) -> None:
        """A sequence (or fixed array) of primitives: an array's bytes as they lie, anything else converted."""
        e = op[1]
        base, length = op[2], op[3]
        size = BASE[base][1]
        dkey = f"_D_{base}"
        self._ns[dkey] = np.dtype(DTYPE[base])
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


def _as_bytes(value: Any, dtype: np.dtype) -> bytes:
    """Bytes of a primitive sequence that is not already a contiguous array of the wire's dtype."""
    return np.ascontiguousarray(value, dtype=dtype).tobytes()


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
