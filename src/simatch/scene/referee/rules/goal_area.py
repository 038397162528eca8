"""Illegal defence and attack, goal area (MSL RC-12.3.4/5): only a team's own goalkeeper may be in its
goal area. A robot is inside when its centre is on the area's painted lines (up to their outer edge: the
lines belong to the area) or inside them; the area extends behind the goal line, into the goal. Judged
while the ball is in play; the opponents get a free kick.
"""

from __future__ import annotations

from ..state import Phase
from .base import Call, Rule


class GoalAreaRule(Rule):
    name = "goal_area"
    phases = frozenset({Phase.PLAY})

    def check(self) -> Call | None:
        obs = self.m.obs
        area = obs.goal_area
        if not any(area):  # (the usual case: nobody in a goal area)
            return None
        active, keeper, own = obs.active, obs.is_goalkeeper, obs.own_side  # (read for every robot)
        for i in range(obs.n):
            side = area[i]
            if not side or not active[i] or (keeper[i] and own[i] == side):
                continue
            depth = side * obs.X[i] - obs.field.area_limits("goal")[0]
            owner = obs.defender_of(side)
            whose = "its own" if obs.team_of[i] == owner else f"{owner}'s"
            return self.call(
                "goal_area",
                i,
                depth,
                0.0,
                f"{obs.names[i]} is in {whose} goal area ({depth:.3f} m inside the outer edge of its line), which only "
                f"{owner}'s goalkeeper may enter",
                restart=self.free_kick_against(i),
            )
        return None
