"""Pushing (MSL RC-12.3.2): contact itself is no foul, but a robot that touches an opponent must stop
driving in that direction and change direction; one that keeps driving into the opponent pushes it.
Charging (`charging.py`) judges the impact; this rule judges what comes after it.

In every control period of a contact (`contacts.py`) robot i *drives into* robot j when i moves towards j
at least ``pushing_speed`` and j is moved away from i at least as fast (it gives way: i is displacing it).
The displacement of j and the time are added up while this goes on without a break; the pusher has
pushed once j was moved ``pushing_distance`` (1 m) or for ``pushing_time`` (3 s) (the event's value and
limit are the distance, or the time when the time was the limit reached). The count ends when the
contact does or i stops driving into j. Two robots pressing against each other for the ball move neither,
so the ordinary duel is not pushing; a robot held still against a wall is not judged (the referee sees
motion, not forces).

A push gives the opponents a free kick where the ball is (a penalty kick when the pusher was a defender in
its own penalty area and ``penalty_for_fouls_in_area``), and ``pushing_card``.

A contact in which either robot is on the ball (the ball's centre within ``dribble_release_distance`` of
its centre, as for possession) is a duel for the ball, not judged here: in the matches of the default
team, a robot that presses a dribbler keeps in contact with it while the dribbler turns and drives away
with the ball (1 m in 1.5-2.5 s), and whether the dribbler gives way or drives away cannot be told from
motion. Charging is judged in duels as everywhere. During a stoppage the foul
stands, the restart does not change.
"""

from __future__ import annotations

from ..state import Phase
from .base import Call, Rule


class PushingRule(Rule):
    name = "pushing"
    phases = frozenset({Phase.STOPPED, Phase.PREPARE, Phase.TAKING, Phase.PLAY})

    def __init__(self, match):
        super().__init__(match)
        self.pushes: dict[tuple[int, int], list[float]] = {}  # (pusher, pushed) -> [distance, periods]

    def check(self) -> list[Call] | None:
        m, p = self.m, self.p
        contacts = m.contacts
        obs = m.obs
        on_ball = p.dribble_release_distance
        going: dict[tuple[int, int], list[float]] = {}
        calls = None
        for c in contacts.now:
            if obs.ball_distance(c.i) <= on_ball or obs.ball_distance(c.j) <= on_ball:
                continue  # a duel for the ball
            for a, b, ux, uy in ((c.i, c.j, c.ux, c.uy), (c.j, c.i, -c.ux, -c.uy)):
                drive = contacts.speed_along(a, ux, uy)
                moved = contacts.speed_along(b, ux, uy)
                if drive < p.pushing_speed or moved < p.pushing_speed:
                    continue
                acc = self.pushes.get((a, b), [0.0, 0])
                acc[0] += moved * m.control_dt
                acc[1] += 1
                going[(a, b)] = acc
                if acc[0] >= p.pushing_distance or acc[1] * m.control_dt >= p.pushing_time - 1e-9:
                    del going[(a, b)]
                    calls = (calls or []) + [self._call(a, b, acc[0], acc[1] * m.control_dt)]
        self.pushes = going
        return calls

    def _call(self, a: int, b: int, distance: float, seconds: float) -> Call:
        p = self.p
        obs = self.m.obs
        restart, then = self.foul_restart(a)
        card = p.pushing_card
        far = distance >= p.pushing_distance
        return self.call(
            "pushing",
            a,
            distance if far else seconds,
            p.pushing_distance if far else p.pushing_time,
            f"{obs.names[a]} kept driving into {obs.names[b]} and pushed it {distance:.2f} m in "
            f"{seconds:.2f} s (limits {p.pushing_distance:.2f} m, {p.pushing_time:.1f} s): {then}"
            + (f", {card} card" if card else ""),
            restart=restart,
            card=card,
        )
