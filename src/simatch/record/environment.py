"""What made a run: the software and the machine a recording was made with, and how another differs.

A run is bit-exact for the same scene, seed and inputs on the same software and the same kind of machine;
MuJoCo, NumPy and the C library choose code paths by the CPU's vector extensions, and Python versions
differ in some of `math`'s results. So a recording keeps the description of its environment (metadata
``environment``, JSON), and `simatch replay --verify` names what differs when a re-simulation does not
reproduce it.
"""

from __future__ import annotations

import ctypes
import json
import platform
import subprocess
import sys
from functools import cache
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _dist_version
from pathlib import Path

#: the CPU flags that decide which code paths the numeric libraries take
VECTOR_FLAGS = ("sse4_2", "avx", "avx2", "fma", "avx512f", "avx512dq", "avx512bw", "avx512vl", "avx512_vnni")
#: the packages whose versions can change a run's results
PACKAGES = ("simatch", "mujoco-core", "numpy", "numba", "llvmlite")
#: the order in which differences are named: what changes results first
ORDER = ("cpu_flags", "python", "mujoco-core", "numpy", "openblas", "numba", "llvmlite", "libc", "machine", "cpu")
ORDER += ("simatch", "commit")


def _package(name: str) -> str:
    try:
        return _dist_version(name)
    except PackageNotFoundError:
        if name == "mujoco-core":  # (the engine's own wheel where it is installed as plain mujoco)
            return _package("mujoco")
        return "not installed"


def _openblas() -> str:
    """NumPy's OpenBLAS: its version and the CPU kernels it chose here (its ``DYNAMIC_ARCH`` build picks them
    by the CPU: ``Haswell``, ``SkylakeX``, ...), which decide the last bits of NumPy's linear algebra."""
    try:
        import numpy

        blas = numpy.__config__.CONFIG["Build Dependencies"]["blas"]
        version = str(blas.get("version", "unknown"))
        if "openblas" not in str(blas.get("name", "")):
            return f"{blas.get('name', 'unknown')} {version}"
        libs = sorted(Path(numpy.__file__).parent.parent.glob("numpy.libs/lib*openblas*.so*"))
        core = ""
        if libs:
            lib = ctypes.CDLL(str(libs[0]))
            for name in ("scipy_openblas_get_corename64_", "scipy_openblas_get_corename", "openblas_get_corename"):
                get = getattr(lib, name, None)
                if get is not None:
                    get.restype = ctypes.c_char_p
                    core = (get() or b"").decode()
                    break
        return f"{version} ({core})" if core else version
    except Exception:  # (a NumPy without that configuration, a library that does not load: not known)
        return "unknown"


def _commit() -> str:
    """The git commit of the source tree simatch runs from ("unknown" outside a git checkout)."""
    root = Path(__file__).resolve().parents[3]
    if not (root / ".git").exists():
        return "unknown"
    try:
        out = subprocess.run(
            ["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=5, check=False
        )
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return out.stdout.strip() or "unknown"


def _cpu() -> tuple[str, str]:
    """The CPU's model name and its vector flags (Linux's /proc/cpuinfo; elsewhere the platform's word)."""
    model, flags = "", set()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            if key.strip() == "model name" and not model:
                model = value.strip()
            elif key.strip() == "flags" and not flags:
                flags = set(value.split())
    except OSError:
        pass
    model = model or platform.processor() or platform.machine()
    return model, " ".join(f for f in VECTOR_FLAGS if f in flags)


@cache
def describe() -> dict[str, str]:
    """This process's environment, as a recording keeps it."""
    model, flags = _cpu()
    libc = " ".join(platform.libc_ver()).strip()
    return {
        "python": f"{platform.python_implementation()} {platform.python_version()}",
        "commit": _commit(),
        **{name: _package(name) for name in PACKAGES},
        "openblas": _openblas(),
        "machine": platform.machine(),
        "cpu": model,
        "cpu_flags": flags,
        "os": platform.platform(),
        "libc": libc or "unknown",
    }


def recorded(metadata: dict[str, str]) -> dict[str, str] | None:
    """The environment a recording's metadata describes (None for a recording made before it was kept)."""
    text = metadata.get("environment")
    if not text:
        return None
    try:
        env = json.loads(text)
    except ValueError:
        return None
    return {str(k): str(v) for k, v in env.items()} if isinstance(env, dict) else None


def differences(then: dict[str, str], now: dict[str, str] | None = None) -> list[str]:
    """What differs between the environment ``then`` and ``now`` (this process's by default), one short
    phrase each, the ones that change results first (CPU flags, Python, the numeric packages)."""
    now = describe() if now is None else now
    out = []
    for key in ORDER:
        a, b = then.get(key), now.get(key)
        if a is None or a == b:
            continue
        if key == "cpu_flags":
            gone = sorted(set(a.split()) - set(b.split()))
            new = sorted(set(b.split()) - set(a.split()))
            parts = ([f"{' '.join(gone)} there, not here"] if gone else []) + (
                [f"{' '.join(new)} here, not there"] if new else []
            )
            out.append(f"CPU vector extensions ({'; '.join(parts)})")
        else:
            out.append(f"{key} {a} there, {b} here")
    return out


def main() -> None:  # pragma: no cover - a convenience: python -m simatch.record.environment
    json.dump(describe(), sys.stdout, indent=2)
    print()


if __name__ == "__main__":  # pragma: no cover
    main()
