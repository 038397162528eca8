"""The wire format of CDR as the generated Python codec (`simatch.msgs.cdr`) writes and reads it: XCDR1 little
endian with the 4-byte encapsulation header; each primitive aligned to its size, counted from the start of the
body."""

from __future__ import annotations

import struct

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
#: ROS base types: numpy dtype of a sequence of them on the wire
DTYPE = {
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


def _ident(typename: str) -> str:
    return typename.replace("/", "_")
