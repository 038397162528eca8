"""The targets: flee from the chasers, keep off walls and out of corners, keep apart (strategy ``flee``).

Each target decides from its own WorldModel: the chasers are the opponents it perceives. Its wish is a sum
of pushes, each a direction times a weight that grows as the thing pushing comes nearer:

* away from every chaser within ``sense_radius`` (weight 1/d - 1/sense_radius, so the nearest dominate);
* away from each wall within ``wall_margin`` and from each corner within ``corner_radius`` (a cornered
  target is a caught target);
* away from free team-mates within ``separation`` (a flock is easier to round up);

and it moves along that wish at a speed set by its nearest chaser: full ``max_speed`` within
``panic_radius``, less further out, still when no chaser is in sight. A wish that points into a wall
slides along it. While fleeing it jinks: the direction turns by a random angle, drawn from the run's seed,
that changes every ``jink_period``. A captured target (the judge says so on ``game_state``) stands still.
"""

from __future__ import annotations

import math

from pydantic import BaseModel, ConfigDict, Field

from ...msgs.game_commands import MatchMode
from ..base import Command, RobotContext, RobotStrategy
from .game import Captures
from .net import Arena
from .view import opponents

#: with no chaser in sight, pushes weaker than this leave a target at rest (it does not creep for ever)
RESTFUL = 0.1


class TargetParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    max_speed: float = Field(2.45, gt=0.0, le=10.0, description="speed cap of a target [m/s]")
    sense_radius: float = Field(4.0, gt=0.0, le=50.0, description="chasers nearer than this are fled from [m]")
    panic_radius: float = Field(2.5, gt=0.0, le=50.0, description="a chaser nearer than this: full speed [m]")
    wall_margin: float = Field(1.0, gt=0.0, le=10.0, description="walls nearer than this push away [m]")
    corner_radius: float = Field(2.5, gt=0.0, le=20.0, description="corners nearer than this push away [m]")
    separation: float = Field(1.0, ge=0.0, le=10.0, description="free team-mates nearer than this push away [m]")
    wall_weight: float = Field(0.6, ge=0.0, le=100.0, description="strength of the walls' push")
    corner_weight: float = Field(1.5, ge=0.0, le=100.0, description="strength of the corners' push")
    separation_weight: float = Field(0.8, ge=0.0, le=100.0, description="strength of the team-mates' push")
    idle_speed: float = Field(
        0.5, ge=0.0, le=10.0, description="speed for keeping apart and off the walls with no chaser in sight [m/s]"
    )
    jink: float = Field(0.35, ge=0.0, le=math.pi, description="spread of the random turn while fleeing [rad]")
    jink_period: float = Field(1.0, gt=0.0, le=60.0, description="how often the random turn changes [s]")
    wall_clearance: float = Field(
        0.25, ge=0.0, le=5.0, description="closest a target's centre comes to a wall (its radius) [m]"
    )


