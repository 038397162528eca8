"""Distributed runs over Zenoh: the server (simulator + judge), team and robot processes, the lockstep
protocol between them, and fair play between teams. See docs/distributed.md."""

from __future__ import annotations

import contextlib
import signal


@contextlib.contextmanager
def interrupt_on_term():
    """SIGTERM and SIGHUP interrupt like Ctrl-C, so every way of stopping a process closes its session (a
    Zenoh session left open can hang the interpreter at exit) and tells the other processes."""

    def interrupt(signum, frame):
        raise KeyboardInterrupt(signal.Signals(signum).name)

    old = {}
    for sig in (signal.SIGTERM, signal.SIGHUP):
        try:
            old[sig] = signal.signal(sig, interrupt)
        except ValueError:  # not the main thread: leave signals alone
            pass
    try:
        yield
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)
