"""The C extensions in use are built from the sources in the tree.

An editable install keeps the last build where an extension has not been rebuilt since its sources changed,
so a change to the C sources could go unnoticed while every test runs the old build. Each build carries the
digest of the sources it was made from (setup.py); they must match."""

from __future__ import annotations

import ast
import hashlib
import importlib
import shutil
import sysconfig
from pathlib import Path

import pytest

import simatch

PACKAGE = Path(simatch.__file__).parent
SETUP = PACKAGE.parents[1] / "setup.py"


def _setup_sources() -> dict[str, list[str]]:
    """Each extension's sources, headers last, as setup.py lists them (paths in the simatch package), read from
    its text (running it would build); empty where setup.py is not beside the package (an installed wheel)."""
    if not SETUP.exists():
        return {}
    tree = ast.parse(SETUP.read_text())
    lists = {
        target.id: ast.literal_eval(node.value)
        for node in tree.body
        if isinstance(node, ast.Assign) and isinstance(node.value, ast.List)
        for target in node.targets
        if isinstance(target, ast.Name)
    }
    found = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "extension":
            name, *parts = node.args
            paths = [lists[p.id] if isinstance(p, ast.Name) else ast.literal_eval(p) for p in parts]
            found[ast.literal_eval(name)] = [path for part in paths for path in part]
    return found


#: each extension's sources, header included, in setup.py's order
SOURCES = _setup_sources()


def test_every_c_file_of_the_package_is_built_into_an_extension():
    """setup.py lists every C source and header of the package (a unit split off is built and digested)."""
    if not SOURCES:
        pytest.skip("no setup.py beside the package (an installed wheel)")
    listed = {path for paths in SOURCES.values() for path in paths}
    files = {f.relative_to(PACKAGE).as_posix() for f in PACKAGE.rglob("*.[ch]")}
    assert files == listed, f"not in setup.py: {sorted(files - listed)}; listed, not found: {sorted(listed - files)}"


def _compiler() -> str | None:
    cc = (sysconfig.get_config_var("CC") or "cc").split()
    return shutil.which(cc[0]) if cc else None


@pytest.mark.parametrize("name", sorted(SOURCES))
def test_the_extension_in_use_is_built_from_the_source_in_the_tree(name):
    sources = [PACKAGE / path for path in SOURCES[name]]
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
