"""Cards and sending off (MSL RC-12.6, the MSL RefBox and the 2020 Simatch rules).

A yellow card is counted per robot; every ``yellow_cards_for_send_off``-th one (the second, in MSL) sends
the robot off for ``yellow_send_off_time``. A red card sends it off for ``red_send_off_time`` (the rest of
the match by default). A robot sent off is parked outside the field, beside the side line in its own half,
and disabled (it ignores its commands and the rules ignore it); when its time is up it comes back at the
next stoppage (robots may re-enter only when the ball is dead), just inside the side line in its own half.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .observation import Observation
from .params import RefereeParams


class Discipline:
    def __init__(self, obs: Observation, params: RefereeParams, world, log: Callable[..., object]):
        self.obs = obs
        self.p = params
        self.world = world
        self.log = log  # log(type, i, value, limit, detail, at=None): at the robot, or at ``at`` (x, y)
        n = obs.n
        self.yellow = np.zeros(n, dtype=np.int64)
        self.red = np.zeros(n, dtype=np.int64)
        self.off_until: dict[int, float] = {}  # robot -> time it may return (inf: not by itself)
        f = obs.field
        self._team_slot = [obs.members[obs.team_of[i]].index(i) for i in range(n)]
        self._park_y = -(f.half_width + max(0.5 * f.margin, max(obs.radius) + 0.05))

    # --- cards -------------------------------------------------------------------------------------------
    def card(self, i: int, colour: str, now: float, why: str) -> None:
        name = self.obs.names[i]
        if colour == "yellow":
            self.yellow[i] += 1
            k = int(self.yellow[i])
            self.log("yellow_card", i, k, self.p.yellow_cards_for_send_off, f"yellow card for {name}: {why}")
            if k % self.p.yellow_cards_for_send_off == 0:
                self.send_off(i, now, self.p.yellow_send_off_time, f"{name}'s yellow card number {k}")
        elif colour == "red":
            self.red[i] += 1
            self.log("red_card", i, int(self.red[i]), 0, f"red card for {name}: {why}")
            self.send_off(i, now, self.p.red_send_off_time, f"{name}'s red card", "for the rest of the match")
        else:
            raise ValueError(f"a card is 'yellow' or 'red', not {colour!r}")

    # --- off and back ---------------------------------------------------------------------------------------
    def send_off(self, i: int, now: float, seconds: float | None, why: str, forever: str = "until returned") -> None:
        """Park robot i outside the field and disable it for ``seconds`` (None: ``forever``)."""
        obs = self.obs
        until = math.inf if seconds is None else now + seconds
        if i in self.off_until:
            self.off_until[i] = max(self.off_until[i], until)
            return
        self.off_until[i] = until
        x, y = self.park(i)
        name = obs.names[i]
        self.world.set_enabled(name, False)
        obs.active[i] = False
        length = forever if seconds is None else f"for {seconds:g} s"
        self.log(
            "send_off",
            i,
            0.0 if seconds is None else seconds,
            0.0,
            f"{name} sent off {length} ({why}); parked at ({x:.2f}, {y:.2f})",
        )

    def park(self, i: int) -> tuple[float, float]:
        """Place robot i at its park spot (beside the side line in its own half) and say where that is."""
        x, y = self.park_spot(i)
        self.world.set_model_state(self.obs.names[i], x=x, y=y, yaw=math.pi / 2, vx=0.0, vy=0.0, wz=0.0)
        return x, y

    def park_spot(self, i: int) -> tuple[float, float]:
        side = self.obs.own_goal_side(self.obs.team_of[i])
        return (side * (1.0 + 0.7 * self._team_slot[i]), self._park_y)

    def due(self, now: float) -> list[int]:
        """Robots whose time off is over."""
        return [i for i, until in self.off_until.items() if now >= until - 1e-9]

    def bring_back(self, i: int, why: str) -> None:
        obs = self.obs
        if i not in self.off_until:
            return
        del self.off_until[i]
        x, y = self.return_spot(i)
        name = obs.names[i]
        self.world.set_model_state(name, x=x, y=y, yaw=math.pi / 2, vx=0.0, vy=0.0, wz=0.0)
        self.world.set_enabled(name, True)
        obs.active[i] = True
        self.log(
            "robot_returned", i, 0.0, 0.0, f"{name} comes back on the field at ({x:.2f}, {y:.2f}) ({why})", at=(x, y)
        )

    def return_spot(self, i: int) -> tuple[float, float]:
        """Just inside the side line in the robot's own half, clear of every other robot and the ball."""
        obs = self.obs
        f = obs.field
        side = obs.own_goal_side(obs.team_of[i])
        y = -(f.half_width - 0.5)
        others = [j for j in range(obs.n) if obs.active[j]]
        for k in range(40):
            x = side * (1.0 + 0.7 * k)
            if abs(x) > f.half_length - 0.5:
                break
            clear = all(obs.distance_to(j, x, y) > 0.8 for j in others)
            if clear and math.hypot(obs.bx - x, obs.by - y) > 0.6:
                return (x, y)
        return (side * 1.0, y)

    @property
    def sent_off(self) -> list[int]:
        return sorted(self.off_until)

    def per_team(self, counts: np.ndarray) -> dict[str, int]:
        return {t: int(counts[self.obs.members[t]].sum()) for t in self.obs.teams}
