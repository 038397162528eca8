"""Distributed runs over Zenoh: the server (simulator + judge), team and robot processes, the lockstep
protocol between them, and fair play between teams. See docs/distributed.md."""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Callable


@contextlib.contextmanager
def interrupt_on_term(stop_soon: Callable[[BaseException], bool] | None = None):
    """SIGTERM and SIGHUP interrupt like Ctrl-C, so every way of stopping a process closes its session (a
    Zenoh session left open can hang the interpreter at exit) and tells the other processes.

    With ``stop_soon`` (given the KeyboardInterrupt, True when it will be raised at a safe point, e.g.
    between two ticks), Ctrl-C too waits for that point: raised wherever a signal lands, the interruption
    can come out of a compiled kernel's dispatch as a SystemError, which a strategy's error guard takes for
    a bug of the strategy, and the process would play on."""

    def interrupt(signum, frame):
        exc = KeyboardInterrupt(signal.Signals(signum).name)
        if stop_soon is None or not stop_soon(exc):
            raise exc

    old = {}
    for sig in (signal.SIGTERM, signal.SIGHUP) + ((signal.SIGINT,) if stop_soon is not None else ()):
        try:
            old[sig] = signal.signal(sig, interrupt)
        except ValueError:  # not the main thread: leave signals alone
            pass
    try:
        yield
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)
