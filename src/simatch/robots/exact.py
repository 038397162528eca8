"""The robots' constant matrices, computed exactly: the same floats on every machine.

A drive's pseudo-inverse (wheel speeds to body velocity) and a quadrotor's mixer (collective thrust and
torques to rotor thrusts) are computed once, when a world is built, and then enter every physics step.
NumPy computes such inverses through LAPACK, and the LAPACK NumPy ships (OpenBLAS) chooses its kernels by
the CPU it runs on: an AVX-512 machine rounds the last bits differently from an AVX2 one, and every match
drifts apart from the first step (docs/reliability.md, "Across machines"). Here the matrix is inverted in
rational arithmetic from its exact float entries and each entry rounded once to the nearest float, so the
result depends on the matrix alone. The matrices are at most a few rows by a few columns; the cost is a
fraction of a millisecond per robot model.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np


def inverse(a) -> np.ndarray:
    """The inverse of the square matrix ``a``, each entry the float nearest to the exact inverse's.

    Raises ValueError if ``a`` is singular."""
    return _rounded(_inverse(_rational(a)))


def pseudo_inverse(a) -> np.ndarray:
    """The Moore-Penrose pseudo-inverse of ``a`` (rows x cols) of full rank, each entry the float nearest to
    the exact one: ``A^T (A A^T)^-1`` when there are no more rows than columns, ``(A^T A)^-1 A^T`` otherwise.

    Raises ValueError if ``a`` is not of full rank (a drive whose wheels cannot move the body in every
    direction)."""
    m = _rational(a)
    t = _transpose(m)
    if len(m) <= len(m[0]):
        return _rounded(_product(t, _inverse(_product(m, t))))
    return _rounded(_product(_inverse(_product(t, m)), t))


def _rational(a) -> list[list[Fraction]]:
    rows = np.asarray(a, dtype=float)
    if rows.ndim != 2 or not rows.size:
        raise ValueError(f"a matrix is needed, not shape {rows.shape}")
    if not np.isfinite(rows).all():
        raise ValueError("the matrix has a NaN or an infinite entry")
    return [[Fraction(float(v)) for v in row] for row in rows]


def _rounded(m: list[list[Fraction]]) -> np.ndarray:
    # float(Fraction) divides two integers, which Python rounds correctly
    return np.array([[float(v) for v in row] for row in m], dtype=float)


def _transpose(m):
    return [list(col) for col in zip(*m)]


def _product(a, b):
    cols = _transpose(b)
    return [[sum((x * y for x, y in zip(row, col)), Fraction(0)) for col in cols] for row in a]


def _inverse(m):
    """Gauss-Jordan elimination in exact arithmetic (any non-zero pivot is as good as another)."""
    n = len(m)
    if any(len(row) != n for row in m):
        raise ValueError(f"a square matrix is needed, not {n} x {len(m[0])}")
    a = [row[:] + [Fraction(int(i == j)) for j in range(n)] for i, row in enumerate(m)]
    for col in range(n):
        pivot = next((r for r in range(col, n) if a[r][col] != 0), None)
        if pivot is None:
            raise ValueError("the matrix is singular")
        a[col], a[pivot] = a[pivot], a[col]
        p = a[col][col]
        a[col] = [v / p for v in a[col]]
        for r in range(n):
            if r != col and a[r][col] != 0:
                f = a[r][col]
                a[r] = [x - f * y for x, y in zip(a[r], a[col])]
    return [row[n:] for row in a]
