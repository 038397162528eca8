"""Dribbling too far (MSL RC-12.3.1, ball holding): a robot may keep the ball only within
``dribble_distance`` (3 m) of the point where it took it, and may drive at most
``dribble_backward_distance`` (2 m) backwards with it.

Possession (see `touches.py`) starts when a robot alone touches or holds the ball, and ends when the ball is
``dribble_release_distance`` from it or another robot alone takes it; the circle restarts at each new
possession. The distance is the robot's (the original referee measured the robot too, not the ball);
backward travel adds up every stretch the robot drives against its heading while it keeps the ball. A
foul gives the opponents a free kick where the ball is.
"""

from __future__ import annotations

import math

from ..state import LIVE
from .base import Call, Rule


class DribblingRule(Rule):
    name = "dribbling"
    phases = LIVE

    def check(self) -> Call | None:
        touches = self.m.touches
        touches.update_possession()
        i = touches.possessor
        if i < 0:
            return None
        obs = self.m.obs
        sx, sy = touches.start_xy
        d = math.hypot(obs.X[i] - sx, obs.Y[i] - sy)
        if d > self.p.dribble_distance:
            touches.possessor = -1
            return self.call(
                "dribble_too_far",
                i,
                d,
                self.p.dribble_distance,
                f"{obs.names[i]} kept the ball {d:.3f} m from where it took it at ({sx:.2f}, {sy:.2f}) "
                f"(limit {self.p.dribble_distance:.2f} m)",
                restart=self.free_kick_against(i),
            )
        back = touches.backward
        if back > self.p.dribble_backward_distance:
            touches.possessor = -1
            return self.call(
                "dribble_backward_too_far",
                i,
                back,
                self.p.dribble_backward_distance,
                f"{obs.names[i]} drove {back:.3f} m backwards with the ball "
                f"(limit {self.p.dribble_backward_distance:.2f} m)",
                restart=self.free_kick_against(i),
            )
        return None
