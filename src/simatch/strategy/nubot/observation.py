"""What one robot knows at one control tick, distilled from its WorldModel into plain floats.

Everything comes from the robot's own topics: its perception (ball, obstacles, its team), its team's
fused StrategyInfo (teammates' roles and passes) and the game command. Opponents are the obstacles that
are not one of the team's robots.
"""

from __future__ import annotations

import math

from ..worldmodel import WorldModel

#: an obstacle this close to a teammate is that teammate [m]
_SAME_ROBOT = 0.1


class Mate:
    """One robot of my team (me included), team frame."""

    __slots__ = ("id", "x", "y", "yaw", "vx", "vy", "w", "holding", "valid", "stuck", "role", "action",
                 "pass_info", "is_goalie")

    def __init__(self, info, is_goalie: bool):
        self.id = info.id
        self.x, self.y, self.yaw = info.x, info.y, info.yaw
        self.vx, self.vy, self.w = info.vx, info.vy, info.w
        self.holding = info.holding_ball
        self.valid = info.valid
        self.stuck = info.stuck
        self.role = -1           # as the robot announced it last (StrategyInfo), -1 if unknown
        self.action = -1
        self.pass_info = None
        self.is_goalie = is_goalie

    def key(self) -> tuple:
        return (self.id, self.x, self.y, self.yaw, self.vx, self.vy, self.holding, self.valid, self.role)


class Observation:
    __slots__ = ("t", "tick", "me", "mates", "by_id", "bx", "by", "bz", "bvx", "bvy", "bvz", "ball_seen",
                 "ball_age", "opps", "mode", "mtype", "coach", "goalie_id")

    def __init__(self, world: WorldModel):
        v = world.vision
        self.t = world.time
        self.tick = world.tick
        gk = world.goalkeeper
        self.goalie_id = gk
        strategies = world.strategies
        mates = []
        me = None
        for r in v.robots:
            m = Mate(r, r.id == gk)
            s = strategies.get(r.id)
            if s is not None:
                m.role, m.action = s.role, s.action
                if s.pass_cmd.is_valid:
                    m.pass_info = s.pass_cmd
            if r.id == world.id:
                me = m
            mates.append(m)
        if me is None:
            raise LookupError(f"robot {world.id} is missing from its own perception")
        self.me = me
        self.mates = mates
        self.by_id = {m.id: m for m in mates}
        b = world.ball
        if b is None:
            self.bx = self.by = self.bvx = self.bvy = self.bvz = 0.0
            self.bz = 0.11
            self.ball_seen = False
            self.ball_age = math.inf
        else:
            self.bx, self.by, self.bz = b.x, b.y, b.z
            self.bvx, self.bvy, self.bvz = b.vx, b.vy, b.vz
            self.ball_seen = b.seen
            self.ball_age = b.age
        o = v.obstacles
        opps = []
        if len(o.x):
            xs, ys, vxs, vys = o.x.tolist(), o.y.tolist(), o.vx.tolist(), o.vy.tolist()
            for k in range(len(xs)):
                x, y = xs[k], ys[k]
                for m in mates:
                    if abs(m.x - x) < _SAME_ROBOT and abs(m.y - y) < _SAME_ROBOT:
                        break
                else:
                    opps.append((x, y, vxs[k], vys[k]))
        self.opps = opps
        c = world.coach
        self.coach = c
        self.mode = c.match_mode if c is not None else 0
        self.mtype = c.match_type if c is not None else 0

    @property
    def ball_speed(self) -> float:
        return math.hypot(self.bvx, self.bvy)

    def field_mates(self) -> list[Mate]:
        """Valid team-mates that are not the goalkeeper, me included."""
        return [m for m in self.mates if m.valid and not m.is_goalie]
