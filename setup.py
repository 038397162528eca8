"""Only the optional C extensions of the messages; everything else is in pyproject.toml.

Both are optional: where they cannot be compiled (no C compiler), simatch uses its pure-Python encoders,
which write the same bytes, and builds messages by their classes (the same messages). Each build carries the
digest of the source it was made from (``SOURCE_DIGEST``): an optional extension that fails to compile only
warns and leaves the last build in place, so tests/msgs/test_extensions.py checks that the extensions in use
are those of the sources in the tree.
"""

import hashlib
from pathlib import Path

from setuptools import Extension, setup


def source_digest(path: str) -> str:
    """The first 16 hex digits of the SHA-256 of a C source (the same in tests/msgs/test_extensions.py)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16]


def extension(name: str, path: str) -> Extension:
    return Extension(name, [path], optional=True, define_macros=[("SIMATCH_SOURCE_DIGEST", f'"{source_digest(path)}"')])


setup(
    ext_modules=[
        extension("simatch.msgs._cdr_accel", "src/simatch/msgs/_cdr_accel.c"),
        extension("simatch.msgs._positional", "src/simatch/msgs/_positional.c"),
    ]
)
