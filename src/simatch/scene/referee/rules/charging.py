"""Charging (MSL RC-12.3.2): contact itself is no foul, but a robot must not drive into an opponent at
speed. Robot contacts are derived from the model states (`contacts.py`). At the first control period of a
contact, each robot's speed towards the other is measured; the robot that drove in faster than
``charging_speed``, and faster than the other by ``charging_margin``, charged. Two robots running into
each other alike is nobody's foul.

A charge gives the opponents a free kick where the ball is (a penalty kick when the charger was a defender
in its own penalty area and ``penalty_for_fouls_in_area``), and ``charging_card``; above
``charging_red_speed`` it is ramming, a red card. During a stoppage the foul and the card stand, the
restart does not change.
"""

from __future__ import annotations

from ..state import Phase
from .base import Call, Rule


class ChargingRule(Rule):
    name = "charging"
    phases = frozenset({Phase.STOPPED, Phase.PREPARE, Phase.TAKING, Phase.PLAY})

    def check(self) -> list[Call] | None:
        calls = None
        contacts = self.m.contacts
        for c in contacts.now:
            if c.new:
                call = self._judge(c.i, c.j, c.ux, c.uy)
                if call is not None:
                    contacts.mark_called(c.pair)  # one contact, one call (see contacts.py)
                    calls = (calls or []) + [call]
        return calls

    def _judge(self, i: int, j: int, ux: float, uy: float) -> Call | None:
        p = self.p
        approach = self.m.contacts.approach
        vi = approach(i, ux, uy)  # i towards j
        vj = approach(j, -ux, -uy)  # j towards i
        if vi >= vj:
            charger, victim, speed, other = i, j, vi, vj
        else:
            charger, victim, speed, other = j, i, vj, vi
        if speed < p.charging_speed or speed - other < p.charging_margin:
            return None
        obs = self.m.obs
        ramming = p.charging_red_speed is not None and speed > p.charging_red_speed
        card = "red" if ramming else p.charging_card
        restart, then = self.foul_restart(charger)
        what = "rammed" if ramming else "charged"
        return self.call(
            "charging",
            charger,
            speed,
            p.charging_red_speed if ramming else p.charging_speed,
            f"{obs.names[charger]} {what} {obs.names[victim]} at {speed:.2f} m/s (the other drove in "
            f"at {max(other, 0.0) + 0.0:.2f} m/s; limit {p.charging_speed:.2f} m/s): {then}"
            + (f", {card} card" if card else ""),
            restart=restart,
            card=card,
        )
