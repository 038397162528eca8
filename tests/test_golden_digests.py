"""Golden state digests: a few short embedded runs must end in exactly these states.

A change that moves any of them changes what simatch simulates; it must be deliberate, documented in
docs/reliability.md, and the table below updated in the same commit. The digests depend on the Python
minor version and on the CPU's vector extensions (MuJoCo, NumPy and the C library pick code paths by CPU), so
they are kept per (Python version, platform); on a combination not in the table the test is skipped and
prints the digests it found, to be added."""

from __future__ import annotations

import platform
import sys
from pathlib import Path

import pytest

import simatch

RUNS = [
    ("msl_5v5", 0, 20.0),
    ("msl_5v5", 3, 20.0),
    ("encirclement_9v7", 0, 10.0),
    ("aerial_encirclement", 0, 10.0),
    ("pursuit_evasion_3d", 3, 10.0),
]

#: (python "3.11", platform key) -> {(scene, seed, seconds): first 16 hex digits of the state digest}
GOLDEN = {
    ("3.11", "x86_64-avx2"): {
        ("msl_5v5", 0, 20.0): "79b220c3354139fd",
        ("msl_5v5", 3, 20.0): "448ec3b9da92cb37",
        ("encirclement_9v7", 0, 10.0): "f6bf42076e569cec",
        ("aerial_encirclement", 0, 10.0): "2aadc6e2b2d10a29",
        ("pursuit_evasion_3d", 3, 10.0): "c1394252d2c9b745",
    },
    # Python 3.12 changed math.hypot and float sum(): the teams' Python differs in the last bits (3.13 as 3.12)
    **{
        (minor, "x86_64-avx2"): {
            ("msl_5v5", 0, 20.0): "f953de7702002a72",
            ("msl_5v5", 3, 20.0): "796b48977b28aed6",
            ("encirclement_9v7", 0, 10.0): "f65f86cfdd8b9945",
            ("aerial_encirclement", 0, 10.0): "e69ef047c7f59882",
            ("pursuit_evasion_3d", 3, 10.0): "c1394252d2c9b745",
        }
        for minor in ("3.12", "3.13")
    },
}


def platform_key() -> str:
    """The machine and the widest vector extension its CPU offers (what the numeric libraries dispatch on)."""
    flags: set[str] = set()
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.exists():
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("flags"):
                flags = set(line.split(":", 1)[1].split())
                break
    level = "avx512" if "avx512f" in flags else "avx2" if "avx2" in flags else "base"
    return f"{platform.machine()}-{level}"


KEY = (f"{sys.version_info.major}.{sys.version_info.minor}", platform_key())


@pytest.mark.parametrize("scene,seed,seconds", RUNS, ids=[f"{s}-seed{n}-{int(t)}s" for s, n, t in RUNS])
def test_golden_digest(scene, seed, seconds):
    with simatch.Simulation(scene, seed=seed) as sim:
        sim.run(seconds)
        digest = sim.state_digest()[:16]
    golden = GOLDEN.get(KEY)
    if golden is None:
        pytest.skip(f"no golden digests for Python {KEY[0]} on {KEY[1]}: this run gave {digest}")
    assert digest == golden[(scene, seed, seconds)], (
        f"{scene} seed {seed} {seconds} s: state digest {digest}, golden {golden[(scene, seed, seconds)]} "
        f"(Python {KEY[0]}, {KEY[1]}); a deliberate change updates GOLDEN and docs/reliability.md"
    )
