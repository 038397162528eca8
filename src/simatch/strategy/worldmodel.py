"""The WorldModel of one robot: everything it knows, in its team frame (its team attacks +x).

It is fed only by topics: its own perception (OmniVisionInfo), its team's fused strategy picture
(TeamStrategy, from StrategyPub), the game command (CoachInfo on receive_from_coach) and the judge's public
picture of the game (GameState on game_state: stage, clock, the judge-specific result). A strategy reads it
and never touches the simulator.

The team frame is the world frame turned so that the team attacks +x. When the teams change ends (at half
time, in a refereed match), the GameState says which way each team attacks now (``attacks``) and the
WorldModel follows it (`sign`, `field`): a robot learns its new side from the game state, in one process or
in a distributed run alike. What it perceives and commands stays in the team frame, so a strategy still
attacks +x.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..field import Area, FieldGeometry


def team_field(field: FieldGeometry, sign: int) -> FieldGeometry:
    """The field as a team sees it: lines and goals are symmetric; named areas and obstacles are turned with
    the frame."""
    if sign > 0 or not (field.areas or field.obstacles):
        return field
    from dataclasses import replace

    areas = tuple(Area(a.name, -a.x1, -a.y1, -a.x0, -a.y0) for a in field.areas)
    return replace(field, areas=areas, obstacles=tuple(o.turned() for o in field.obstacles))


@dataclass
class Ball:
    """The ball as this robot knows it (team frame)."""

    x: float
    y: float
    z: float
    vx: float
    vy: float
    vz: float
    angle: float  # bearing from my kicker axis [rad]
    distance: float  # from my centre [m]
    seen: bool  # seen in the latest observation (else: last known position)
    age: float  # seconds since it was last seen


class WorldModel:
    def __init__(self, team: str, rid: int, sign: int, field: FieldGeometry, goalkeeper: int | None):
        self.team = team
        self.id = rid
        self.sign = sign
        self._world_field = field
        self.field = team_field(field, sign)
        self.goalkeeper = goalkeeper
        self.vision = None  # latest OmniVisionInfo
        self.coach = None  # latest CoachInfo
        self.game = None  # latest GameState from the judge (None if it publishes none)
        self.team_strategy = None  # latest TeamStrategy (the team's fused StrategyInfo)
        self._strategies: dict | None = {}
        self.time = 0.0
        self.tick = 0
        self._ball: Ball | None = None
        self._me = None  # my RobotInfo in the latest observation (found on first use)
        self._last_ball = None  # the BallInfo of the last observation that saw the ball
        self._last_seen = -math.inf

    # --- inputs (bus callbacks) -------------------------------------------------------------------------
    def on_vision(self, msg) -> None:
        self.vision = msg
        self.time = msg.stamp
        self.tick = msg.tick
        if msg.ball.pos_known:
            self._last_seen = msg.stamp
            self._last_ball = msg.ball
        self._ball = None  # built on first use this tick
        self._me = None

    def on_team(self, msg) -> None:
        self.team_strategy = msg
        self._strategies = None  # made on first use (the robots of a team share the message)

    @property
    def strategies(self) -> dict:
        """Teammate id -> latest StrategyInfo (from the team picture)."""
        found = self._strategies
        if found is None:
            found = self._strategies = {}
            for s in self.team_strategy.strategies:
                found[s.agent_id] = s
        return found

    @strategies.setter
    def strategies(self, value: dict) -> None:
        self._strategies = value

    def on_coach(self, msg) -> None:
        self.coach = msg

    def on_game(self, msg) -> None:
        self.game = msg
        attacks = msg.attacks
        if attacks and self.team in msg.teams:
            k = list(msg.teams).index(self.team)
            if k < len(attacks):
                sign = -1 if attacks[k] == "-x" else 1
                if sign != self.sign:
                    self.sign = sign
                    self.field = team_field(self._world_field, sign)

    # --- what a strategy reads ---------------------------------------------------------------------------
    @property
    def ready(self) -> bool:
        return self.vision is not None

    @property
    def me(self):
        """My RobotInfo (team frame)."""
        me = self._me
        if me is None:
            for r in self.vision.robots:
                if r.id == self.id:
                    self._me = r
                    return r
            raise LookupError(f"robot {self.id} is missing from its own perception")
        return me

    @property
    def teammates(self) -> list:
        """RobotInfo of the other robots of my team."""
        return [r for r in self.vision.robots if r.id != self.id]

    @property
    def robots(self) -> list:
        """RobotInfo of my whole team, me included."""
        return list(self.vision.robots)

    @property
    def ball(self) -> Ball | None:
        """The ball seen in the latest observation, else where it was last seen (not moving); None before
        it has ever been seen."""
        if self._ball is None and self.vision is not None:
            b = self.vision.ball
            if b.pos_known:
                self._ball = Ball(b.x, b.y, b.z, b.vx, b.vy, b.vz, b.angle, b.distance, True, 0.0)
            elif self._last_ball is not None:
                last, me = self._last_ball, self.me
                dx, dy = last.x - me.x, last.y - me.y
                self._ball = Ball(
                    last.x,
                    last.y,
                    last.z,
                    0.0,
                    0.0,
                    0.0,
                    math.remainder(math.atan2(dy, dx) - me.yaw, 2 * math.pi),
                    math.hypot(dx, dy),
                    False,
                    self.time - self._last_seen,
                )
        return self._ball

    @property
    def obstacles(self) -> np.ndarray:
        """(K, 4): x, y, vx, vy of every other robot I see (team frame), as float64 (the perception's
        float32 numbers, exactly)."""
        o = self.vision.obstacles
        return np.stack((o.x, o.y, o.vx, o.vy), axis=1).astype(np.float64) if len(o.x) else np.zeros((0, 4))

    @property
    def opponents(self) -> np.ndarray:
        """Obstacles that are not one of my teammates (farther than 0.1 m from every teammate)."""
        obs = self.obstacles
        mates = self.teammates
        if not len(obs) or not mates:
            return obs
        mx = np.array([[r.x, r.y] for r in mates])
        d = np.hypot(obs[:, None, 0] - mx[None, :, 0], obs[:, None, 1] - mx[None, :, 1])
        return obs[d.min(axis=1) > 0.1]

    @property
    def match_mode(self) -> int:
        return self.coach.match_mode if self.coach is not None else 0

    @property
    def match_type(self) -> int:
        return self.coach.match_type if self.coach is not None else 0

    @property
    def is_goalkeeper(self) -> bool:
        return self.goalkeeper is not None and self.id == self.goalkeeper
