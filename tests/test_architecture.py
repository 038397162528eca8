"""The architecture and the code style are checked, not only described.

The import contract in pyproject.toml ([tool.importlinter]) holds the layers of docs/architecture.md and
the independence of the paper's three subsystems; a change that crosses a boundary fails here with the
offending import named. ruff checks the whole tree (lint rules and formatting in pyproject.toml).

Sizes: no module in src/ over 600 lines (nor a C source or header of the extensions), no function (``def``
or ``async def``, methods and nested functions included) over 80 lines from its ``def`` to its last line. A
function that reads best whole may be longer if it says why at its top: its docstring, or a comment before its
first statement, holds the marker ``Long because:`` followed by the reason, e.g.::

    def parse(text):
        # Long because: one state machine over the grammar's states, each case a few lines.
"""

from __future__ import annotations

import ast
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

MAX_MODULE_LINES = 600
#: the C sources and headers of the extensions: one job each, as a module
MAX_C_FILE_LINES = 600
MAX_FUNCTION_LINES = 80
#: what a long function's docstring or first comment says, followed by the reason it reads best whole
LONG_BECAUSE = "Long because:"


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


def _functions(node: ast.AST, prefix: str = ""):
    """(qualified name, node) of every function under ``node``: ``Class.method``, ``outer.inner``."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield prefix + child.name, child
            yield from _functions(child, f"{prefix}{child.name}.")
        elif isinstance(child, ast.ClassDef):
            yield from _functions(child, f"{prefix}{child.name}.")
        else:
            yield from _functions(child, prefix)


def _says_why(fn: ast.FunctionDef | ast.AsyncFunctionDef, lines: list[str]) -> bool:
    """The function's docstring, or a comment before its first statement, gives the reason it is long."""
    doc = ast.get_docstring(fn, clean=False) or ""
    if LONG_BECAUSE in doc:
        return True
    body = fn.body[1:] if doc and len(fn.body) > 1 else fn.body
    head = lines[fn.lineno - 1 : body[0].lineno]
    return any(LONG_BECAUSE in line.partition("#")[2] for line in head)


def _too_long_functions(path: str, text: str) -> dict[str, int]:
    """``path::name`` -> lines, for the functions of one module over the limit that do not say why."""
    lines = text.splitlines()
    out = {}
    for name, fn in _functions(ast.parse(text)):
        length = fn.end_lineno - fn.lineno + 1
        if length > MAX_FUNCTION_LINES and not _says_why(fn, lines):
            out[f"{path}::{name}"] = length
    return out


def _sources():
    for file in sorted((ROOT / "src").rglob("*.py")):
        yield file.relative_to(ROOT).as_posix(), file.read_text()


def test_no_module_is_too_long():
    long = _too_long_files(_sources(), MAX_MODULE_LINES)
    assert not long, f"modules over {MAX_MODULE_LINES} lines (split them along their seams): {long}"


def _c_sources():
    for file in sorted((ROOT / "src").rglob("*.[ch]")):
        yield file.relative_to(ROOT).as_posix(), file.read_text()


def _too_long_files(sources, limit: int) -> dict[str, int]:
    return {path: n for path, text in sources if (n := len(text.splitlines())) > limit}


def test_no_c_file_is_too_long():
    long = _too_long_files(_c_sources(), MAX_C_FILE_LINES)
    assert not long, f"C files over {MAX_C_FILE_LINES} lines (split them into units with one job each): {long}"


def test_the_c_length_guard_bites():
    """A C file one line over the bound fails, one at the bound passes; the guard finds the tree's C files."""
    at_bound = "int x;\n" * MAX_C_FILE_LINES
    assert _too_long_files([("a.c", at_bound + "int y;\n"), ("b.h", at_bound)], MAX_C_FILE_LINES) == {
        "a.c": MAX_C_FILE_LINES + 1
    }
    assert any(path.endswith("_cdr_accel.c") for path, _ in _c_sources())


def test_no_function_is_too_long():
    long: dict[str, int] = {}
    for path, text in _sources():
        long.update(_too_long_functions(path, text))
    assert not long, (
        f"functions over {MAX_FUNCTION_LINES} lines (split them, or say at their top {LONG_BECAUSE!r} and why): {long}"
    )


def test_a_long_function_must_say_why():
    """The length guard bites: 81 lines fail; the same with the reason in its docstring or in a comment
    before its first statement pass; 80 lines pass."""
    body = "".join(f"    x{k} = {k}\n" for k in range(79))
    plain = f"def f():\n    pass\n{body}"
    assert _too_long_functions("m.py", plain) == {"m.py::f": 81}
    assert _too_long_functions("m.py", f"def f():\n{body}") == {}
    documented = f'def f():\n    """Long because: one table, row by row."""\n{body}'
    assert _too_long_functions("m.py", documented) == {}
    commented = f"class C:\n    def f(self):\n        # {LONG_BECAUSE} one table, row by row\n{body}".replace(
        "\n    x", "\n        x"
    )
    assert _too_long_functions("m.py", commented) == {}
    late = f"def f():\n    pass\n    # {LONG_BECAUSE} too late\n{body}"
    assert _too_long_functions("m.py", late) == {"m.py::f": 82}
