"""Ball holding, the ball's rotation (MSL RC-12.3.1): a robot that holds the ball must not exert forces against
the ball's natural rotation for more than ``ball_rotation_time`` (1 s) or over more than
``ball_rotation_distance`` (30 cm) of the ball's travel, and may do so again only after
``ball_rotation_rest`` (4 s) without, or once it has released the ball.

The natural rotation of a ball that moves over the floor is rolling with its motion: spin w = z x v / r. The
rule reads the ball's spin from the model states (the physics computes it: the floor and the dribbler's
rollers turn the ball, see `simatch.sim.ballhandling`) at the control period, while one robot alone holds
the ball (its dribbler, as ``ball_contacts`` says), the ball is on the ground and moves over the floor at
least ``ball_rotation_min_speed``: the rotation ratio is the ball's spin along its rolling axis over the
spin of rolling, ``r (w_y v_x - w_x v_y) / |v|^2`` (1 rolling, 0 sliding unturned, below 0 turned against
its motion). A ratio below ``ball_rotation_ratio`` (1/2) is holding it against its rotation; the time and
the ball's travel add up until the ball is released or ``ball_rotation_rest`` passes without it. A foul
gives the opponents a free kick where the ball is.

An active dribbler turns the ball with its motion (the shipped one does, ``dribbler.roller_spin = 1``); one
that clamps the ball (``roller_spin = 0``) makes it slide and commits the foul after 30 cm.
"""

from __future__ import annotations

import math

from ..state import LIVE
from .base import Call, Rule

ON_GROUND = 0.05  # the ball's centre at most this above its radius: on the ground [m]


class BallRotationRule(Rule):
    name = "ball_rotation"
    phases = LIVE

    def __init__(self, match):
        super().__init__(match)
        self.robot = -1  # the robot holding the ball
        self.time = 0.0  # held against its rotation: seconds ...
        self.travel = 0.0  # ... and the ball's way [m]
        self.since = math.inf  # seconds since it was last held against its rotation

    def on_restart(self) -> None:
        self._forget(-1)

    def _forget(self, robot: int) -> None:
        self.robot, self.time, self.travel, self.since = robot, 0.0, 0.0, math.inf

    def check(self) -> Call | None:
        m, p = self.m, self.p
        obs, touches = m.obs, m.touches
        fresh = touches.contact_step >= obs.step - 1
        i = touches.holder if fresh and touches.contact == (touches.holder,) else -1
        if i < 0 or not obs.active[i]:
            if self.robot >= 0:  # (forgotten already otherwise: nothing else changes while nobody is followed)
                self._forget(-1)  # released (or in a duel): it may begin anew
            return None
        if i != self.robot:
            self._forget(i)
        r = obs.ball_radius
        vx, vy = obs.bvx, obs.bvy
        v2 = vx * vx + vy * vy
        dt = m.control_dt
        if obs.bz > r + ON_GROUND or v2 < p.ball_rotation_min_speed**2:
            self._rest(dt)
            return None
        ratio = r * (obs.bwy * vx - obs.bwx * vy) / v2
        if ratio >= p.ball_rotation_ratio:
            self._rest(dt)
            return None
        self.since = 0.0
        self.time += dt
        self.travel += math.sqrt(v2) * dt
        far = self.travel > p.ball_rotation_distance
        if not far and self.time <= p.ball_rotation_time + 1e-9:
            return None
        value, limit = (self.travel, p.ball_rotation_distance) if far else (self.time, p.ball_rotation_time)
        what = f"{self.travel:.2f} m" if far else f"{self.time:.2f} s"
        self._forget(i)
        return self.call(
            "ball_rotation",
            i,
            value,
            limit,
            f"{obs.names[i]} held the ball against its natural rotation for {what} (it turned at {ratio:.2f} of "
            f"rolling with its motion, at least {p.ball_rotation_ratio:.2f}; limits {p.ball_rotation_time:.1f} s "
            f"and {p.ball_rotation_distance:.2f} m): free kick for {obs.other(obs.team_of[i])}",
            restart=self.free_kick_against(i),
        )

    def _rest(self, dt: float) -> None:
        """A period without holding the ball against its rotation: after ``ball_rotation_rest`` it may begin
        anew."""
        self.since += dt
        if self.since >= self.p.ball_rotation_rest - 1e-9:
            self.time = self.travel = 0.0
