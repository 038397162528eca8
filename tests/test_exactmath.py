"""simatch.exactmath: the compiled hypot and remainder equal CPython's math ones bit for bit."""

from __future__ import annotations

import math
import sys

import numba
import numpy as np
import pytest

from simatch import exactmath
from simatch.exactmath import SAME_AS_CPYTHON, hypot, remainder, wrap


@numba.njit(cache=False)
def _hypots(xs, ys, out):
    for i in range(xs.size):
        out[i] = hypot(xs[i], ys[i])


@numba.njit(cache=False)
def _remainders(xs, ys, out):
    for i in range(xs.size):
        out[i] = remainder(xs[i], ys[i])


@numba.njit(cache=False)
def _libm_hypots(xs, ys, out):
    for i in range(xs.size):
        out[i] = math.hypot(xs[i], ys[i])


def _bits(values) -> np.ndarray:
    return np.asarray(values, dtype=np.float64).view(np.int64)


def _inputs(n: int = 200_000) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """Distributions where a hypot's last bit is hard: the field's scale, exponents over 16 decades, nearly
    equal coordinates, and the decimal grids perception and strategies produce."""
    rng = np.random.default_rng(1)
    field = rng.uniform(-20.0, 20.0, (2, n))
    wide = rng.normal(0.0, 1.0, (2, n)) * 10.0 ** rng.integers(-8, 8, (2, n))
    x = rng.uniform(-1.0, 1.0, n)
    near = np.stack((x, x * rng.uniform(0.9999, 1.0001, n)))
    grid = np.stack((rng.integers(-1000, 1000, n) * 0.001, rng.integers(-1000, 1000, n) * 0.005))
    f32 = rng.uniform(-12.0, 12.0, (2, n)).astype(np.float32).astype(np.float64)
    return [("field", *field), ("wide", *wide), ("near", *near), ("grid", *grid), ("float32", *f32)]


SPECIAL = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    3.0,
    4.0,
    5e-324,
    -5e-324,
    2.2250738585072014e-308,
    1e-310,
    1e308,
    -1e308,
    1.7976931348623157e308,
    math.pi,
    2 * math.pi,
    -math.pi,
    math.inf,
    -math.inf,
    math.nan,
]


def test_this_python_is_the_one_reproduced():
    # a move to another Python changes math.hypot (3.12 has another algorithm): this names it
    assert SAME_AS_CPYTHON, f"exactmath.hypot reproduces CPython 3.11's math.hypot, this is {sys.version}"


@pytest.mark.parametrize("name,xs,ys", _inputs(), ids=lambda v: v if isinstance(v, str) else "")
def test_hypot_equals_math_hypot(name, xs, ys):
    out = np.empty_like(xs)
    _hypots(xs, ys, out)
    want = [math.hypot(a, b) for a, b in zip(xs.tolist(), ys.tolist())]
    differ = np.flatnonzero(_bits(out) != _bits(want))
    assert differ.size == 0, f"{differ.size} of {xs.size} differ, e.g. hypot({xs[differ[0]]!r}, {ys[differ[0]]!r})"


def test_the_c_library_hypot_would_differ():
    # what the module is for: numba's own math.hypot (the C library's) is not CPython's
    _, xs, ys = _inputs(200_000)[3]
    out = np.empty_like(xs)
    _libm_hypots(xs, ys, out)
    want = [math.hypot(a, b) for a, b in zip(xs.tolist(), ys.tolist())]
    assert np.count_nonzero(_bits(out) != _bits(want)) > 0


def test_hypot_special_values():
    for a in SPECIAL:
        for b in SPECIAL:
            got, want = hypot(a, b), math.hypot(a, b)
            assert _bits(got) == _bits(want) or (math.isnan(got) and math.isnan(want)), (a, b, got, want)
    assert hypot(math.inf, math.nan) == math.inf and hypot(math.nan, -math.inf) == math.inf
    assert math.isnan(hypot(math.nan, 1.0))


@pytest.mark.parametrize("name,xs,ys", _inputs(100_000), ids=lambda v: v if isinstance(v, str) else "")
def test_remainder_equals_math_remainder(name, xs, ys):
    # angles of every size against 2 pi (how strategies wrap them), and against the other coordinates
    for divisors in (np.full_like(ys, 2.0 * math.pi), np.where(ys == 0.0, 1.0, ys)):
        out = np.empty_like(xs)
        _remainders(xs * 3.0, divisors, out)
        want = [math.remainder(a, b) for a, b in zip((xs * 3.0).tolist(), divisors.tolist())]
        assert np.array_equal(_bits(out), _bits(want))


def test_remainder_ties_go_to_the_even_multiple():
    for x, y in [(5.0, 2.0), (7.0, 2.0), (-5.0, 2.0), (3.0 * math.pi, 2.0 * math.pi), (0.5, 1.0), (1.5, 1.0)]:
        assert _bits(remainder(x, y)) == _bits(math.remainder(x, y)), (x, y)


def test_remainder_special_values():
    for a in SPECIAL:
        for b in SPECIAL:
            try:
                want = math.remainder(a, b)
            except ValueError:  # CPython raises where IEEE says NaN (y == 0, x infinite)
                assert math.isnan(remainder(a, b)), (a, b)
                continue
            got = remainder(a, b)
            assert _bits(got) == _bits(want) or (math.isnan(got) and math.isnan(want)), (a, b, got, want)


def test_wrap_is_remainder_by_two_pi():
    rng = np.random.default_rng(3)
    for a in rng.uniform(-50.0, 50.0, 10_000).tolist() + [math.pi, -math.pi, 3 * math.pi, 0.0, -0.0]:
        assert _bits(wrap(a)) == _bits(math.remainder(a, exactmath.TWO_PI))
