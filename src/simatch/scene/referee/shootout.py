"""The penalty shoot-out (MSL rules, 2020 Simatch rules): ``shootout_kicks`` (5) kicks per team, taken in
turn (the team that kicked off the match first), each from the penalty mark against the other team's
goalkeeper; then rounds of sudden death, at most ``shootout_max_rounds``, after which a level shoot-out
ends drawn. It is decided as soon as one team cannot catch up.

A kick is scored when the ball enters the goal. It is missed when the ball leaves the field otherwise,
when a robot of the kicking team touches the ball after the kick (one touch only), or when it is not a
goal ``shootout_shot_time`` after START. Shoot-out goals do not change the match score.
"""

from __future__ import annotations

from .observation import Observation
from .params import RefereeParams
from .restarts import Restart, Spots


class ShootOut:
    def __init__(self, obs: Observation, params: RefereeParams, spots: Spots, first: str):
        self.obs = obs
        self.p = params
        self.spots = spots
        self.order = [first, obs.other(first)]
        self.kicks: dict[str, list[bool]] = {t: [] for t in obs.teams}

    @property
    def kicking(self) -> str:
        a, b = self.order
        return a if len(self.kicks[a]) <= len(self.kicks[b]) else b

    def next_restart(self) -> Restart:
        team = self.kicking
        return self.spots.penalty(team, self.obs.own_goal_side(self.obs.other(team)))

    def goals(self, team: str) -> int:
        return sum(self.kicks[team])

    def record(self, team: str, scored: bool) -> None:
        self.kicks[team].append(scored)

    def decided(self) -> bool:
        a, b = self.order
        n = self.p.shootout_kicks
        ka, kb = len(self.kicks[a]), len(self.kicks[b])
        ga, gb = self.goals(a), self.goals(b)
        if ka <= n and kb <= n:
            if ga + (n - ka) < gb or gb + (n - kb) < ga:
                return True  # one team can no longer catch up
            if ka < n or kb < n:
                return False
        if ka != kb:
            return False
        return ga != gb or ka >= n + self.p.shootout_max_rounds

    def winner(self) -> str | None:
        a, b = self.order
        ga, gb = self.goals(a), self.goals(b)
        return a if ga > gb else b if gb > ga else None

    def summary(self) -> dict:
        return {t: {"goals": self.goals(t), "kicks": len(self.kicks[t])} for t in self.obs.teams}
