"""A lob from the own half without the intent to pass (MSL RC-10.1.2, the lob rule): a team with at least
``lob_min_robots`` (3) robots on the field may not lob the ball from its own half, higher than
``lob_height`` (60 cm), to where no team-mate is within ``lob_mate_distance`` (3 m) when it lands. The
opponents get a free kick on the half-way line.

A lob is read from the flight of the ball, not from the kicker's lob flag: after any kick (the kicker
firing, from ``ball_contacts``) the rule follows the ball at the control period — its highest point (the
ball's underside) and where it first comes down, found by following the last observed flight to the
ground — until it lands. A flight that any robot touches (a team-mate taking it in the air, an opponent
blocking it), that leaves the field or ends in a goal is not judged: a pass was received or another rule
decides. "From the own half" is where the kicker's centre stood (as for the shooter, RC-10.1.1). The
kicker does not count as the team-mate near the landing point.
"""

from __future__ import annotations

import math

from ..state import LIVE
from .base import Call, Rule


class LobRule(Rule):
    name = "lob"
    phases = LIVE

    def __init__(self, match):
        super().__init__(match)
        self.seen_kick = -1  # step of the last kick already followed
        self.flight: dict | None = None

    def on_restart(self) -> None:
        self.flight = None
        k = self.m.touches.kick
        self.seen_kick = k[1] if k is not None else -1

    def check(self) -> Call | None:
        m = self.m
        obs, touches = m.obs, m.touches
        kick = touches.kick
        if kick is not None and kick[1] > self.seen_kick:
            i, step, x, y = kick
            self.seen_kick = step
            self.flight = {
                "kicker": i,
                "step": step,
                "x": x,
                "y": y,
                "own_half": not obs.in_opponent_half(i, x),
                "apex": 0.0,
                "prev": None,
                "airborne": False,
            }
        f = self.flight
        if f is None:
            return None
        if self._touched_since(f):
            self.flight = None
            return None
        r = obs.ball_radius
        height = obs.bz - r
        f["apex"] = max(f["apex"], height)
        prev = f["prev"]
        f["prev"] = (obs.bx, obs.by, obs.bz, obs.bvx, obs.bvy, obs.bvz)
        if height > 0.05:
            f["airborne"] = True
            if prev is None or not (prev[5] < 0.0 and obs.bvz > 0.0):
                return None  # still flying (or the bounce happened between two samples: land)
        elif not f["airborne"]:
            if prev is not None and math.hypot(obs.bx - f["x"], obs.by - f["y"]) > 1.5:
                self.flight = None  # a ground kick rolling away: no lob
            return None
        self.flight = None
        lx, ly = self._landing(prev) if prev is not None else (obs.bx, obs.by)
        return self._judge(f, lx, ly)

    def _touched_since(self, f: dict) -> bool:
        touches = self.m.touches
        if touches.contact_step <= f["step"]:
            return False
        gap = round(self.p.double_touch_gap / self.m.dt)
        return any(j != f["kicker"] or touches.contact_step - f["step"] > gap for j in touches.contact)

    def _landing(self, prev: tuple) -> tuple[float, float]:
        """Where the ball first came down, following the flight from the previous sample."""
        x, y, z, vx, vy, vz = prev
        g = self.m.gravity
        r = self.m.obs.ball_radius
        h = z - r
        if g <= 0.0 or h <= 0.0:
            return (x, y)
        t = (vz + math.sqrt(max(vz * vz + 2.0 * g * h, 0.0))) / g
        return (x + vx * t, y + vy * t)

    def _judge(self, f: dict, lx: float, ly: float) -> Call | None:
        m, p = self.m, self.p
        obs = m.obs
        i = f["kicker"]
        team = obs.team_of[i]
        on_field = [j for j in obs.members[team] if obs.active[j]]
        if not f["own_half"] or f["apex"] <= p.lob_height or len(on_field) < p.lob_min_robots:
            return None
        mates = [j for j in on_field if j != i]
        near = min((math.hypot(obs.X[j] - lx, obs.Y[j] - ly) for j in mates), default=math.inf)
        if near <= p.lob_mate_distance:
            return None
        other = obs.other(team)
        restart = m.spots.at_ball("free_kick", other, 0.0, ly)
        nearest = f"the nearest team-mate was {near:.2f} m away" if mates else "it had no team-mate on the field"
        call = self.call(
            "lob",
            i,
            near if mates else 0.0,
            p.lob_mate_distance,
            f"{obs.names[i]} lobbed the ball from its own half (x = {f['x']:.2f} m) {f['apex']:.2f} m "
            f"high (limit {p.lob_height:.2f} m); it landed at ({lx:.2f}, {ly:.2f}) where {nearest} "
            f"(at most {p.lob_mate_distance:.2f} m for a pass): free kick for {other} on the half-way "
            f"line",
            restart=restart,
        )
        call.x, call.y = f["x"], f["y"]
        return call
