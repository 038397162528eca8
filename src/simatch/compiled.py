"""Compiled (numba) kernels with declared signatures: how every subsystem writes and calls its hot code.

A kernel is a plain Python function, compiled by numba, whose parameters are declared by name and type::

    from simatch.compiled import Float, Vector, Matrix, kernel

    @kernel(q=Vector, bq=Vector, radius=Float, out=Matrix)
    def roll_held_ball(q, bq, radius, out): ...

It runs wherever it is called: from Python through numba's dispatcher (which types every argument at every
call), from other kernels, or, for the call sites that run every control tick or every physics step,
through :func:`bind`, which returns the version compiled for the declared signature and skips the
dispatcher. That compiled version takes its arguments as they are: an ``int64`` array where ``float64`` is
declared, or a strided view where a C-contiguous one is, would be read as wrong memory. So a bound kernel
checks every argument against its declaration when checking is on (``SIMATCH_CHECK_KERNELS=1``: the tests
and debug runs) and raises a :class:`TypeError` that names the kernel and the parameter. Off (the default),
the call costs what the compiled function costs.

Helpers that only kernels call need no declaration: ``@kernel`` alone compiles them where they are used.

Why declarations and not sample arguments: the signature is then part of the kernel's source, read next to
its parameters, checked against them when the module is imported (a declared name that is not a parameter,
or a parameter without a type, is an error), and the same declaration drives the argument checks.

numba's on-disk cache keys a compiled kernel by its own file only; a kernel that calls a kernel of another
file would keep a stale compiled version after that other file changed. simatch's kernels are therefore
cached under a stamp of all of simatch's kernel modules together (:class:`_PackageStamp`).

Shared by the simulator (``simatch.sim``) and the strategies (``simatch.strategy``), which may not import
each other."""

from __future__ import annotations

import hashlib
import inspect
import os
from pathlib import Path

import numba
import numpy as np
from numba.core import caching, types

#: a double (Python float); ints are accepted where a float is declared, as Python's arithmetic does
Float = types.float64
#: a signed 64-bit integer (Python int)
Int = types.int64
#: a truth value (Python bool)
Bool = types.boolean


def Array(dtype=np.float64, ndim: int = 1, *, readonly: bool = False) -> types.Array:
    """A C-contiguous NumPy array of ``dtype`` and ``ndim`` dimensions; a record dtype gives named fields.
    ``readonly=True`` accepts read-only arrays (a kernel that writes to it does not compile); otherwise the
    array must be writable."""
    return types.Array(numba.from_dtype(np.dtype(dtype)), ndim, "C", readonly=readonly)


#: the shapes most kernels take: float64 vectors and matrices, C-contiguous, writable
Vector = Array(np.float64, 1)
Matrix = Array(np.float64, 2)

CHECK_ENV = "SIMATCH_CHECK_KERNELS"


def checking() -> bool:
    """Whether bound kernels check their arguments (``SIMATCH_CHECK_KERNELS`` set to anything but 0/empty)."""
    return os.environ.get(CHECK_ENV, "") not in ("", "0")


def kernel(function=None, /, **declared):
    """Compile ``function`` with numba (cached on disk) and declare its parameters' types by name.

    ``@kernel`` alone: a helper called from other kernels (types inferred where it is called).
    ``@kernel(name=type, ...)``: every parameter declared (see :data:`Float`, :data:`Int`, :data:`Bool`,
    :func:`Array` or any numba type); :func:`bind` gives the compiled version for that signature."""

    def compile_(py_func):
        params = list(inspect.signature(py_func).parameters)
        if declared:
            missing = [p for p in params if p not in declared]
            unknown = [d for d in declared if d not in params]
            if missing or unknown:
                raise TypeError(
                    f"kernel {py_func.__qualname__}: "
                    + "; ".join(
                        part
                        for part in (
                            f"parameters without a declared type: {', '.join(missing)}" if missing else "",
                            f"declared names that are not parameters: {', '.join(unknown)}" if unknown else "",
                        )
                        if part
                    )
                )
        compiled = numba.njit(cache=True)(py_func)
        target = compiled if hasattr(compiled, "py_func") else py_func
        try:
            target.declared = tuple((p, declared[p]) for p in params) if declared else ()
        except AttributeError:  # pragma: no cover - a builtin cannot carry attributes
            pass
        return compiled

    if function is not None:
        return compile_(function)
    return compile_


