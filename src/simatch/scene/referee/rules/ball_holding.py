"""Ball holding, how far the ball enters a robot (MSL RC-12.0.1, RC-12.3.1): the ball may enter the robot's
convex hull by at most ``ball_holding_depth`` (1/3) of its diameter, and by up to
``ball_holding_brief_depth`` (1/2) only briefly, for less than ``ball_holding_brief_time`` (1 s), as when
the robot stops a ball.

The convex hull of a simulated robot seen from above is its footprint: the circle of its ``radius`` (the
mouth is cut into it, so the ball can sit inside the circle). The depth is measured from the model states
at the control period: the robot's radius plus the ball's minus the distance between their centres, while
the ball is on the ground (its centre within 5 cm of its radius; a ball in the air is not in a robot's
mouth). A foul gives the opponents a free kick where the ball is.

What the robot does, not what is done to it, is judged: only a robot in sole contact with the ball, and not
at a goal post, where another body can press the ball into it (a duel squeezing the ball between two mouths,
a ball pinned against a post: the contact's softness lets it in deeper). An impact does the same for a few
milliseconds (a 10 m/s shot into a robot driving at it: deeper than 1/2 for 5-10 ms, deeper than 1/3 for
0.07 s), so a depth beyond 1/2 counts only when seen at ``SETTLE_PERIODS`` control periods in a row.

With the shipped robots (``mouth_depth`` 0.07 m, below 1/3 of the 0.22 m ball) a held ball sits 0.066 m
deep and the mouth's collider keeps it there: the rule cannot fire on them (tests/referee/
test_ball_holding_depth.py presses the ball as hard as a robot can). It judges robot models whose mouth is
deeper (``teams.<team>.model_params.mouth_depth``).
"""

from __future__ import annotations

import math

from ..state import LIVE
from .base import Call, Rule

ON_GROUND = 0.05  # the ball's centre at most this above its radius: on the ground [m]
POST_CLEARANCE = 0.35  # a ball this close to a goal post's centre may be pressed against it [m]
SETTLE_PERIODS = 2  # a depth beyond the brief limit counts when seen at this many control periods in a row


class BallHoldingRule(Rule):
    name = "ball_holding"
    phases = LIVE

    def __init__(self, match):
        super().__init__(match)
        f = match.obs.field
        self.posts = (
            [(sx * f.half_length, sy * 0.5 * f.goal_width) for sx in (-1, 1) for sy in (-1, 1)] if f.goals else []
        )
        # a ball nearer the half-way line than this is farther than POST_CLEARANCE from every post (by a
        # micrometre: the distances' rounding cannot matter), so the posts need no test
        self._posts_far = min((abs(x) for x, _ in self.posts), default=math.inf) - POST_CLEARANCE - 1e-6
        self.robot = -1  # the robot being followed
        self.deep_for = 0  # control periods the ball has been deeper than the limit in it
        self.deeper_for = 0  # ... and deeper than the brief limit

    def on_restart(self) -> None:
        self.robot = -1

    def check(self) -> Call | None:
        m, p = self.m, self.p
        obs, touches = m.obs, m.touches
        r = obs.ball_radius
        i = touches.contact[0] if len(touches.contact) == 1 and touches.contact_step >= obs.step - 1 else -1
        if (
            i < 0
            or obs.bz > r + ON_GROUND
            or not obs.active[i]
            or (
                not -self._posts_far < obs.bx < self._posts_far
                and any(math.hypot(obs.bx - x, obs.by - y) < POST_CLEARANCE for x, y in self.posts)
            )
        ):
            self.robot = -1
            return None
        d = 2.0 * r
        limit, brief = p.ball_holding_depth * d, p.ball_holding_brief_depth * d
        depth = obs.radius[i] + r - math.hypot(obs.bx - obs.X[i], obs.by - obs.Y[i])
        if i != self.robot:
            self.robot, self.deep_for, self.deeper_for = i, 0, 0
        self.deep_for = self.deep_for + 1 if depth > limit else 0
        self.deeper_for = self.deeper_for + 1 if depth > brief else 0
        held = self.deep_for * m.control_dt
        if self.deeper_for >= SETTLE_PERIODS:
            value, lim, what = depth, brief, f"{depth:.3f} m (limit {brief:.3f} m, 1/2 of the ball's diameter)"
        elif self.deep_for and held >= p.ball_holding_brief_time - 1e-9:
            value, lim, what = (
                depth,
                limit,
                (
                    f"{depth:.3f} m (limit {limit:.3f} m) for {held:.2f} s (up to "
                    f"{brief:.3f} m only for less than {p.ball_holding_brief_time:.1f} s)"
                ),
            )
        else:
            return None
        self.robot = -1
        return self.call(
            "ball_holding",
            i,
            value,
            lim,
            f"the ball entered {obs.names[i]}'s convex hull by {what}: free kick for {obs.other(obs.team_of[i])}",
            restart=self.free_kick_against(i),
        )
