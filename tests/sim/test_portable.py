"""A match's numbers do not depend on the CPU's vector extensions (docs/reliability.md, "Across machines").

What the world computes goes through numba's kernels (no fast-math, no contraction: the same instructions'
results on every x86-64), MuJoCo (built for AVX, with no dispatch by CPU) and the C library's math. What
would make it depend on the CPU is kept out of the world's Python: LAPACK and BLAS (OpenBLAS picks its
kernels by CPU), and the NumPy functions that NumPy dispatches to CPU-specific code of other accuracy
(``sin``, ``arctan2``, ``power``...: X86_V3 and AVX-512 variants beside the baseline one). Constant matrices
are computed exactly (`simatch.robots.exact`).
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from simatch.robots import exact

SRC = Path(__file__).resolve().parents[2] / "src" / "simatch"
#: the modules that compute the world (the re-simulation of a recording runs these alone)
WORLD = [
    *sorted((SRC / "sim").glob("*.py")),
    *sorted((SRC / "robots").glob("*.py")),
    *sorted((SRC / "worlds").glob("*.py")),
    SRC / "field.py",
]
#: the modules that decide what enters it in a match (the teams, the referee and the judges, the coaches)
DECIDERS = [*sorted((SRC / "strategy").rglob("*.py")), *sorted((SRC / "scene").rglob("*.py"))]


def _dispatched_math() -> set[str]:
    """NumPy's floating-point functions with a CPU-specific variant for float64 beside the baseline one (as the
    NumPy installed here was built), less the exactly rounded IEEE operations whose result cannot differ."""
    from numpy._core import _multiarray_umath as umath

    exact_ops = set(
        "add subtract multiply divide negative absolute sqrt square maximum minimum fmax fmin floor ceil rint"
        " trunc frexp ldexp reciprocal equal not_equal less less_equal greater greater_equal sign signbit"
        " argmax argmin".split()
    )
    found = set()
    for name, loops in umath.__cpu_targets_info__.items():
        for types, where in loops.items():
            if "d" in types and where["available"].split() != [where["current"]] and name not in exact_ops:
                found.add(name)
    return found


def test_the_exact_inverse_is_the_rounded_rational_one():
    a = np.array([[1.0, 1.0, 1.0, 1.0], [0.1, 0.1, -0.1, -0.1], [-0.1, 0.1, 0.1, -0.1], [-0.01, 0.01, -0.01, 0.01]])
    inv = exact.inverse(a)
    rational = [[Fraction(float(v)) for v in row] for row in a]
    product = [[sum(rational[i][k] * Fraction(float(inv[k][j])) for k in range(4)) for j in range(4)] for i in range(4)]
    for i in range(4):
        for j in range(4):
            assert abs(float(product[i][j]) - (i == j)) < 1e-14
    assert np.allclose(inv, np.linalg.inv(a), rtol=1e-13, atol=1e-13)
    # the X configuration's mixer: its first column is exactly a quarter (LAPACK's here is 0.24999999999999997)
    assert (inv[:, 0] == 0.25).all()


def test_the_exact_pseudo_inverse_of_a_drive():
    angles = np.radians([45.0, 135.0, 225.0, 315.0])
    m = np.stack([-np.sin(angles), np.cos(angles), np.full(4, 0.2)], axis=1)  # 4 wheels x (vx, vy, w)
    p = exact.pseudo_inverse(m)
    assert p.shape == (3, 4)
    assert np.allclose(p @ m, np.eye(3), atol=1e-14)
    assert np.allclose(p, np.linalg.pinv(m), atol=1e-14)
    assert np.allclose(exact.pseudo_inverse(m.T), np.linalg.pinv(m.T), atol=1e-14)  # wide as well as tall


@pytest.mark.parametrize(
    "bad, message",
    [
        (np.zeros((2, 2)), "singular"),
        (np.array([[1.0, np.nan], [0.0, 1.0]]), "NaN"),
        (np.ones((2, 3)), "square"),
        (np.ones(3), "matrix"),
    ],
)
def test_bad_matrices_are_refused(bad, message):
    with pytest.raises(ValueError, match=message):
        exact.inverse(bad)


def test_a_drive_without_full_rank_is_refused():
    with pytest.raises(ValueError, match="singular"):
        exact.pseudo_inverse(np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]))


def test_the_world_constants_do_not_follow_openblas_kernels():
    """The drives' pseudo-inverses and the mixers come out the same under another OpenBLAS kernel set."""
    probe = (
        "import hashlib, simatch\n"
        "with simatch.Simulation('aerial_encirclement', seed=0) as sim:\n"
        "    s = sim.simulator\n"
        "    print(hashlib.sha256(s.drive.Mpinv.tobytes() + s.aerial.mix.tobytes()).hexdigest())\n"
    )

    def run(coretype: str | None) -> str:
        env = dict(os.environ)
        env.pop("OPENBLAS_CORETYPE", None)
        if coretype:
            env["OPENBLAS_CORETYPE"] = coretype
        out = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, timeout=300)
        assert out.returncode == 0, out.stderr
        return out.stdout.strip()

    assert run(None) == run("Prescott")


def _numpy_calls(tree: ast.AST, names: set[str]) -> list[str]:
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef) and any(
            (isinstance(d, ast.Call) and getattr(d.func, "id", "") == "kernel") or getattr(d, "id", "") == "kernel"
            for d in node.decorator_list
        ):
            node.body = []  # numba compiles a kernel's NumPy calls to the C library's functions
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "np":
            if node.attr in names or node.attr in ("dot", "matmul", "linalg", "vdot", "inner", "tensordot"):
                found.append(f"np.{node.attr} (line {node.lineno})")
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.MatMult):
            found.append(f"@ (line {node.lineno})")
    return found


@pytest.mark.parametrize("part, paths", [("world", WORLD), ("deciders", DECIDERS)])
def test_nothing_depends_on_the_cpu(part, paths):
    names = _dispatched_math()
    assert {"sin", "cos", "arctan2"} <= names, f"NumPy's dispatch table is not what this test reads: {names}"
    offending = {}
    for path in paths:
        calls = _numpy_calls(ast.parse(path.read_text()), names)
        if calls:
            offending[str(path.relative_to(SRC))] = calls
    assert not offending, f"CPU-dependent NumPy in the Python of the {part} (use math or a kernel): {offending}"
