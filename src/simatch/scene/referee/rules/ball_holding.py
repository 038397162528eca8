"""Ball holding, how far the ball enters a robot (MSL RC-12.0.1, RC-12.3.1): the ball may enter the robot's
convex hull by at most ``ball_holding_depth`` (1/3) of its diameter, and by up to
``ball_holding_brief_depth`` (1/2) only briefly, for less than ``ball_holding_brief_time`` (1 s), as when
the robot stops a ball.

The convex hull of a simulated robot seen from above is its footprint: the circle of its ``radius`` (the
mouth is cut into it, so the ball can sit inside the circle). The depth is measured from the model states
at the control period: the robot's radius plus the ball's minus the distance between their centres, while
the ball is on the ground (its centre within 5 cm of its radius; a ball in the air is not in a robot's
mouth). A foul gives the opponents a free kick where the ball is.

With the shipped robots (``mouth_depth`` 0.07 m, below 1/3 of the 0.22 m ball) a held ball sits 0.066 m
deep and the mouth's collider keeps it from going deeper than the mouth: the rule cannot fire (a test
proves it, pressing the ball as hard as a robot can). It judges robot models whose mouth is deeper
(``teams.<team>.model_params.mouth_depth``).
"""

from __future__ import annotations

import math
from typing import Optional

from ..state import LIVE
from .base import Call, Rule

ON_GROUND = 0.05    # the ball's centre at most this above its radius: on the ground [m]


class BallHoldingRule(Rule):
    name = "ball_holding"
    phases = LIVE

    def __init__(self, match):
        super().__init__(match)
        self.deep_for = [0] * match.obs.n      # control periods the ball has been deeper than the depth limit

    def on_restart(self) -> None:
        self.deep_for = [0] * self.m.obs.n

    def check(self) -> Optional[Call]:
        m, p = self.m, self.p
        obs = m.obs
        r = obs.ball_radius
        if obs.bz > r + ON_GROUND:
            self.deep_for = [0] * obs.n
            return None
        d = 2.0 * r
        limit, brief = p.ball_holding_depth * d, p.ball_holding_brief_depth * d
        bx, by = obs.bx, obs.by
        X, Y, R, deep_for = obs.X, obs.Y, obs.radius, self.deep_for
        for i in range(obs.n):
            dx = bx - X[i]
            reach = R[i] + r - limit
            if dx > reach or -dx > reach or not obs.active[i]:
                deep_for[i] = 0
                continue
            depth = R[i] + r - math.hypot(dx, by - Y[i])
            if depth <= limit:
                deep_for[i] = 0
                continue
            deep_for[i] += 1
            held = deep_for[i] * m.control_dt
            if depth > brief:
                value, lim, what = depth, brief, f"{depth:.3f} m (limit {brief:.3f} m, 1/2 of the ball's diameter)"
            elif held >= p.ball_holding_brief_time - 1e-9:
                value, lim, what = depth, limit, (f"{depth:.3f} m (limit {limit:.3f} m) for {held:.2f} s (deeper "
                                                  f"than the limit for less than {p.ball_holding_brief_time:.1f} s "
                                                  f"is allowed)")
            else:
                continue
            deep_for[i] = 0
            return self.call("ball_holding", i, value, lim,
                             f"the ball entered {obs.names[i]}'s convex hull by {what}: free kick for "
                             f"{obs.other(obs.team_of[i])}", restart=self.free_kick_against(i))
        return None
