"""The C extensions in use are built from the sources in the tree.

An editable install keeps the last build where an extension has not been rebuilt since its sources changed,
so a change to the C sources could go unnoticed while every test runs the old build. Each build carries the
digest of the sources it was made from (setup.py); they must match."""

from __future__ import annotations

import hashlib
import importlib
import shutil
import sysconfig
from pathlib import Path

import pytest

import simatch

#: each extension's sources, header included, in setup.py's order (paths in the simatch package)
SOURCES = {
    "simatch.msgs._cdr_accel": ["msgs/_cdr_accel.c", "record/_messagelog.c", "msgs/_cdr_accel.h"],
    "simatch.sim._inputs": ["sim/_inputs.c"],
    "simatch.msgs._positional": ["msgs/_positional.c"],
}


def _compiler() -> str | None:
    cc = (sysconfig.get_config_var("CC") or "cc").split()
    return shutil.which(cc[0]) if cc else None


@pytest.mark.parametrize("name", sorted(SOURCES))
def test_the_extension_in_use_is_built_from_the_source_in_the_tree(name):
    package = Path(simatch.__file__).parent
    sources = [package / path for path in SOURCES[name]]
    if not all(source.exists() for source in sources):
        pytest.skip("installed without the C sources (a wheel): nothing to compare with")
    digest = hashlib.sha256()
    for source in sources:  # (as setup.py's source_digest)
        digest.update(source.read_bytes())
    digest = digest.hexdigest()[:16]
    try:
        module = importlib.import_module(name)
    except ImportError as exc:
        if _compiler() is None:
            pytest.skip("no C compiler here")
        pytest.fail(f"{name} is not built although a C compiler is here ({exc}): `pip install -e . -v` says why")
    assert module.SOURCE_DIGEST == digest, (
        f"{name} was built from other versions of {SOURCES[name]} (a failed compile keeps the last build): "
        f"rebuild it (make setup, or pip install -e . -v) and read the compiler's messages"
    )
