"""Double touch (MSL RC-8.3, RC-13): the taker of a set piece may not touch the ball again before another
robot has. The taker has let go of the ball once it has been out of contact for ``double_touch_gap``; a
touch after that, before any other robot touched the ball, is a foul (free kick for the opponents where it
happened). Contacts come from the simulator's ball bumper at the physics rate (`touches.py`)."""

from __future__ import annotations

from ..state import LIVE
from .base import Call, Rule


class DoubleTouchRule(Rule):
    name = "double_touch"
    phases = LIVE

    def check(self) -> Call | None:
        touches = self.m.touches
        if touches.retouch is None:
            return None
        step, x, y, gap_steps = touches.retouch
        i = touches.taker
        touches.retouch = None
        touches.armed = False
        obs = self.m.obs
        gap = gap_steps * self.m.dt
        call = self.call(
            "double_touch",
            i,
            gap,
            self.p.double_touch_gap,
            f"{obs.names[i]} took the {self.m.restart_name()}, let go of the ball for {gap:.2f} s and "
            f"touched it again before any other robot did",
            restart=self.free_kick_against(i),
        )
        call.x, call.y = x, y
        return call
