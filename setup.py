"""The C extensions of simatch; everything else is in pyproject.toml.

* ``simatch.msgs._cdr_accel`` (required): the CDR codec (msgs/_cdr_*.c, one unit per layer) and, compiled with it
  because it calls the encoder directly, the recorder's message log (record/_messagelog*.c); they share
  msgs/_cdr_accel.h (the log's units also record/_messagelog.h).
* ``simatch.sim._inputs`` (required): the simulator's input taps (sim/_inputs.c).
* ``simatch.msgs._positional`` (required): positional construction of messages and of the strategies'
  slotted records, their slots filled in C.

Each build carries the digest of the sources it was made from (``SOURCE_DIGEST``), so tests/msgs/test_extensions.py
checks that the extensions in use are those of the sources in the tree.
"""

import hashlib
from pathlib import Path

from setuptools import Extension, setup

SRC = "src/simatch/"


def source_digest(paths: list[str]) -> str:
    """The first 16 hex digits of the SHA-256 of C sources, in order (the same in tests/msgs/test_extensions.py)."""
    digest = hashlib.sha256()
    for path in paths:
        digest.update(Path(path).read_bytes())
    return digest.hexdigest()[:16]


def extension(name: str, sources: list[str], headers: list[str] = ()) -> Extension:
    sources, headers = [SRC + s for s in sources], [SRC + h for h in headers]
    digest = source_digest(sources + headers)
    return Extension(name, sources, depends=headers, define_macros=[("SIMATCH_SOURCE_DIGEST", f'"{digest}"')])


#: the units of simatch.msgs._cdr_accel: the CDR codec's layers, then the recorder's message log's
CDR_ACCEL = [
    "msgs/_cdr_accel.c",
    "msgs/_cdr_program.c",
    "msgs/_cdr_encode.c",
    "msgs/_cdr_memo.c",
    "msgs/_cdr_decode.c",
    "record/_messagelog.c",
    "record/_messagelog_poses.c",
    "record/_messagelog_chunks.c",
]

setup(
    ext_modules=[
        extension("simatch.msgs._cdr_accel", CDR_ACCEL, ["msgs/_cdr_accel.h", "record/_messagelog.h"]),
        extension("simatch.sim._inputs", ["sim/_inputs.c"]),
        extension("simatch.msgs._positional", ["msgs/_positional.c"]),
    ]
)
