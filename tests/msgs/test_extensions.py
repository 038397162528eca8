"""The C extensions in use are built from the sources in the tree.

Both are optional (setup.py): where one fails to compile, pip only warns, and an editable install keeps the
last build, so a broken change to the C source could go unnoticed while every test runs the old build. Each
build carries the digest of the source it was made from; where a C compiler is at hand (the development and CI
machines), the extensions must be there and match."""

from __future__ import annotations

import hashlib
import importlib
import shutil
import sysconfig
from pathlib import Path

import pytest

import simatch.msgs

SOURCES = {"simatch.msgs._cdr_accel": "_cdr_accel.c", "simatch.msgs._positional": "_positional.c"}


def _compiler() -> str | None:
    cc = (sysconfig.get_config_var("CC") or "cc").split()
    return shutil.which(cc[0]) if cc else None


@pytest.mark.parametrize("name", sorted(SOURCES))
def test_the_extension_in_use_is_built_from_the_source_in_the_tree(name):
    source = Path(simatch.msgs.__file__).parent / SOURCES[name]
    if not source.exists():
        pytest.skip("installed without the C sources (a wheel): nothing to compare with")
    digest = hashlib.sha256(source.read_bytes()).hexdigest()[:16]  # (as setup.py's source_digest)
    try:
        module = importlib.import_module(name)
    except ImportError as exc:
        if _compiler() is None:
            pytest.skip("no C compiler here: simatch uses the pure-Python twins")
        pytest.fail(f"{name} is not built although a C compiler is here ({exc}): `pip install -e . -v` says why")
    assert module.SOURCE_DIGEST == digest, (
        f"{name} was built from another version of {source.name} (a failed compile keeps the last build): "
        f"rebuild it (make setup, or pip install -e . -v) and read the compiler's messages"
    )
