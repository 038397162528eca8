"""What else the machine was doing during a benchmark: the share of CPU time the hypervisor gave to other
guests (*steal*, Linux's ``/proc/stat``).

On a virtual machine a noisy neighbour takes cores away for milliseconds at a time: the latency benchmarks'
tails (p99, max) then measure the host, not simatch. Each benchmark reports the steal of its run beside its
figures, so that a figure can be judged.
"""

from __future__ import annotations


def cpu_times() -> tuple[int, int] | None:
    """(steal, total) clock ticks of every CPU since boot; None where ``/proc/stat`` does not say."""
    try:
        with open("/proc/stat") as f:
            fields = f.readline().split()
    except OSError:
        return None
    if len(fields) < 9 or fields[0] != "cpu":
        return None
    ticks = [int(v) for v in fields[1:9]]  # user nice system idle iowait irq softirq steal
    return ticks[7], sum(ticks)


def steal_pct(before: tuple[int, int] | None, after: tuple[int, int] | None) -> float | None:
    """The share [%] of CPU time stolen between two `cpu_times` (None if unknown)."""
    if before is None or after is None or after[1] <= before[1]:
        return None
    return round(100.0 * (after[0] - before[0]) / (after[1] - before[1]), 1)
