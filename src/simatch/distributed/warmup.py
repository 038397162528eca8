"""Warming a team or robot process up before it joins: its compiled kernels are loaded, not met mid-match.

A strategy may use numba kernels cached on disk (the default team does). In a process of its own, the
first call of the first kernel also starts numba's compiler machinery: several hundred milliseconds,
at whatever tick first takes that code path (in the default team: the kick-off). Embedded, the simulator
has already paid that; in a lockstep run the whole match waits for it, in a real-time run the process
misses a string of ticks. So a process loads, before it joins, every cached kernel of the modules it has
imported.

numba has no public call for "load what the cache holds", so this reads the cache's index through numba's
internals; if they change, nothing is loaded (the kernels then load at first use, as before): it is only a
matter of when the time is spent.
"""

from __future__ import annotations

import logging
import sys

log = logging.getLogger(__name__)


def preload_compiled_kernels(prefixes: tuple[str, ...] = ("simatch",)) -> int:
    """Load the disk-cached compilations of every numba kernel in the imported modules whose name starts
    with one of ``prefixes``; returns how many were loaded (0 if numba is not in use)."""
    if "numba" not in sys.modules:  # the strategy does not use numba: nothing to warm
        return 0
    try:
        from numba.core.registry import CPUDispatcher
    except ImportError:
        return 0
    loaded = 0
    for name, module in list(sys.modules.items()):
        if module is None or not name.startswith(prefixes):
            continue
        for obj in list(vars(module).values()):
            if not isinstance(obj, CPUDispatcher) or obj.signatures:
                continue
            try:
                index = obj._cache._cache_file._load_index()
                for key in index:
                    obj.compile(key[0])
                    loaded += 1
            except Exception as exc:  # internals changed, or a stale cache: it loads at first use instead
                log.debug("could not preload %s.%s: %s", name, getattr(obj, "__name__", "?"), exc)
    return loaded
