"""What one robot knows at one control tick, distilled from its WorldModel into plain floats.

Everything comes from the robot's own topics: its perception (ball, obstacles, its team), its team's
fused StrategyInfo (teammates' roles and passes) and the game command. Opponents are the obstacles that
are not one of the team's robots.
"""

from __future__ import annotations

import math
from itertools import chain
from operator import is_

import numpy as np

from ..worldmodel import WorldModel

#: an obstacle this close to a teammate is that teammate [m]
_SAME_ROBOT = 0.1


class Mate:
    """One robot of my team (me included), team frame."""

    __slots__ = (
        "id",
        "x",
        "y",
        "yaw",
        "vx",
        "vy",
        "w",
        "holding",
        "valid",
        "stuck",
        "role",
        "action",
        "pass_info",
        "is_goalie",
        "attacking",
        "role_time",
    )

    def __init__(
        self,
        info,
        is_goalie: bool,
        role: int = -1,
        action: int = -1,
        pass_info=None,
        attacking: int = -1,
        role_time: float = 1e9,
    ):
        self.id = info.id
        self.x, self.y, self.yaw = info.x, info.y, info.yaw
        self.vx, self.vy, self.w = info.vx, info.vy, info.w
        self.holding = info.holding_ball
        self.valid = info.valid
        self.stuck = info.stuck
        self.role = role  # as the robot announced it last (StrategyInfo), -1 if unknown
        self.action = action
        self.pass_info = pass_info
        self.is_goalie = is_goalie
        self.attacking = attacking  # whether its team picture said "we attack" last tick (1/0), -1 if unknown
        self.role_time = role_time  # how long it has had its announced role [s]

    def key(self) -> tuple:
        return (self.id, self.x, self.y, self.yaw, self.vx, self.vy, self.holding, self.valid, self.role)


class TeamView:
    """The part of an observation that every robot of the team shares (its team's RobotInfo list and
    StrategyInfo messages): built once per tick by the first robot of the team in this process, reused by
    the others when they hold the very same messages."""

    __slots__ = ("tick", "robots", "infos", "mates", "by_id", "array", "spots", "opps", "opp_array")

    def __init__(self):
        self.tick = -1
        self.robots = None
        self.infos: tuple = ()
        self.mates: list[Mate] = []
        self.by_id: dict[int, Mate] = {}
        self.array = np.zeros((0, 5))  # (K, 5): x, y, vx, vy, id of every team-mate, for kernels
        self.spots: set = set()  # where the team-mates are, to tell them among obstacles
        # the last opponents' array built from this view, reused by a robot that sees the same opponents
        self.opps: list = []
        self.opp_array = _array(self.opps, 4)

    def get(self, world: WorldModel) -> tuple[list[Mate], dict[int, Mate], np.ndarray]:
        robots = world.vision.robots
        strategies = world.strategies
        infos = self.infos
        if (
            self.tick == world.tick
            and self.robots is robots
            and len(infos) == len(strategies)
            and all(map(is_, infos, strategies.values()))
        ):
            return self.mates, self.by_id, self.array
        gk = world.goalkeeper
        mates = []
        told = strategies.get
        for r in robots:
            s = told(r.id)
            if s is None:
                mates.append(Mate(r, r.id == gk))
                continue
            user = s.user.tolist()
            attacking, role_time = (int(user[0]), user[1]) if len(user) >= 2 else (-1, 1e9)
            pass_cmd = s.pass_cmd
            mates.append(
                Mate(r, r.id == gk, s.role, s.action, pass_cmd if pass_cmd.is_valid else None, attacking, role_time)
            )
        self.tick, self.robots, self.infos = world.tick, robots, tuple(strategies.values())
        self.mates, self.by_id = mates, {m.id: m for m in mates}
        self.array = _array([(m.x, m.y, m.vx, m.vy, m.id) for m in mates], 5)
        self.spots = {(m.x, m.y) for m in mates}
        return self.mates, self.by_id, self.array


class Observation:
    __slots__ = (
        "t",
        "tick",
        "me",
        "mates",
        "by_id",
        "mate_array",
        "bx",
        "by",
        "bz",
        "bvx",
        "bvy",
        "bvz",
        "ball_seen",
        "ball_age",
        "opps",
        "_opp_array",
        "_view",
        "mode",
        "mtype",
        "coach",
        "goalie_id",
    )

    def __init__(self, world: WorldModel, view: TeamView | None = None):
        v = world.vision
        self.t = world.time
        self.tick = world.tick
        self.goalie_id = world.goalkeeper
        view = view or TeamView()
        self._view = view
        mates, by_id, self.mate_array = view.get(world)
        me = by_id.get(world.id)
        if me is None:
            raise LookupError(f"robot {world.id} is missing from its own perception")
        self.me = me
        self.mates = mates
        self.by_id = by_id
        b = v.ball if v.ball.pos_known else world.ball
        if b is None:
            self.bx = self.by = self.bvx = self.bvy = self.bvz = 0.0
            self.bz = 0.11
            self.ball_seen = False
            self.ball_age = math.inf
        else:
            self.bx, self.by, self.bz = b.x, b.y, b.z
            self.bvx, self.bvy, self.bvz = b.vx, b.vy, b.vz
            self.ball_seen = b is v.ball
            self.ball_age = 0.0 if self.ball_seen else b.age
        self.opps = opponents(v.obstacles, mates, view.spots)
        self._opp_array = None
        c = world.coach
        self.coach = c
        self.mode = c.match_mode if c is not None else 0
        self.mtype = c.match_type if c is not None else 0

    @property
    def opp_array(self) -> np.ndarray:
        """(M, 4): the opponents as an array (x, y, vx, vy), for kernels."""
        arr = self._opp_array
        if arr is None:
            view, opps = self._view, self.opps
            if view.opps == opps:
                arr = view.opp_array  # a team-mate in this process saw the same opponents
            else:
                arr = _array(opps, 4)
                view.opps, view.opp_array = opps, arr
            self._opp_array = arr
        return arr

    @property
    def ball_speed(self) -> float:
        return math.hypot(self.bvx, self.bvy)

    def field_mates(self) -> list[Mate]:
        """Valid team-mates that are not the goalkeeper, me included."""
        return [m for m in self.mates if m.valid and not m.is_goalie]


def _array(rows: list[tuple], width: int) -> np.ndarray:
    """(len(rows), width) float array of equal-length tuples of numbers: the values of
    ``np.array(rows, dtype=float)``, built faster for a handful of rows. (Shared between the robots of a
    team in one process: read it, never write it.)"""
    return np.fromiter(chain.from_iterable(rows), float, width * len(rows)).reshape(-1, width)


def opponents(o, mates: list[Mate], spots: set) -> list[tuple[float, float, float, float]]:
    """(x, y, vx, vy) of the obstacles that are not team-mates. With exact perception a team-mate's
    obstacle is exactly where the team list puts it; otherwise (noise) anything within _SAME_ROBOT of one."""
    n = len(o.x)
    if n == 0:
        return []
    x, y, vx, vy = o.x.tolist(), o.y.tolist(), o.vx.tolist(), o.vy.tolist()
    rest = [(x[k], y[k], vx[k], vy[k]) for k in range(n) if (x[k], y[k]) not in spots]
    if n - len(rest) < len(mates) - 1:
        # some team-mates are not where the team list says (noisy perception): match by distance
        rest = [q for q in rest if all(abs(m.x - q[0]) >= _SAME_ROBOT or abs(m.y - q[1]) >= _SAME_ROBOT for m in mates)]
    return rest
