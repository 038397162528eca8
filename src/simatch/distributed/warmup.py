"""Warming a team or robot process up before it joins: its compiled kernels are loaded, not met mid-match.

A strategy may use numba kernels cached on disk (the default team does). In a process of its own, the
first call of the first kernel also starts numba's compiler machinery: several hundred milliseconds,
at whatever tick first takes that code path (in the default team: the kick-off). Embedded, the simulator
has already paid that; in a lockstep run the whole match waits for it, in a real-time run the process
misses a string of ticks. So a process loads, before it joins, every cached kernel of the modules it has
imported.

On a machine where the kernels were never compiled (a fresh install, a changed strategy), there is
nothing to load: compiling them takes tens of seconds, far beyond a lockstep tick's deadline, so a
process that met them at its first tick would be left behind and the match would be played without it.
Such a process first `rehearse`\\ s: it plays a few throwaway seconds of the run's scene embedded, its own
team alone on the field, which compiles (and caches) every kernel of the common path, then calls its
strategy's ``warm_up`` hook for those that only open play or set pieces reach.

numba has no public call for "load what the cache holds", so this reads the cache's index through numba's
internals; if they change, nothing is loaded and every kernel counts as uncached (the rehearsal then
compiles them): it is only a matter of when the time is spent.
"""

from __future__ import annotations

import logging
import sys
from typing import NamedTuple

log = logging.getLogger(__name__)

#: simulated seconds of the rehearsal: the kick-off and the first seconds of open play
REHEARSAL_SECONDS = 4.0


class Preloaded(NamedTuple):
    loaded: int  #: compilations read from the disk cache
    uncached: int  #: kernels with none there: they compile at their first call


def preload_compiled_kernels(prefixes: tuple[str, ...] = ("simatch",)) -> Preloaded:
    """Load the disk-cached compilations of every numba kernel in the imported modules whose name starts
    with one of ``prefixes``; says how many were loaded and how many kernels had none in the cache."""
    if "numba" not in sys.modules:  # the strategy does not use numba: nothing to warm
        return Preloaded(0, 0)
    try:
        from numba.core.registry import CPUDispatcher
    except ImportError:
        return Preloaded(0, 0)
    loaded = uncached = 0
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
                index = {}
            if not index:
                uncached += 1
    return Preloaded(loaded, uncached)


def rehearse(scene, team: str, seed: int, seconds: float = REHEARSAL_SECONDS) -> None:
    """Play ``seconds`` of ``scene`` (a scene in which only ``team`` has a strategy) embedded and throw it
    away, then call the ``warm_up()`` of the team's strategy class.

    The rehearsal's nodes are its own (nothing of the process's real nodes is touched), so it leaves the
    run bit for bit as it would be without it; what it leaves behind is compiled code and imports."""
    from ..simulation import Simulation
    from ..strategy import strategy_class

    with Simulation(scene, seed=seed) as sim:
        sim.run(seconds=seconds, until_done=False)
    spec = scene.spec.teams[team].strategy
    try:
        cls = strategy_class(spec)
    except Exception:  # "none", "external": nothing of its own to warm
        return
    cls.warm_up()  # (a TeamStrategy's calls its robot_class's by default)