def signature(k) -> tuple:
    """``k``'s declared parameter types in parameter order (a kernel made by ``@kernel(...)``)."""
    declared = getattr(k, "declared", None)
    if not declared:
        raise TypeError(f"{getattr(k, '__qualname__', k)!r} has no declared signature: use @kernel(name=type, ...)")
    return tuple(t for _, t in declared)


def bind(k):
    """The version of kernel ``k`` compiled for its declared signature, to call without numba's dispatcher.

    Compiled now (or loaded from the cache). With checking on (:func:`checking`), the function returned
    checks each argument against the declaration first. Without numba's compiler (``NUMBA_DISABLE_JIT``)
    it is the Python function, checked the same way."""
    sig = signature(k)
    compile_for = getattr(k, "compile", None)
    fast = compile_for(sig) if compile_for is not None else k
    if not checking():
        return fast
    name = getattr(k, "__qualname__", getattr(k, "__name__", repr(k)))
    checks = [(param, _check_for(t)) for param, t in k.declared]

    def checked(*args):
        if len(args) != len(checks):
            raise TypeError(f"kernel {name}: {len(args)} arguments given, {len(checks)} declared")
        for value, (param, check) in zip(args, checks):
            problem = check(value)
            if problem:
                raise TypeError(f"kernel {name}, parameter {param!r}: {problem}")
        return fast(*args)

    checked.__name__ = checked.__qualname__ = f"checked_{getattr(k, '__name__', 'kernel')}"
    checked.kernel = k
    return checked


def _check_for(declared):
    """A function of one value returning what is wrong with it for type ``declared`` ('' when nothing)."""
    if isinstance(declared, types.Array):
        dtype = np.dtype(numba.np.numpy_support.as_dtype(declared.dtype))
        ndim, readonly = declared.ndim, not declared.mutable

        def array(value):
            if not isinstance(value, np.ndarray):
                return f"expected a {dtype} array, got {type(value).__name__}"
            if value.dtype != dtype:
                return f"expected dtype {dtype}, got {value.dtype}"
            if value.ndim != ndim:
                return f"expected {ndim} dimension(s), got {value.ndim}"
            if not value.flags.c_contiguous:
                return "expected a C-contiguous array, got a strided view"
            if not readonly and not value.flags.writeable:
                return "expected a writable array, got a read-only one"
            return ""

        return array
    if declared == types.float64:
        return lambda v: (
            ""
            if isinstance(v, (float, int, np.floating, np.integer)) and not isinstance(v, bool)
            else (f"expected a float, got {type(v).__name__}")
        )
    if declared == types.int64:
        return lambda v: (
            ""
            if isinstance(v, (int, np.integer)) and not isinstance(v, bool)
            else (f"expected an int, got {type(v).__name__}")
        )
    if declared == types.boolean:
        return lambda v: "" if isinstance(v, (bool, np.bool_)) else f"expected a bool, got {type(v).__name__}"

    def other(value):
        got = numba.typeof(value)
        return "" if got == declared else f"expected {declared}, got {got}"

    return other


# -- the on-disk cache: one stamp for all of simatch's kernel modules ------------------------------------

_PACKAGE = Path(__file__).resolve().parent


class _PackageStamp:
    """Cache locators for simatch's own files whose source stamp covers every simatch module with kernels,
    so that editing a kernel invalidates the cached kernels of the other files that call it."""

    _stamp: str | None = None

    def get_source_stamp(self):
        if _PackageStamp._stamp is None:
            digest = hashlib.sha256()
            for path in sorted(_PACKAGE.rglob("*.py")):
                text = path.read_bytes()
                if b"numba" in text or b"simatch.compiled" in text or b"from ..compiled" in text:
                    digest.update(str(path.relative_to(_PACKAGE)).encode() + b"\0" + text)
            _PackageStamp._stamp = digest.hexdigest()
        return _PackageStamp._stamp

    @classmethod
    def from_function(cls, py_func, py_file):
        try:
            Path(py_file).resolve().relative_to(_PACKAGE)
        except (ValueError, OSError):
            return None
        return super().from_function(py_func, py_file)


class _InTreeLocator(_PackageStamp, caching.InTreeCacheLocator):
    pass


class _UserWideLocator(_PackageStamp, caching.UserWideCacheLocator):
    pass


if _InTreeLocator not in caching.CacheImpl._locator_classes:
    caching.CacheImpl._locator_classes[:0] = [_InTreeLocator, _UserWideLocator]
