"""simatch.compiled: declared kernel signatures, checked when bound (the tests run with checking on)."""

from __future__ import annotations

import numpy as np
import pytest

from simatch import compiled
from simatch.compiled import Array, Bool, Float, Int, Vector, bind, kernel


@kernel
def _twice(x):
    return 2.0 * x


@kernel(values=Vector, scale=Float, count=Int, negate=Bool, out=Array(np.float64, 1))
def _scaled_sum(values, scale, count, negate, out):
    total = 0.0
    for i in range(count):
        total += values[i] * scale
    out[0] = -_twice(total) if negate else _twice(total)


def test_checking_is_on_in_the_tests():
    assert compiled.checking()


def test_bound_kernel_computes_what_the_kernel_does():
    out = np.zeros(1)
    bind(_scaled_sum)(np.arange(4.0), 0.5, 4, True, out)
    assert out[0] == -6.0
    _scaled_sum(np.arange(4.0), 0.5, 4, False, out)
    assert out[0] == 6.0


@pytest.mark.parametrize(
    "args,message",
    [
        ((np.arange(4), 0.5, 4, False, np.zeros(1)), "parameter 'values': expected dtype float64, got int64"),
        ((np.arange(8.0)[::2], 0.5, 4, False, np.zeros(1)), "parameter 'values': expected a C-contiguous"),
        ((np.zeros((2, 2)), 0.5, 4, False, np.zeros(1)), "parameter 'values': expected 1 dimension"),
        ((np.arange(4.0), "0.5", 4, False, np.zeros(1)), "parameter 'scale': expected a float"),
        ((np.arange(4.0), 0.5, 4.0, False, np.zeros(1)), "parameter 'count': expected an int"),
        ((np.arange(4.0), 0.5, 4, 1, np.zeros(1)), "parameter 'negate': expected a bool"),
        ((np.arange(4.0), 0.5, 4, False, np.zeros(1, np.float32)), "parameter 'out': expected dtype float64"),
    ],
)
def test_a_wrong_argument_is_an_error_naming_kernel_and_parameter(args, message):
    with pytest.raises(TypeError, match="kernel _scaled_sum, " + message.replace("(", r"\(")):
        bind(_scaled_sum)(*args)


def test_a_read_only_array_is_refused_where_the_kernel_may_write():
    frozen = np.zeros(1)
    frozen.flags.writeable = False
    with pytest.raises(TypeError, match="parameter 'out': expected a writable array"):
        bind(_scaled_sum)(np.arange(4.0), 0.5, 4, False, frozen)


def test_declarations_must_match_the_parameters():
    with pytest.raises(TypeError, match="parameters without a declared type: b"):

        @kernel(a=Vector)
        def _missing(a, b):
            return a

    with pytest.raises(TypeError, match="declared names that are not parameters: c"):

        @kernel(a=Vector, c=Float)
        def _unknown(a):
            return a


def test_a_kernel_without_declaration_cannot_be_bound():
    with pytest.raises(TypeError, match="no declared signature"):
        bind(_twice)


def test_without_checking_the_compiled_version_is_returned(monkeypatch):
    monkeypatch.setenv(compiled.CHECK_ENV, "0")
    fast = bind(_scaled_sum)
    assert not hasattr(fast, "kernel")
    out = np.zeros(1)
    fast(np.arange(4.0), 0.5, 4, False, out)
    assert out[0] == 6.0


def test_one_cache_stamp_covers_every_kernel_module():
    """Editing a kernel's file must invalidate the cached kernels of other files that call it: the stamp
    of simatch's own kernels covers all of its kernel modules."""
    import simatch.sim.kernels as k

    locator = compiled._InTreeLocator.from_function(k.__dict__["roll_held_ball"].py_func, k.__file__)
    assert locator is not None
    stamp = locator.get_source_stamp()
    assert isinstance(stamp, str) and len(stamp) == 64
    assert compiled._InTreeLocator.from_function(_twice.py_func, __file__) is None
