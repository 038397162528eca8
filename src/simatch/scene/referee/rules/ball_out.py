"""The ball out of the field (MSL RC-15, RC-16, and the corner kick), decided by the last touch.

The ball is out once it has wholly crossed a side line or a goal line (outside the goal), judged at the
physics rate. The lines belong to the field: the whole ball must be past the painted line's outer edge
(``FieldGeometry.outer_half_width`` / ``outer_half_length``); a ball resting on the line is in play. The
event's value is the ball centre's distance past the middle of the line, its limit half the line's width plus
the ball's radius. Over a side line: a throw-in for the team that did not touch it last, ``throw_in_inset``
inside the line where the ball crossed. Over a goal line: a goal kick when the attacking team touched it
last, a corner kick when the defending team did. When nobody has touched the ball, a dropped ball.
"""

from __future__ import annotations

from ..state import LIVE
from .base import Call, Rule


class BallOutRule(Rule):
    name = "ball_out"
    phases = LIVE

    def limit(self) -> float:
        """How far the ball's centre is past the middle of a line when the whole ball has crossed it."""
        obs = self.m.obs
        return 0.5 * obs.field.line_width + obs.ball_radius

    def crossed_side_line(self, x: float, y: float) -> Call:
        obs, spots = self.m.obs, self.m.spots
        over = abs(y) - obs.field.half_width
        where = f"over the side line at x = {x:.2f} m"
        last = self.m.touches.last
        if last < 0:
            r = spots.throw_in("", x, y)
            return self._call(x, y, over, where, spots.at_ball("dropped_ball", "", r.x, r.y))
        team = obs.other(obs.team_of[last])
        return self._call(x, y, over, where, spots.throw_in(team, x, y), f"throw-in for {team}")

    def crossed_goal_line(self, side: int, x: float, y: float, z: float) -> Call:
        obs, spots = self.m.obs, self.m.spots
        f = obs.field
        over = side * x - f.half_length
        defending = obs.defender_of(side)
        attacking = obs.other(defending)
        last = self.m.touches.last
        if f.goals and abs(y) < 0.5 * f.goal_width:
            where = f"over {defending}'s goal line above the bar (ball centre at {z:.2f} m)"
        else:
            where = f"over {defending}'s goal line at y = {y:.2f} m, outside the posts"
        if last < 0:
            px, py = spots.restart_point(side, y)
            return self._call(x, y, over, where, spots.at_ball("dropped_ball", "", px, py))
        if obs.team_of[last] == attacking:
            return self._call(x, y, over, where, spots.goal_kick(defending, side, y), f"goal kick for {defending}")
        return self._call(x, y, over, where, spots.corner(attacking, side, y), f"corner kick for {attacking}")

    def _call(self, x: float, y: float, over: float, where: str, restart, then: str = "") -> Call:
        """The ball out ``where``, ``over`` past the line's middle, and its ``restart``: ``then`` after the
        last touch, or a dropped ball when nobody has touched it."""
        obs, last = self.m.obs, self.m.touches.last
        return Call(
            "ball_out",
            team=obs.team_of[last] if last >= 0 else "",
            robot=last,
            x=x,
            y=y,
            value=over,
            limit=self.limit(),
            detail=f"ball out {where}, last touched by {obs.names[last]}: {then}"
            if last >= 0
            else f"ball out {where}; nobody touched it: dropped ball",
            restart=restart,
        )
