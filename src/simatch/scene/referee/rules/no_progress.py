"""No progress (MSL RC-8.5.1, game stuck): a ball in play that stays within ``no_progress_radius`` of where
it was for ``no_progress_time`` — stuck between robots, held without moving, or lying where nobody plays
it — becomes a dropped ball where it is. Not a foul."""

from __future__ import annotations

import math

from ..state import Phase
from .base import Call, Rule


class NoProgressRule(Rule):
    name = "no_progress"
    phases = frozenset({Phase.PLAY})

    def __init__(self, match):
        super().__init__(match)
        self.anchor = (math.nan, math.nan)
        self.ticks = 0  # control periods in play since the ball was last at least the radius away

    def on_restart(self) -> None:
        self.anchor = (math.nan, math.nan)

    def check(self) -> Call | None:
        m = self.m
        bx, by = m.obs.bx, m.obs.by
        ax, ay = self.anchor
        if not (math.hypot(bx - ax, by - ay) <= self.p.no_progress_radius):  # also true for the NaN anchor
            self.anchor = (bx, by)
            self.ticks = 0
            return None
        self.ticks += 1
        stuck = self.ticks * m.control_dt
        if stuck < self.p.no_progress_time - 1e-9:
            return None
        self.anchor = (math.nan, math.nan)
        return Call(
            "no_progress",
            x=bx,
            y=by,
            value=stuck,
            limit=self.p.no_progress_time,
            detail=f"the ball stayed within {self.p.no_progress_radius:.2f} m of ({ax:.2f}, {ay:.2f}) for "
            f"{stuck:.1f} s: dropped ball",
            restart=m.spots.at_ball("dropped_ball", "", bx, by),
        )
