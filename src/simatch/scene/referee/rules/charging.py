"""Charging (MSL RC-12.3.2): contact itself is no foul, but a robot must not drive into an opponent at
speed. Robot contacts are derived from the model states (no simulator internals): two robots of opposite
teams touch when their centres are closer than their footprint radii plus ``contact_margin``. At the
first control period of a contact, each robot's speed towards the other is measured (the larger of this
period's and the last one's, since the impact itself slows it); the robot that drove in faster than
``charging_speed``, and faster than the other by ``charging_margin``, charged. Two robots running into
each other alike is nobody's foul.

A charge gives the opponents a free kick where the ball is (a penalty kick when the charger was a defender
in its own penalty area and ``penalty_for_fouls_in_area``), and ``charging_card``; above
``charging_red_speed`` it is ramming, a red card. During a stoppage the foul and the card stand, the
restart does not change.
"""

from __future__ import annotations

import math
from typing import Optional

from ..state import LIVE, Phase
from .base import Call, Rule


class ChargingRule(Rule):
    name = "charging"
    phases = frozenset({Phase.STOPPED, Phase.PREPARE, Phase.TAKING, Phase.PLAY})

    def __init__(self, match):
        super().__init__(match)
        obs = match.obs
        t = obs.team_ix
        self.pairs = [(i, j, obs.radius[i] + obs.radius[j] + self.p.contact_margin)
                      for i in range(obs.n) for j in range(i + 1, obs.n) if t[i] != t[j]]
        self.touching = [False] * len(self.pairs)
        self.prev_vx = [0.0] * obs.n
        self.prev_vy = [0.0] * obs.n

    def check(self) -> Optional[list[Call]]:
        obs = self.m.obs
        X, Y, active, touching = obs.X, obs.Y, obs.active, self.touching
        calls = None
        for k, (i, j, reach) in enumerate(self.pairs):
            dx = X[j] - X[i]
            if dx > reach or -dx > reach:
                touching[k] = False
                continue
            dy = Y[j] - Y[i]
            dist = math.hypot(dx, dy)
            now = dist <= reach and active[i] and active[j]
            if now and not touching[k] and dist > 1e-9:
                call = self._judge(i, j, dx / dist, dy / dist)
                if call is not None:
                    calls = (calls or []) + [call]
            touching[k] = now
        self.prev_vx[:] = obs.VX
        self.prev_vy[:] = obs.VY
        return calls

    def _approach(self, i: int, ux: float, uy: float) -> float:
        obs = self.m.obs
        return max(obs.VX[i] * ux + obs.VY[i] * uy, self.prev_vx[i] * ux + self.prev_vy[i] * uy)

    def _judge(self, i: int, j: int, ux: float, uy: float) -> Optional[Call]:
        p = self.p
        vi = self._approach(i, ux, uy)          # i towards j
        vj = self._approach(j, -ux, -uy)        # j towards i
        if vi >= vj:
            charger, victim, speed, other = i, j, vi, vj
        else:
            charger, victim, speed, other = j, i, vj, vi
        if speed < p.charging_speed or speed - other < p.charging_margin:
            return None
        m = self.m
        obs = m.obs
        ramming = p.charging_red_speed is not None and speed > p.charging_red_speed
        card = "red" if ramming else p.charging_card
        restart = None
        then = "the ball is not in play: the restart stands"
        if m.game.phase in LIVE:
            team = obs.team_of[charger]
            if p.penalty_for_fouls_in_area and obs.penalty_area[charger] == obs.own_side[charger]:
                restart = m.spots.penalty(obs.other(team), obs.own_side[charger])
                then = f"penalty kick for {obs.other(team)}"
            else:
                restart = self.free_kick_against(charger)
                then = f"free kick for {obs.other(team)}"
        what = "rammed" if ramming else "charged"
        return self.call("charging", charger, speed, p.charging_red_speed if ramming else p.charging_speed,
                         f"{obs.names[charger]} {what} {obs.names[victim]} at {speed:.2f} m/s (the other drove in "
                         f"at {max(other, 0.0) + 0.0:.2f} m/s; limit {p.charging_speed:.2f} m/s): {then}"
                         + (f", {card} card" if card else ""), restart=restart, card=card)
