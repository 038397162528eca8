"""What the set-piece position rules share: the spot, the kicker, and a list of offenders judged once
when START is given (logged, play goes on) and then whenever a robot newly breaks the rule before the ball
is in play (the restart is retaken when the defending team did it, and the offender cautioned, FIFA Law 12;
the opponents get a free kick when the kicking team did). The referee retakes a restart at most
``max_retakes`` times in a row (`referee.MslReferee._enact`)."""

from __future__ import annotations

import math

from ..restarts import NAMES
from ..state import Phase
from .base import Call, Rule

_BEFORE_PLAY = (Phase.PREPARE, Phase.TAKING)  # (made once, read at every tick without the Enum's lookups)


class PositionRule(Rule):
    phases = frozenset({Phase.TAKING})
    kinds: frozenset[str] = frozenset()
    #: a robot whose infringement makes the restart be taken again is cautioned (FIFA Law 12: failing to
    #: respect the required distance at a restart; not a robot on the wrong side of the line at a kick-off).
    #: A dropped ball is in play at START: its distance is only logged
    cautions = False

    def __init__(self, match):
        super().__init__(match)
        self.flagged: set[int] = set()

    def applies(self) -> bool:
        r = self.m.game.restart
        return r is not None and r.kind in self.kinds and self.m.game.phase in _BEFORE_PLAY

    def spot_distances(self) -> list[float]:
        """Each robot's centre's distance from the restart spot."""
        r = self.m.game.restart
        obs = self.m.obs
        X, Y, x, y = obs.X, obs.Y, r.x, r.y
        return [math.hypot(X[i] - x, Y[i] - y) for i in range(obs.n)]

    def clearances(self, d: list[float]) -> list[float]:
        """How far each robot stays from the restart spot: from the nearest point of its footprint (its centre's
        distance less its radius). The MSL distances are circles round the ball that the robots must keep
        completely outside of."""
        radius = self.m.obs.radius
        return [d[i] - radius[i] for i in range(len(d))]

    def designated_kicker(self, d: list[float]) -> int:
        """The taker if it touched the ball already, else the kicking team's robot nearest to the spot."""
        m = self.m
        if m.touches.armed and m.touches.taker >= 0:
            return m.touches.taker
        team = m.game.restart.team
        if not team:
            return -1
        mates = [i for i in m.obs.members[team] if m.obs.active[i]]
        return min(mates, key=lambda i: d[i]) if mates else -1

    def offenders(self) -> list[tuple[int, float, float, str]]:
        """(robot, measured, limit, what) for every robot out of position now."""
        raise NotImplementedError

    def ready(self) -> bool:
        return not self.applies() or not self.offenders()

    def on_restart(self) -> None:
        self.flagged.clear()

    def at_start(self) -> list[Call]:
        if not self.applies():
            return []
        calls = []
        for i, value, limit, what in self.offenders():
            self.flagged.add(i)
            calls.append(self.call(self.name, i, value, limit, f"at START of the {self.what()}: {what}"))
        return calls

    def check(self) -> Call | None:
        if not self.applies():
            return None
        for i, value, limit, what in self.offenders():
            if i in self.flagged:
                continue
            self.flagged.add(i)
            r = self.m.game.restart
            obs = self.m.obs
            card = None
            if r.team and obs.team_of[i] == r.team:
                then = f"free kick for {obs.other(r.team)}"
                restart = self.m.spots.at_ball("free_kick", obs.other(r.team), r.x, r.y)
            else:
                then = f"the {self.what()} is taken again"
                restart = r
                if self.cautions and self.p.caution_distance_at_restarts:
                    # FIFA Law 12 (kept by MSL): failing to respect the required distance at a restart is
                    # cautioned; without it a team could stop the match by encroaching at every restart
                    card = "yellow"
                    then += f"; {obs.names[i]} is cautioned for not respecting the distance"
            return self.call(
                self.name, i, value, limit, f"before the ball was in play: {what}; {then}", restart=restart, card=card
            )
        return None

    def what(self) -> str:
        return NAMES[self.m.game.restart.kind]
