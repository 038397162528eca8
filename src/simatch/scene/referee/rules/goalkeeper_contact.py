"""Touching the goalkeeper in its goal area (MSL RC-12.3.5, illegal attack): while the goalkeeper's centre
is in its own goal area, an opponent may not come into contact with it.

Contacts come from `contacts.py`. A contact is judged once, when it begins (or when the goalkeeper enters
its goal area while the contact goes on): the attacker commits the foul unless the goalkeeper drove into
it — the goalkeeper's speed towards the attacker greater than the attacker's towards the goalkeeper (a
goalkeeper coming out to an attacker that stands its ground is no foul by the attacker). The defending
team gets a free kick (placed at the restart spot of that half, as every free kick in a penalty area).

One contact, one call: a contact another rule has already called (an attacker charging the goalkeeper) is
not judged here, and contacts are followed while the ball is dead too (without calls), so that robots still
touching when play resumes are not judged as a new contact.
"""

from __future__ import annotations

from ..state import LIVE, Phase
from .base import Call, Rule

_TAKING, _PLAY = Phase.TAKING, Phase.PLAY  # LIVE's members as globals, compared by identity at every tick
assert LIVE == {_TAKING, _PLAY}


class GoalkeeperContactRule(Rule):
    name = "goalkeeper_contact"
    phases = frozenset({Phase.STOPPED, Phase.PREPARE, Phase.TAKING, Phase.PLAY})

    def __init__(self, match):
        super().__init__(match)
        self.judged: set[int] = set()  # contact pairs judged while they go on

    def check(self) -> Call | None:
        m = self.m
        obs, contacts = m.obs, m.contacts
        phase = m.game.phase
        live = phase is _TAKING or phase is _PLAY  # (in LIVE: by identity, with no Enum hash, at every tick)
        judged: set[int] = set()
        call = None
        for c in contacts.now:
            if c.pair in self.judged or c.pair in contacts.called:
                judged.add(c.pair)
                continue
            for keeper, attacker, ux, uy in ((c.i, c.j, c.ux, c.uy), (c.j, c.i, -c.ux, -c.uy)):
                if not obs.is_goalkeeper[keeper] or obs.goal_area[keeper] != obs.own_side[keeper]:
                    continue
                judged.add(c.pair)
                if not live:
                    continue  # the ball is dead: followed, not judged
                v_att = contacts.approach(attacker, -ux, -uy)  # attacker towards the keeper
                v_keep = contacts.approach(keeper, ux, uy)  # keeper towards the attacker
                if v_keep > v_att or call is not None:
                    continue
                call = self.call(
                    "goalkeeper_contact",
                    attacker,
                    max(v_att, 0.0),
                    max(v_keep, 0.0),
                    f"{obs.names[attacker]} touched {obs.names[keeper]}, the goalkeeper, in its goal area "
                    f"(driving in at {max(v_att, 0.0):.2f} m/s, the goalkeeper at {max(v_keep, 0.0):.2f} "
                    f"m/s): free kick for {obs.team_of[keeper]}",
                    restart=self.free_kick_against(attacker),
                )
                contacts.mark_called(c.pair)
        self.judged = judged
        return call
