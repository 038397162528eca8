"""Robots of opposite teams in contact, derived from the model states once per control period.

The contact rules (charging, pushing, touching the goalkeeper) share one reading, so every rule sees the
same contacts and the pairs are scanned once: two robots of opposite teams touch when their centres are
closer than their footprint radii plus ``contact_margin``. No simulator internals are used, so a replayed
recording is judged the same way as a live run.

Speeds towards the other robot are taken as the larger of this period's and the last one's, because the
impact itself slows the robot that drove in.

One contact, one call: a rule that calls a foul on a contact marks its pair (`mark_called`), and the contact
rules that judge a contact once (charging, touching the goalkeeper) do not judge a marked pair again while
the contact lasts, through stoppages too: robots still touching when play resumes after the foul are not
called a second time.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from .observation import Observation


class Contact(NamedTuple):
    pair: int  # index of the pair (stable for the match)
    i: int  # the robots, i < j
    j: int
    ux: float  # unit vector from i to j
    uy: float
    new: bool  # the contact began this control period


class RobotContacts:
    def __init__(self, obs: Observation, margin: float):
        self.obs = obs
        t = obs.team_ix
        self.pairs = [
            (i, j, obs.radius[i] + obs.radius[j] + margin)
            for i in range(obs.n)
            for j in range(i + 1, obs.n)
            if t[i] != t[j]
        ]
        self._rows = [(k, i, j, reach) for k, (i, j, reach) in enumerate(self.pairs)]  # (the loop's order)
        self.touching = [False] * len(self.pairs)
        self.called: set[int] = set()  # pairs whose contact (still going on) a rule has called already
        self.prev_vx = [0.0] * obs.n
        self.prev_vy = [0.0] * obs.n
        self._vx = [0.0] * obs.n
        self._vy = [0.0] * obs.n
        self.now: list[Contact] = []

    def update(self) -> None:
        """Read the contacts of this control period (call once, after the observation's refresh)."""
        obs = self.obs
        X, Y, active, touching = obs.X, obs.Y, obs.active, self.touching
        self.prev_vx, self._vx = self._vx, self.prev_vx
        self.prev_vy, self._vy = self._vy, self.prev_vy
        self._vx[:] = obs.VX
        self._vy[:] = obs.VY
        now = []
        for k, i, j, reach in self._rows:
            dx = X[j] - X[i]
            if dx > reach or -dx > reach:  # (the usual case: apart along x)
                if touching[k]:
                    touching[k] = False
                continue
            dy = Y[j] - Y[i]
            dist = math.hypot(dx, dy)
            on = dist <= reach and active[i] and active[j] and dist > 1e-9
            if on:
                now.append(Contact(k, i, j, dx / dist, dy / dist, not touching[k]))
            touching[k] = on
        self.now = now
        if self.called:
            self.called.intersection_update(c.pair for c in now)

    def mark_called(self, pair: int) -> None:
        """A rule called a foul on this contact: it is not judged again while it lasts."""
        self.called.add(pair)

    def approach(self, i: int, ux: float, uy: float) -> float:
        """Robot i's speed along (ux, uy): the larger of this period's and the last one's [m/s]."""
        obs = self.obs
        return max(obs.VX[i] * ux + obs.VY[i] * uy, self.prev_vx[i] * ux + self.prev_vy[i] * uy)

    def speed_along(self, i: int, ux: float, uy: float) -> float:
        """Robot i's speed along (ux, uy) this period [m/s]."""
        obs = self.obs
        return obs.VX[i] * ux + obs.VY[i] * uy
