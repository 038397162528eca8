"""The lock files of locks/ as the tests read them: which lock belongs to this Python, what it pins, and what it
leaves out for this Python and why (scripts/lock.py writes them; docs/install.md)."""

from __future__ import annotations

import sys
import tomllib
from pathlib import Path

import pytest
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parents[1]
LOCKS = ROOT / "locks"
TAG = f"py{sys.version_info[0]}{sys.version_info[1]}"


def read(path: Path) -> dict:
    return tomllib.loads(path.read_text(encoding="utf-8"))


def pins(lock: dict) -> dict[str, str]:
    """{normalised name: version} of a lock's packages."""
    return {canonicalize_name(p["name"]): p["version"] for p in lock["packages"]}


def left_out(lock: dict) -> tuple[set[str], str]:
    """The declared packages a lock leaves out for its Python, and the reason it records."""
    note = lock.get("tool", {}).get("simatch", {})
    return {canonicalize_name(n) for n in note.get("left-out", [])}, note.get("reason", "")


def skip_unless_locked(name: str) -> None:
    """Skips the calling test, with the lock's reason, where this Python's test lock leaves ``name`` out (torch's
    CPU wheel exists for some Pythons only); where the lock has it, the test runs and a missing package fails."""
    path = LOCKS / f"pylock.test-{TAG}.toml"
    if not path.is_file():
        pytest.fail(f"no lock for this Python in {path.parent}: {path.name} (supported Pythons: docs/install.md)")
    missing, reason = left_out(read(path))
    if canonicalize_name(name) in missing:
        pytest.skip(f"{name} is not in the lock of Python {sys.version_info[0]}.{sys.version_info[1]}: {reason}")
