"""Real-time pacing of a server run (``simatch server --realtime``): simulated time follows the wall clock.

A node of the ACT phase, after the physics: it sleeps until the wall-clock time of the next physics step,
so each step's states are published when their time comes (not in bursts). A run that falls behind by more
than ``slack`` catches up no further (it re-anchors) and counts the lag, which `stats` reports.
"""

from __future__ import annotations

import time

from ..bus import Node, Phase


class Pacer(Node):
    phase = Phase.ACT
    name = "pacer"

    def __init__(self, dt: float, pace: float = 1.0, slack: float = 0.2):
        self.period = dt
        self.dt = dt
        self.pace = pace
        self.slack = slack
        self.anchor: tuple[float, float] | None = None  # (wall, sim) when pacing began
        self.steps = 0
        self.late_steps = 0  # steps that started behind their wall-clock time
        self.max_lag = 0.0  # [s]
        self.reanchored = 0

    def tick(self, now: float) -> None:
        wall = time.perf_counter()
        nxt = now + self.dt
        if self.anchor is None:
            self.anchor = (wall, now)
        due = self.anchor[0] + (nxt - self.anchor[1]) / self.pace
        ahead = due - wall
        self.steps += 1
        if ahead > 0:
            time.sleep(ahead)
            return
        self.late_steps += 1
        self.max_lag = max(self.max_lag, -ahead)
        if -ahead > self.slack:
            self.anchor = (wall, nxt)
            self.reanchored += 1

    def reset_stats(self) -> None:
        self.steps = self.late_steps = self.reanchored = 0
        self.max_lag = 0.0

    def stats(self) -> dict:
        return {
            "late_steps": self.late_steps,
            "steps": self.steps,
            "max_lag_ms": round(self.max_lag * 1e3, 3),
            "reanchored": self.reanchored,
        }