class Target(RobotStrategy):
    Params = TargetParams

    def __init__(self, ctx: RobotContext):
        super().__init__(ctx)
        arena = Arena.of(ctx.field, ctx.params.wall_clearance)
        self.half_x, self.half_y = arena.half_x, arena.half_y
        self.captures = Captures()
        self.name = f"{ctx.team}/{ctx.id}"
        self.jink_angle = 0.0
        self.jink_until = -math.inf

    def decide(self, world) -> Command:
        if world.match_mode == MatchMode.STOPROBOT:
            return Command()
        caps = self.captures.update(world)
        if self.name in caps.names:
            return Command()
        p = self.ctx.params
        me = world.me
        x, y = me.x, me.y
        # chasers
        flee_x = flee_y = 0.0
        nearest = math.inf
        sense = p.sense_radius
        for cx, cy in self.threats(world):
            dx, dy = x - cx, y - cy
            if abs(dx) < sense and abs(dy) < sense:
                d = max(math.hypot(dx, dy), 0.3)
                if d < sense:
                    w = (1.0 / d - 1.0 / sense) / d
                    flee_x += dx * w
                    flee_y += dy * w
                    nearest = min(nearest, d)
        norm = math.hypot(flee_x, flee_y)
        wish_x, wish_y = (flee_x / norm, flee_y / norm) if norm > 1e-9 else (0.0, 0.0)
        # walls and corners
        push_x, push_y = self._pushes(world, caps, x, y)
        fleeing = norm > 1e-9
        if fleeing:
            wish_x, wish_y = self._jinked(world.time, wish_x + push_x, wish_y + push_y)
            urgency = min(1.0, max(0.0, (p.sense_radius - nearest) / max(p.sense_radius - p.panic_radius, 1e-6)))
            speed = max(p.max_speed * urgency, p.idle_speed)
        else:
            wish_x, wish_y = push_x, push_y
            push = math.hypot(push_x, push_y)
            speed = p.idle_speed * min(1.0, push) if push > RESTFUL else 0.0
        wish_x, wish_y = self._slide(x, y, wish_x, wish_y)
        n = math.hypot(wish_x, wish_y)
        if n < 1e-9 or speed <= 0.0:
            return Command()
        vx, vy = wish_x / n * speed, wish_y / n * speed
        c, s = math.cos(me.yaw), math.sin(me.yaw)
        return Command(vx=c * vx + s * vy, vy=-s * vx + c * vy, w=0.0, intent=(x + vx, y + vy))

    # --- what a variant may change (see simatch.strategy.aerial) -------------------------------------------
    def threats(self, world) -> list[tuple[float, float]]:
        """The chasers to flee from (team frame): every opponent I perceive."""
        return opponents(world)

    # --- pushes -------------------------------------------------------------------------------------------
    def _pushes(self, world, caps: Captures, x: float, y: float) -> tuple[float, float]:
        """The sum of the walls', corners' and free team-mates' pushes."""
        px, py = self._walls(x, y)
        cx, cy = self._corners(x, y)
        sx, sy = self._separation(world, caps, x, y)
        return px + cx + sx, py + cy + sy

    def _walls(self, x: float, y: float) -> tuple[float, float]:
        p = self.ctx.params
        m, k = p.wall_margin, p.wall_weight
        fx = fy = 0.0
        for gap, sign, axis in (
            (self.half_x - x, -1.0, 0),
            (self.half_x + x, 1.0, 0),
            (self.half_y - y, -1.0, 1),
            (self.half_y + y, 1.0, 1),
        ):
            if gap < m:
                f = k * (m - max(gap, 0.0)) / m * (1.0 + 1.0 / max(gap, 0.1))
                if axis == 0:
                    fx += sign * f
                else:
                    fy += sign * f
        return fx, fy

    def _corners(self, x: float, y: float) -> tuple[float, float]:
        p = self.ctx.params
        R, k = p.corner_radius, p.corner_weight
        fx = fy = 0.0
        for cx in (-self.half_x, self.half_x):
            for cy in (-self.half_y, self.half_y):
                dx, dy = x - cx, y - cy
                d = math.hypot(dx, dy)
                if 1e-9 < d < R:
                    f = k * (R - d) / R / d
                    fx += dx * f
                    fy += dy * f
        return fx, fy

    def _separation(self, world, caps: Captures, x: float, y: float) -> tuple[float, float]:
        p = self.ctx.params
        if p.separation <= 0.0:
            return 0.0, 0.0
        fx = fy = 0.0
        team = world.team
        for mate in world.teammates:
            dx, dy = x - mate.x, y - mate.y
            d = math.hypot(dx, dy)
            if 1e-9 < d < p.separation and f"{team}/{mate.id}" not in caps.names:
                f = p.separation_weight * (p.separation - d) / p.separation / d
                fx += dx * f
                fy += dy * f
        return fx, fy

    def _slide(self, x: float, y: float, wx: float, wy: float) -> tuple[float, float]:
        """A wish into a wall the target already touches becomes a slide along that wall."""
        edge = 0.05
        if (x >= self.half_x - edge and wx > 0) or (x <= -self.half_x + edge and wx < 0):
            wx = 0.0
        if (y >= self.half_y - edge and wy > 0) or (y <= -self.half_y + edge and wy < 0):
            wy = 0.0
        return wx, wy

    def _jinked(self, now: float, wx: float, wy: float) -> tuple[float, float]:
        p = self.ctx.params
        if p.jink <= 0.0:
            return wx, wy
        if now >= self.jink_until:
            self.jink_angle = float(self.ctx.rng.normal(0.0, p.jink))
            self.jink_until = now + p.jink_period
        c, s = math.cos(self.jink_angle), math.sin(self.jink_angle)
        return c * wx - s * wy, s * wx + c * wy
