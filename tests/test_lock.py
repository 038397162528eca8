"""The lock files (locks/, written by `make lock`) hold to pyproject.toml's ranges and lock every declared dependency,
for every supported Python; and the environment `make` installed is the lock of its Python, version for version."""

from __future__ import annotations

import re
import sys
import tomllib
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.specifiers import SpecifierSet
from packaging.utils import canonicalize_name
from packaging.version import Version

from .lockfile import LOCKS, ROOT, TAG, left_out, pins, read

PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
TEST_EXTRAS = re.search(r"^TEST_EXTRAS\s*:=\s*(\S+)\s*$", (ROOT / "Makefile").read_text(), re.M).group(1).split(",")
SUPPORTED = ("3.11", "3.12", "3.13")


def _declared(python: str, extras: list[str]) -> list[Requirement]:
    """The requirements a set-up for ``python`` declares: build requirements, dependencies and ``extras``."""
    project = PYPROJECT["project"]
    texts = [*PYPROJECT["build-system"]["requires"], *project["dependencies"]]
    texts += [r for extra in extras for r in project["optional-dependencies"][extra]]
    env = {"python_version": python, "python_full_version": f"{python}.0", "extra": ""}
    return [r for r in map(Requirement, texts) if r.marker is None or r.marker.evaluate(env)]


def test_the_supported_pythons_are_the_locked_ones_and_requires_python_says_so():
    requires = SpecifierSet(PYPROJECT["project"]["requires-python"])
    locked = sorted(p.name for p in LOCKS.glob("pylock.*.toml"))
    expected = sorted(f"pylock.{kind}-py{v.replace('.', '')}.toml" for v in SUPPORTED for kind in ("run", "test"))
    assert locked == expected
    assert all(Version(f"{v}.0") in requires for v in SUPPORTED)
    assert Version("3.10.13") not in requires and Version("3.14.0") not in requires, requires


@pytest.mark.parametrize("python", SUPPORTED)
def test_every_declared_dependency_is_locked_within_its_range(python):
    tag = "py" + python.replace(".", "")
    run, test = read(LOCKS / f"pylock.run-{tag}.toml"), read(LOCKS / f"pylock.test-{tag}.toml")
    assert run["lock-version"] == "1.0" and test["lock-version"] == "1.0"
    missing, reason = left_out(test)
    assert missing <= {"torch", "stable-baselines3"} and (not missing or reason), (missing, reason)
    for lock, extras in ((run, []), (test, TEST_EXTRAS)):
        versions = pins(lock)
        for req in _declared(python, extras):
            name = canonicalize_name(req.name)
            if name in missing:
                assert lock is test and name not in versions, f"{name} is both left out and locked"
                continue
            assert name in versions, f"{req} is declared in pyproject.toml but not locked for Python {python}"
            assert req.specifier.contains(versions[name], prereleases=True), (
                f"the lock of Python {python} has {name} {versions[name]}, outside pyproject.toml's {req}"
            )
    test_versions = pins(test)
    moved = {n: (v, test_versions.get(n)) for n, v in pins(run).items() if test_versions.get(n) != v}
    assert not moved, f"the test lock changes what the run lock installs (run, test): {moved}"


def test_every_locked_artifact_has_a_hash():
    for path in LOCKS.glob("pylock.*.toml"):
        for package in read(path)["packages"]:
            files = package.get("wheels", []) + ([package["sdist"]] if "sdist" in package else [])
            assert files and all(f["hashes"].get("sha256") for f in files), (path.name, package["name"])


def _installed_by_pip() -> dict[str, str]:
    """{name: version} of the distributions pip installed in this environment (the ROS interface packages that
    `simatch ros2 --build-interfaces` builds, and the egg-info the ROS wheels carry, are not pip's)."""
    found = {}
    for dist in metadata.distributions():
        if (dist.read_text("INSTALLER") or "").strip() == "pip":
            found[canonicalize_name(dist.metadata["Name"])] = dist.version
    return found


def test_the_environment_make_set_up_is_the_lock_of_this_python():
    if not (Path(sys.prefix) / ".installed-test").is_file():
        pytest.skip(f"not run in a venv that `make setup` installed ({sys.prefix}); `make test` runs it there")
    lock = pins(read(LOCKS / f"pylock.test-{TAG}.toml"))
    installed = _installed_by_pip()
    project = {"simatch", "pip"}  # the project (editable, from the tree) and the pip the Makefile pins
    pip = re.search(r"^PIP\s*:=\s*pip==(\S+)\s*$", (ROOT / "Makefile").read_text(), re.M).group(1)
    assert installed.get("pip") == pip, f"pip {installed.get('pip')} installed, the Makefile pins {pip}"
    wrong = {n: (v, installed.get(n)) for n, v in lock.items() if installed.get(n) != v}
    extra = sorted(set(installed) - set(lock) - project)
    assert not wrong, f"installed versions differ from the lock (locked, installed): {wrong}"
    assert not extra, f"installed but not locked (make test's set-up installs the lock alone): {extra}"
