"""MuJoCo's profiling timers, not kept during simatch's runs.

MuJoCo times the phases of every step (``MjData.timer``: position, velocity, collision, constraint
solver ...) with the clock it gets from the global callback ``mjcb_time``, or from the system clock
when none is installed, some twenty times per physics step. simatch never reads those timers, so it
does not pay for the clock: `keep_timers_off` installs a clock that returns 0, a native function (a numba
C callback) that MuJoCo calls without the interpreter; the timers then read 0 and their counts still
count.

The callback is MuJoCo's and global: it holds for every model of the process. So it is installed
only where nobody else has installed one (a program that embeds simatch and sets its own clock keeps
it), and not at all when ``SIMATCH_MUJOCO_TIMERS=1`` is set, for whoever profiles MuJoCo's phases in
a simatch run. The physics is untouched: the timers are read by nothing that moves the world."""

from __future__ import annotations

import ctypes
import os

import mujoco

_clock = None  # the installed callback's objects, kept alive as long as MuJoCo may call them


def keep_timers_off() -> bool:
    """Install the zero clock as MuJoCo's ``mjcb_time`` unless a clock is installed already or
    ``SIMATCH_MUJOCO_TIMERS=1``; True when MuJoCo's timers are off (by this call or an earlier one)."""
    global _clock
    if _clock is not None:
        return mujoco.get_mjcb_time() is _clock[1]
    if os.environ.get("SIMATCH_MUJOCO_TIMERS") == "1" or mujoco.get_mjcb_time() is not None:
        return False
    try:
        import numba

        native = numba.cfunc("float64()", cache=True)(_zero)
        address = native.address
    except Exception:  # noqa: BLE001 - no compiler (NUMBA_DISABLE_JIT, a stripped install): MuJoCo's own clock
        return False
    pointer = ctypes.cast(address, ctypes.CFUNCTYPE(ctypes.c_double))
    mujoco.set_mjcb_time(pointer)
    _clock = (native, pointer)
    return True


def _zero() -> float:
    return 0.0
