"""The generated Python decoders of `simatch.msgs.cdr.Codec`: for each type, Python source made from its fields
and compiled once, which unpacks each run of fixed-size fields with one precompiled ``struct.Struct``, reads
primitive sequences as read-only numpy views of the payload, and checks every length against what is left
(`MessageError` on a malformed payload, never anything else)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from rosbags.interfaces import Nodetype

from .cdr_encoders import _Lazy
from .cdr_wire import BASE, DTYPE, _ident, _run_structs


class PythonDecoders:
    """The decoder generation of `Codec` (a base class of it: they share its namespace and caches)."""

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
            self._ns[dkey] = np.dtype(DTYPE[base])
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


def _read_string(indent: str, x: str) -> list[str]:
    return [
        f"{indent}pos += -pos & 3",
        f"{indent}k, = _U32.unpack_from(b, pos)",
        f"{indent}if k < 1 or pos + 4 + k > len(b) or b[pos + 3 + k] != 0:",
        f"{indent}    raise Error('bad string at byte %d' % pos)",
        f"{indent}{x} = b[pos + 4:pos + 3 + k].decode()",
        f"{indent}pos += 4 + k",
    ]


class _LazyDecoder(_Lazy):
    __slots__ = ()

    def get(self) -> Callable:
        if self.func is None:
            self.func = self.codec._decoder_at(self.typename)
        return self.func
