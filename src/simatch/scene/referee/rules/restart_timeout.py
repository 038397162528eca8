"""The 7 s rule (MSL RC-8.3, RC-13): a set piece must be kicked within ``restart_timeout`` of START. If it
is not, the ball is in play for everybody (the defending team may approach and play it; the kicking team
still may not score directly). A penalty kick not taken within ``penalty_kick_time`` ends with a goal kick.
This is not a foul: the event says what happened, the match goes on."""

from __future__ import annotations

from ..state import Phase
from .base import Call, Rule


class RestartTimeoutRule(Rule):
    name = "restart_timeout"
    phases = frozenset({Phase.TAKING})

    def check(self) -> Call | None:
        m = self.m
        r = m.game.restart
        if r is None:
            return None
        penalty = r.kind == "penalty"
        limit = self.p.penalty_kick_time if penalty else self.p.restart_timeout
        waited = m.game.phase_time
        if waited < limit - 1e-9:
            return None
        from ..restarts import NAMES

        what = NAMES[r.kind]
        if penalty:
            defending = m.obs.other(r.team)
            side = m.obs.own_goal_side(defending)
            return Call(
                "restart_timeout",
                team=r.team,
                x=r.x,
                y=r.y,
                value=waited,
                limit=limit,
                detail=f"{r.team} did not take the {what} within {limit:.1f} s: goal kick for {defending}",
                restart=m.spots.goal_kick(defending, side, r.y),
            )
        return Call(
            "restart_timeout",
            team=r.team,
            x=r.x,
            y=r.y,
            value=waited,
            limit=limit,
            detail=f"{r.team} did not take the {what} within {limit:.1f} s: the ball is in play for everybody",
            in_play=True,
        )
