"""Illegal defence and attack, penalty area (MSL RC-12.3.4/5): besides the defending goalkeeper, at most
``penalty_area_robots`` (1) robot of each team may be in a penalty area, and for at most
``penalty_area_time`` (10 s).

A robot is inside when its centre is on the area's painted lines (up to their outer edge: the lines belong
to the area) or inside them (behind the goal line included). The time counts only while the ball is in play
and starts again when the robot leaves the area. Who is in the area is followed while the ball is dead too
(nothing is called then): a robot that leaves the area during a stoppage and comes back starts a new stay,
and the last robot to enter is known when play resumes. The robot that made the area too crowded (the last
to enter) or stayed too long commits the foul; the opponents get a free kick.
"""

from __future__ import annotations

from ..state import Phase
from .base import Call, Rule

_PLAY = Phase.PLAY  # (a global, read at every tick without the Enum metaclass's attribute lookup)


class PenaltyAreaRule(Rule):
    name = "penalty_area"
    phases = frozenset({Phase.STOPPED, Phase.PREPARE, Phase.TAKING, Phase.PLAY})

    def __init__(self, match):
        super().__init__(match)
        n = match.obs.n
        self.inside = [0] * n  # side of the area each robot is counted in (0: none)
        self.time_in = [0.0] * n  # seconds inside while the ball was in play
        self.entered = [0] * n  # step it entered
        self.dt = match.control_dt

    def check(self) -> Call | None:
        obs = self.m.obs
        play = self.m.game.phase is _PLAY
        area, inside, time_in = obs.penalty_area, self.inside, self.time_in
        active, keeper, own = obs.active, obs.is_goalkeeper, obs.own_side  # (read for every robot, every tick)
        groups: dict[tuple[int, int], list[int]] = {}
        for i in range(obs.n):
            side = area[i] if active[i] else 0
            if not side and not inside[i]:
                continue  # outside, and counted outside already: nothing to follow (most robots)
            if side and keeper[i] and own[i] == side:
                side = 0  # the defending goalkeeper is not counted
            if side != inside[i]:
                inside[i] = side
                time_in[i] = 0.0
                self.entered[i] = obs.step
            if side:
                if play:
                    time_in[i] += self.dt
                groups.setdefault((side, obs.team_ix[i]), []).append(i)
        if not play:
            return None  # the ball is dead: followed, not judged
        for (side, _), robots in groups.items():
            call = self._judge(side, robots)
            if call is not None:
                return call
        return None

    def _judge(self, side: int, robots: list[int]) -> Call | None:
        obs, p = self.m.obs, self.p
        owner = obs.defender_of(side)
        if len(robots) > p.penalty_area_robots:
            i = max(robots, key=lambda j: (self.entered[j], j))
            where = "its own" if obs.team_of[i] == owner else f"{owner}'s"
            others = ", ".join(obs.names[j] for j in robots if j != i)
            self.time_in[i] = 0.0
            return self.call(
                "penalty_area_crowded",
                i,
                len(robots),
                p.penalty_area_robots,
                f"{obs.names[i]} entered {where} penalty area where {others} already was "
                f"({len(robots)} robots of {obs.team_of[i]}, limit {p.penalty_area_robots} besides "
                f"the goalkeeper)",
                restart=self.free_kick_against(i),
            )
        for i in robots:
            spent = self.time_in[i]
            if spent > p.penalty_area_time + 1e-9:
                where = "its own" if obs.team_of[i] == owner else f"{owner}'s"
                self.time_in[i] = 0.0
                return self.call(
                    "penalty_area_time",
                    i,
                    spent,
                    p.penalty_area_time,
                    f"{obs.names[i]} stayed {spent:.2f} s in {where} penalty area (limit {p.penalty_area_time:.1f} s)",
                    restart=self.free_kick_against(i),
                )
        return None
