"""CPU time per thread of the processes of a distributed benchmark (Linux ``/proc``).

On a machine shared with other work the wall clock of a distributed run counts the time other jobs held the
cores; the CPU time each process (and each of its threads) used per control tick does not, so a change to
the wire or the lockstep protocol can be judged by it while the machine is busy. The server's thread that
runs the simulation is told apart from the rest of its process (Zenoh's threads: receiving, sending,
accepting), which run beside it.

    before = Sample.take({"server": os.getpid(), "cyan": pid1})
    ...  # run
    used = Sample.take(before.pids).minus(before)   # {"server": {"tid": seconds, ...}, ...}
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass


def _thread_seconds(pid: int) -> dict[int, float]:
    """CPU seconds used so far by each thread of ``pid`` (``schedstat``: nanoseconds on the CPU); empty if the
    process is gone or the system does not say."""
    out: dict[int, float] = {}
    try:
        tids = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return out
    for tid in tids:
        try:
            with open(f"/proc/{pid}/task/{tid}/schedstat", encoding="ascii") as f:
                out[int(tid)] = int(f.read().split()[0]) / 1e9
        except (OSError, ValueError, IndexError):
            continue  # the thread ended meanwhile
    return out


@dataclass
class Sample:
    """CPU seconds of every thread of some named processes at one moment."""

    pids: dict[str, int]
    threads: dict[str, dict[int, float]]

    @classmethod
    def take(cls, pids: Mapping[str, int]) -> Sample:
        return cls(dict(pids), {name: _thread_seconds(pid) for name, pid in pids.items()})

    def minus(self, before: Sample) -> dict[str, dict[int, float]]:
        """CPU seconds each thread used since ``before`` (threads started since then count from zero)."""
        return {
            name: {tid: s - before.threads.get(name, {}).get(tid, 0.0) for tid, s in threads.items()}
            for name, threads in self.threads.items()
        }


def per_tick_ms(used: Mapping[int, float], ticks: int, only: int | None = None, but: int | None = None) -> float:
    """Milliseconds of CPU per tick of the threads in ``used`` (just thread ``only``, or all but ``but``)."""
    total = sum(s for tid, s in used.items() if (only is None or tid == only) and tid != but)
    return round(1e3 * total / max(ticks, 1), 3)
