"""The penalty shoot-out (MSL rules, 2020 Simatch rules): ``shootout_kicks`` (5) kicks per team, taken in
turn (the team that kicked off the match first), each from the penalty mark against the other team's
goalkeeper; then rounds of sudden death, at most ``shootout_max_rounds``, after which a level shoot-out
ends drawn. It is decided as soon as one team cannot catch up.

A kick is scored when the ball enters the goal. It is missed when the ball leaves the field otherwise,
when a robot of the kicking team touches the ball after the kick (one touch only), or when it is not a
goal ``shootout_shot_time`` after START. A foul does not restart play: the kicking team's misses the kick,
the defending team's has it taken again. Shoot-out goals do not change the match score.

`ShootOut` keeps the tally; `ShootOutKicks`, mixed into the referee, judges each kick.
"""

from __future__ import annotations

from .observation import Observation
from .params import RefereeParams
from .restarts import Restart, Spots
from .rules import Call


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


class ShootOutKicks:
    """Mixed into `MslReferee`: each kick of the shoot-out judged, its result logged, the next kick called."""

    def _shootout_check(self, now: float) -> None:
        """At the control period while a kick is taken: a second touch by the kicking team, or time up, is a
        miss."""
        m = self.m
        touches, obs, r = m.touches, m.obs, m.game.restart
        k = obs.teams.index(r.team)
        taker = touches.taker
        if touches.retouch is not None or any(i != taker for i in touches.touched_by(k)):
            self._shootout_result(now, False, "the kicking team touched the ball again")
        elif (self.ctx.step() - self._kick_step) * self.dt >= self.p.shootout_shot_time - 1e-9:
            self._shootout_result(now, False, f"no goal {self.p.shootout_shot_time:.0f} s after START")

    def _shootout_foul(self, now: float, call: Call) -> None:
        """A foul during a kick (already logged): the card stands; the kick is missed or taken again."""
        g = self.m.game
        if call.card and call.robot >= 0:
            self.discipline.card(call.robot, call.card, now, call.detail)
        if call.team == g.restart.team:
            self._shootout_result(
                now, False, f"{call.type} by {self.m.obs.names[call.robot]}" if call.robot >= 0 else call.type
            )
        else:
            self._stop(now, g.restart, f"{call.type}: the penalty is taken again")

    def _shootout_result(self, now: float, scored: bool, why: str) -> None:
        m = self.m
        so, r = self.shootout, m.game.restart
        so.record(r.team, scored)
        taker = m.touches.taker
        rid = m.obs.rid[taker] if taker >= 0 else 0
        tally = ", ".join(f"{t} {so.goals(t)}/{len(so.kicks[t])}" for t in self.teams)
        self._log(
            now,
            "shootout_kick",
            team=r.team,
            robot=rid,
            x=m.obs.bx,
            y=m.obs.by,
            value=1.0 if scored else 0.0,
            limit=1.0,
            detail=f"{r.team}'s penalty {'scored' if scored else 'missed'}: {why} (shoot-out: {tally})",
        )
        m.game.version += 1
        if so.decided():
            self._end_match(now)
        else:
            self._stop(now, so.next_restart(), "shoot-out: next kick")
