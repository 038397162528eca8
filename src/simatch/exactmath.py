"""CPython's own `math.hypot` and `math.remainder`, compiled with numba, equal bit for bit.

A run is deterministic and checked by its state digest, so a kernel compiled for speed must compute exactly
what the Python code it replaces computed. For most of `math` that holds by itself: CPython's `sqrt`,
`sin`, `cos`, `atan2`, `asin`, `tan` are the C library's (IEEE `sqrt` is exact; the others are the same
libm calls numba makes). Two are not:

* ``math.hypot``: CPython 3.11 computes it itself, correctly rounded in practice (an extended-precision sum
  of squares with Veltkamp splitting and one Newton correction of the square root); numba's calls the C
  library's ``hypot``, which differs in the last bit for about 6 results in 1000. `hypot` here is
  CPython 3.11's algorithm (``vector_norm`` for two coordinates, Objects/mathmodule.c), step for step.
* ``math.remainder``: numba has none; `remainder` here is CPython's ``m_remainder`` (exact: it uses only
  ``fmod``, which is exact in IEEE arithmetic).

Both are checked against `math` on millions of inputs and the special values in tests/test_exactmath.py.
Only CPython 3.11's ``hypot`` is reproduced: 3.12 changed its algorithm (``dl_mul``/``DoubleLength``),
which differs in about 11 results in a million. `SAME_AS_CPYTHON` says whether this interpreter's is the
one reproduced (the test suite checks it, so a move to another Python version cannot pass unnoticed).

Plain Python may call these too (they then run as numba dispatches: about 0.3 us, slower than ``math``);
they are meant to be called from other kernels.
"""

from __future__ import annotations

import math
import sys

import numba
import numpy as np

#: Veltkamp's splitting constant for doubles (2**27 + 1): x * T27 splits x into two 26-bit halves
_T27 = 134217729.0
#: the smallest normal double: CPython scales subnormal inputs up by it before splitting them
_MIN_NORMAL = 2.2250738585072014e-308

#: whether `hypot` reproduces this interpreter's math.hypot (CPython 3.11's algorithm)
SAME_AS_CPYTHON = sys.implementation.name == "cpython" and sys.version_info[:2] == (3, 11)


@numba.njit(cache=True)
def hypot(x: float, y: float) -> float:
    """``math.hypot(x, y)`` of CPython 3.11, bit for bit."""
    a = abs(x)
    b = abs(y)
    # special values first, as vector_norm: an infinity wins over a NaN
    if math.isinf(a) or math.isinf(b):
        return math.inf
    if math.isnan(a) or math.isnan(b):
        return math.nan
    mx = a if a > b else b
    if mx == 0.0:
        return mx
    _, e = math.frexp(mx)
    factor = 1.0
    if e < -1023:
        # subnormal largest coordinate: scale into the normal range first, undo at the end
        a = a / _MIN_NORMAL
        b = b / _MIN_NORMAL
        mx = mx / _MIN_NORMAL
        factor = _MIN_NORMAL
        _, e = math.frexp(mx)
    scale = math.ldexp(1.0, -e)
    # sum of squares in extended precision: each square is split into hi*hi + 2*hi*lo + lo*lo, the rounding
    # errors of the running sum kept in frac1 (hi*hi), frac2 (2*hi*lo) and frac3 (lo*lo); the sum starts at
    # 1.0 so that every addend is below its ulp's exponent (the coordinates are scaled below 1)
    csum = 1.0
    frac1 = 0.0
    frac2 = 0.0
    frac3 = 0.0
    for v in (a, b):
        x = v * scale
        t = x * _T27
        hi = t - (t - x)
        lo = x - hi
        x = hi * hi
        old = csum
        csum += x
        frac1 += (old - csum) + x
        x = 2.0 * hi * lo
        old = csum
        csum += x
        frac2 += (old - csum) + x
        frac3 += lo * lo
    h = math.sqrt(csum - 1.0 + (frac1 + frac2 + frac3))
    # one step of Newton's method on the square root, with the residual computed in the same way
    x = h
    t = x * _T27
    hi = t - (t - x)
    lo = x - hi
    x = -hi * hi
    old = csum
    csum += x
    frac1 += (old - csum) + x
    x = -2.0 * hi * lo
    old = csum
    csum += x
    frac2 += (old - csum) + x
    x = -lo * lo
    old = csum
    csum += x
    frac3 += (old - csum) + x
    x = csum - 1.0 + (frac1 + frac2 + frac3)
    h = h + x / (2.0 * h)
    if factor != 1.0:
        return factor * (h / scale)
    return h / scale


@numba.njit(cache=True)
def remainder(x: float, y: float) -> float:
    """``math.remainder(x, y)`` of CPython (IEEE 754 remainder: x - n y, n the nearest integer to x / y, ties
    to even), bit for bit; NaN where CPython raises ValueError (y == 0, or x infinite)."""
    if math.isfinite(x) and math.isfinite(y):
        if y == 0.0:
            return math.nan
        absx = abs(x)
        absy = abs(y)
        m = np.fmod(absx, absy)
        # compare m with absy - m rather than with 0.5 * absy (which may be inexact for tiny absy)
        c = absy - m
        if m < c:
            r = m
        elif m > c:
            r = -c
        else:
            # exactly half way: to the even multiple
            r = m - 2.0 * np.fmod(0.5 * (absx - m), absy)
        return math.copysign(1.0, x) * r
    if math.isnan(x):
        return x
    if math.isnan(y):
        return y
    if math.isinf(x):
        return math.nan
    return x


TWO_PI = 2.0 * math.pi


@numba.njit(cache=True)
def wrap(a: float) -> float:
    """An angle in [-pi, pi]: ``math.remainder(a, 2 pi)`` of CPython, bit for bit."""
    return remainder(a, TWO_PI)


@numba.njit(cache=True)
def pymin(a: float, b: float) -> float:
    """Python's ``min(a, b)`` in a kernel: the first of equals (``min(0.0, -0.0)`` is 0.0)."""
    return b if b < a else a


@numba.njit(cache=True)
def pymax(a: float, b: float) -> float:
    """Python's ``max(a, b)`` in a kernel: the first of equals."""
    return b if b > a else a
