"""Writes the lock files of one Python: exact versions and hashes of what `make run` and `make test` install.

    python scripts/lock.py --python python3.12              # locks/pylock.run-py312.toml and pylock.test-py312.toml
    python scripts/lock.py --python python3.11 --extras test,learn,ros2

`make lock` runs it for every supported Python (docs/install.md). Each lock is a PEP 751 ``pylock.toml`` written by
``pip lock`` in a scratch venv of that Python, so the pip that installs it (``pip install -r``) resolved it:

* ``pylock.run-pyXY.toml``: the project's dependencies and its build requirements (setuptools and wheel: the
  project is installed without build isolation, so the C extensions are built by the locked setuptools);
* ``pylock.test-pyXY.toml``: the same, plus the extras ``make test`` adds, resolved with the run lock's versions as
  constraints, so the test set-up never changes a version that the run set-up installed.

Packages come from PyPI, with its URLs in the lock, whatever mirrors pip's configuration names (a lock written on
one machine installs on another). torch is the exception: PyPI's Linux wheel is the CUDA build, so torch's CPU
wheel comes from a local folder (``--torch-wheels``, where the project's machines keep it). A Python for which that
folder has no torch wheel gets no torch and none of the packages that need it; the lock's ``[tool.simatch]`` table
names them with the reason, and the tests that need them skip with that reason (tests/conftest.py).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LOCKS = ROOT / "locks"
PIP = "pip==26.3"  # the pip that writes the locks; the Makefile installs the same one (PIP there)
NEEDS_TORCH = ("torch", "stable-baselines3")  # left out together where torch's CPU wheel is missing


def _name(requirement: str) -> str:
    """The distribution's name of a requirement string, normalised (PEP 503)."""
    end = len(requirement)
    for stop in "<>=!~;[ @":
        at = requirement.find(stop)
        if at != -1:
            end = min(end, at)
    return requirement[:end].strip().lower().replace("_", "-").replace(".", "-")


def _requirements(extras: list[str]) -> tuple[list[str], list[str]]:
    """The run set (build requirements and dependencies) and what the extras add, from pyproject.toml."""
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    optional = pyproject["project"]["optional-dependencies"]
    unknown = sorted(set(extras) - set(optional))
    if unknown:
        raise SystemExit(f"lock: no such extra in pyproject.toml: {', '.join(unknown)}")
    run = [*pyproject["build-system"]["requires"], *pyproject["project"]["dependencies"]]
    added = [r for extra in extras for r in optional[extra]]
    return run, added


def _torch_wheel(folder: Path, tag: str) -> Path | None:
    """torch's CPU wheel for this CPython tag (``cp312``) in the local folder, if there is one."""
    found = sorted(folder.glob(f"torch-*+cpu-{tag}-{tag}-*.whl")) if folder.is_dir() else []
    return found[-1] if found else None


def _pip_env(torch_wheels: Path) -> dict[str, str]:
    """pip's environment for locking: PyPI alone (no configured mirrors or constraints), plus the torch folder."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("PIP_")}
    env.update(PIP_CONFIG_FILE=os.devnull, PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_FIND_LINKS=str(torch_wheels))
    return env


def _lock(python: Path, env: dict, requirements: list[str], out: Path, constraints: Path | None) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        reqs = Path(tmp) / "requirements.txt"
        reqs.write_text("\n".join(requirements) + "\n", encoding="utf-8")
        cmd = [str(python), "-m", "pip", "lock", "--quiet", "-r", str(reqs), "-o", str(out)]
        if constraints is not None:
            cmd += ["-c", str(constraints)]
        subprocess.run(cmd, env=env, check=True)


def _pins(lock: Path) -> str:
    """A lock's versions as pip constraints (``name==version`` lines)."""
    packages = tomllib.loads(lock.read_text(encoding="utf-8"))["packages"]
    return "".join(f"{p['name']}=={p['version']}\n" for p in packages)


def _note(out: Path, left_out: list[str], reason: str) -> None:
    """Records in the lock's [tool.simatch] table what it leaves out and why (PEP 751 keeps [tool] for tools)."""
    names = ", ".join(f'"{n}"' for n in left_out)
    text = out.read_text(encoding="utf-8").rstrip("\n")
    out.write_text(f'{text}\n\n[tool.simatch]\nleft-out = [{names}]\nreason = "{reason}"\n', encoding="utf-8")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--python", required=True, help="the interpreter to lock for (python3.12, a path)")
    p.add_argument("--extras", default="test,learn,ros2", help="the extras make test installs (comma-separated)")
    p.add_argument("--torch-wheels", type=Path, default=Path("/opt/wheels"), help="where torch's CPU wheels lie")
    args = p.parse_args(argv)
    run, added = _requirements([e for e in args.extras.split(",") if e])
    with tempfile.TemporaryDirectory(prefix="simatch-lock-") as tmp:
        venv = Path(tmp) / "venv"
        subprocess.run([args.python, "-m", "venv", str(venv)], check=True)
        python = venv / "bin" / "python"
        env = _pip_env(args.torch_wheels)
        subprocess.run([str(python), "-m", "pip", "install", "--quiet", PIP], env=env, check=True)
        tag = subprocess.run(
            [str(python), "-c", "import sys; print('cp%d%d' % sys.version_info[:2])"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        wheel = _torch_wheel(args.torch_wheels, tag)
        left_out: list[str] = []
        if wheel is None:
            left_out = [n for n in NEEDS_TORCH if n in {_name(r) for r in added}]
        LOCKS.mkdir(exist_ok=True)
        run_lock = LOCKS / f"pylock.run-py{tag[2:]}.toml"
        test_lock = LOCKS / f"pylock.test-py{tag[2:]}.toml"
        _lock(python, env, run, run_lock, None)
        pins = Path(tmp) / "run-pins.txt"
        # torch pinned to the local CPU wheel's version (the newest on PyPI would be the CUDA build)
        torch = f"torch=={wheel.name.split('-')[1]}\n" if wheel is not None else ""
        pins.write_text(_pins(run_lock) + torch, encoding="utf-8")
        test = run + [r for r in added if _name(r) not in left_out]
        _lock(python, env, test, test_lock, pins)
        if left_out:
            reason = (
                f"no torch CPU wheel for {tag} in {args.torch_wheels} (PyPI's Linux torch is the CUDA build, "
                "whose CUDA packages this machine's registries do not serve)"
            )
            _note(test_lock, left_out, reason)
    print(f"lock: wrote {run_lock.relative_to(ROOT)} and {test_lock.relative_to(ROOT)}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
