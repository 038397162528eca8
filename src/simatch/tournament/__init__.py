"""Tournaments: every pairing of many teams over many seeded matches, played on Ray, with a standing
(docs/tournament.md). The command is ``simatch tournament``; in Python:

    from simatch.tournament import Tournament, RayPool, parse_entries
    t = Tournament(parse_entries(["nubot,simple"]), seeds=range(10), out="results")
    pool = RayPool()
    try:
        summary = t.play(pool)
    finally:
        pool.close()
"""

from __future__ import annotations

from .entries import Entry, parse_entries
from .runner import PlainLoop, RayPool
from .tournament import Tournament

__all__ = ["Entry", "PlainLoop", "RayPool", "Tournament", "parse_entries"]
