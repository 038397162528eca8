"""The two set-ups of the README's quick start: `make run` installs what running needs, `make test` adds the
test extras. Checked on the Makefile's own commands (``make -n``) and on the code: nothing under src/ imports
a distribution that only the test extras bring, so a run set-up runs every command."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
import tomllib
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

from .lockfile import TAG

ROOT = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]


def _make(target: str, tmp_path, *settings: str, venv: str | None = None) -> list[str]:
    """The pip commands ``make TARGET`` runs with this interpreter on a machine with nothing set up (a venv of its
    own in tmp_path), into that venv (or into ``venv``)."""
    into = venv or str(tmp_path / "venv")
    out = subprocess.run(
        ["make", "-n", "-B", target, f"PYTHON={sys.executable}", f"VENV={tmp_path / 'venv'}", *settings],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    ).stdout
    return [line for line in out.splitlines() if " install " in line and line.startswith(f"{into}/bin/pip")]


def test_make_run_installs_the_run_lock_then_the_project_without_extras(tmp_path):
    installs = _make("run", tmp_path)
    project = [line for line in installs if "-e" in line.split()]
    assert len(project) == 1 and project[0].split()[-1] == ".", installs
    assert "--no-deps" in project[0].split(), "the run lock brings the dependencies, pip resolves nothing more"
    assert any(line.endswith(f"-r locks/pylock.run-{TAG}.toml") for line in installs), installs
    assert not any("[" in line for line in installs), f"the run set-up installs extras: {installs}"


def test_make_test_adds_the_test_lock_of_the_extras_named_in_one_place(tmp_path):
    extras = re.search(r"^TEST_EXTRAS\s*:=\s*(\S+)\s*$", (ROOT / "Makefile").read_text(), re.M).group(1).split(",")
    assert "test" in extras and set(extras) <= set(PROJECT["optional-dependencies"])
    installs = _make("test", tmp_path)
    assert installs[: len(_make("run", tmp_path))] == _make("run", tmp_path), "the test set-up builds on the run one"
    assert installs[-1].endswith(f"-r locks/pylock.test-{TAG}.toml"), installs  # its extras: tests/test_lock.py


def test_make_test_sets_up_another_python_in_a_venv_of_its_own(tmp_path):
    """For the tests across Python versions, `make test` installs the run lock of the newest other supported
    Python the machine has (scripts/other-python.sh) into a venv named after it, never into the test venv."""
    this = f"{sys.version_info[0]}.{sys.version_info[1]}"
    other = subprocess.run(
        [str(ROOT / "scripts" / "other-python.sh"), this], capture_output=True, text=True, timeout=60, check=True
    ).stdout.strip()
    if not other:
        pytest.skip("this machine has no other supported Python")
    version = subprocess.run(
        [other, "-c", "import sys; print('%d%d' % sys.version_info[:2])"], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert version != this.replace(".", "") and (ROOT / "locks" / f"pylock.run-py{version}.toml").exists()
    installs = _make("test", tmp_path, venv=f".venv-py{version}")
    assert installs[-2].endswith(f"-r locks/pylock.run-py{version}.toml"), installs
    assert installs[-1].split()[-4:] == ["--no-deps", "--no-build-isolation", "-e", "."], installs
    assert _make("test", tmp_path, "OTHER_PYTHON=", venv=f".venv-py{version}") == []


def test_an_interpreter_without_a_lock_is_refused_with_the_supported_pythons(tmp_path):
    out = subprocess.run(
        ["make", "setup-run", "PYTHON=python2-no-such-interpreter", f"VENV={tmp_path / 'venv'}"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode != 0 and "python2-no-such-interpreter does not run here" in out.stderr, out.stderr
    assert not (tmp_path / "venv").exists()


def _names(requirements: list[str]) -> set[str]:
    return {canonicalize_name(Requirement(r).name) for r in requirements}


def _closure(names: set[str]) -> set[str]:
    """The distributions ``names`` need, with what they need, as installed (extras not asked for left out)."""
    seen: set[str] = set()
    todo = list(names)
    while todo:
        name = canonicalize_name(todo.pop())
        if name in seen:
            continue
        seen.add(name)
        try:
            requires = metadata.requires(name) or []
        except metadata.PackageNotFoundError:
            continue
        for text in requires:
            req = Requirement(text)
            if req.marker is None or req.marker.evaluate({"extra": ""}):
                todo.append(req.name)
    return seen


def test_the_code_imports_nothing_that_only_the_test_extras_bring():
    optional = PROJECT["optional-dependencies"]
    allowed = _closure(_names(PROJECT["dependencies"]))
    for extra, reqs in optional.items():
        if extra != "test":
            allowed |= _closure(_names(reqs))  # a feature's own extra (imported where that feature is used)
    test_only = _closure(_names(optional["test"])) - allowed
    assert {"playwright", "pytest"} <= test_only
    owners = metadata.packages_distributions()
    wrong = []
    for path in sorted((ROOT / "src" / "simatch").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                modules = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                modules = [node.module]
            else:
                continue
            for module in modules:
                dists = {canonicalize_name(d) for d in owners.get(module.split(".")[0], ())}
                if dists and dists <= test_only:
                    wrong.append(
                        f"{path.relative_to(ROOT)}:{node.lineno} imports {module} ({', '.join(sorted(dists))})"
                    )
    assert not wrong, "only the test extras install these:\n" + "\n".join(wrong)
