"""Restarts and where the referee places the ball for each (world frame, metres).

* kick-off: the centre mark; penalty: the penalty mark in front of the defended goal;
* throw-in: where the ball crossed the side line, ``throw_in_inset`` inside it;
* corner kick: the corner on the side where the ball crossed, ``corner_inset`` inside both lines;
* goal kick: the restart spot (``restart_spot``: distance from the goal line, |y|) on the side where the ball
  crossed (the original referee's points, outside the penalty area);
* free kick and dropped ball: where the ball is, kept ``restart_border`` inside the lines, and moved to the
  nearer restart spot of that half if it lies in a penalty area (as the original referee did).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...field import FieldGeometry
from ...msgs.game_commands import RESTART_COMMANDS, MatchMode, for_team
from .params import RefereeParams

KINDS = tuple(RESTART_COMMANDS)
NAMES = {
    "kickoff": "kick-off",
    "throw_in": "throw-in",
    "penalty": "penalty kick",
    "goal_kick": "goal kick",
    "corner_kick": "corner kick",
    "free_kick": "free kick",
    "dropped_ball": "dropped ball",
}


@dataclass(frozen=True)
class Restart:
    """How play restarts: ``kind`` (a key of RESTART_COMMANDS), the team that takes it ("" for a dropped
    ball), and the ball's spot."""

    kind: str
    team: str
    x: float
    y: float

    def command_for(self, team: str) -> MatchMode:
        """The set-piece command as ``team`` hears it (OUR_x for the taker, OPP_x for the other)."""
        cmd = RESTART_COMMANDS[self.kind]
        if not self.team:
            return cmd
        return for_team(cmd, self.team, team)

    def describe(self) -> str:
        who = f" for {self.team}" if self.team else ""
        return f"{NAMES[self.kind]}{who} at ({self.x:.2f}, {self.y:.2f})"


class Spots:
    def __init__(self, field: FieldGeometry, params: RefereeParams, ball_radius: float):
        self.f = field
        self.p = params
        self.r = ball_radius

    def kickoff(self, team: str) -> Restart:
        return Restart("kickoff", team, 0.0, 0.0)

    def penalty(self, team: str, goal_side: int) -> Restart:
        x, y = self.f.penalty_spot(goal_side)
        return Restart("penalty", team, x, y)

    def throw_in(self, team: str, x_out: float, y_out: float) -> Restart:
        f, inset = self.f, self.p.throw_in_inset
        x = max(-(f.half_length - inset), min(f.half_length - inset, x_out))
        return Restart("throw_in", team, x, math.copysign(f.half_width - inset, y_out))

    def corner(self, team: str, goal_side: int, y_out: float) -> Restart:
        f, inset = self.f, self.p.corner_inset
        return Restart(
            "corner_kick",
            team,
            goal_side * (f.half_length - inset),
            math.copysign(f.half_width - inset, y_out if y_out else 1.0),
        )

    def restart_point(self, goal_side: int, y: float) -> tuple[float, float]:
        dx, ay = self.p.restart_spot
        return (goal_side * (self.f.half_length - dx), math.copysign(ay, y if y else 1.0))

    def goal_kick(self, team: str, goal_side: int, y_out: float) -> Restart:
        x, y = self.restart_point(goal_side, y_out)
        return Restart("goal_kick", team, x, y)

    def at_ball(self, kind: str, team: str, x: float, y: float) -> Restart:
        """A free kick or dropped ball where the ball is (kept inside the lines and out of penalty areas)."""
        f, b = self.f, self.p.restart_border
        x = max(-(f.half_length - b), min(f.half_length - b, x))
        y = max(-(f.half_width - b), min(f.half_width - b, y))
        for side in (-1, 1):
            if f.in_penalty_area(x, y, side):
                x, y = self.restart_point(side, y)
        return Restart(kind, team, x, y)
