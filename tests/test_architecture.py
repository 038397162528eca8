"""The architecture and the code style are checked, not only described.

The import contract in pyproject.toml ([tool.importlinter]) holds the layers of docs/architecture.md and
the independence of the paper's three subsystems; a change that crosses a boundary fails here with the
offending import named. ruff checks the whole tree (lint rules and formatting in pyproject.toml).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _tool(name: str) -> str:
    path = Path(sys.executable).parent / name
    found = str(path) if path.exists() else shutil.which(name)
    assert found, f"{name} is not installed (it comes with the test extras: pip install -e '.[test]')"
    return found


def _run(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run(argv, cwd=ROOT, capture_output=True, text=True, timeout=120)


def test_import_contracts_hold():
    out = _run(_tool("lint-imports"), "--no-cache")
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-2000:]
    assert "0 broken" in out.stdout


def test_a_crossing_import_is_named(tmp_path):
    """The contract really bites: a copy of the tree where the simulator imports the referee fails, and the
    report names the importing module and the imported one."""
    tree = tmp_path / "src"
    shutil.copytree(ROOT / "src" / "simatch", tree / "simatch", ignore=shutil.ignore_patterns("__pycache__", "*.so"))
    victim = tree / "simatch" / "sim" / "perception.py"
    victim.write_text(victim.read_text() + "\nfrom ..scene.referee import referee as _crossing  # noqa\n")
    config = tmp_path / "contracts.toml"
    config.write_text((ROOT / "pyproject.toml").read_text())
    out = subprocess.run(
        [_tool("lint-imports"), "--no-cache", "--config", str(config)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        env={"PYTHONPATH": str(tree), "PATH": "/usr/bin:/bin"},
    )
    assert out.returncode != 0
    assert "simatch.sim.perception -> simatch.scene.referee.referee" in out.stdout


def test_ruff_lint_is_clean():
    out = _run(_tool("ruff"), "check", "--no-cache", ".")
    assert out.returncode == 0, out.stdout[-4000:]


def test_ruff_format_is_clean():
    out = _run(_tool("ruff"), "format", "--check", "--no-cache", ".")
    assert out.returncode == 0, out.stdout[-4000:]
