"""The aerial encirclement's teams (scene ``aerial_encirclement``): ground chasers helped by drones that see
farther round fleeing targets up among obstacles.

* ``aerial_encircle`` (`AerialChasers`, a team strategy): its ground robots are `GroundChaser`\\ s, the
  paper's net of ``encircle`` (`simatch.strategy.encirclement`) that also steers round obstacles and knows
  every target any team-mate reports (`reports.Sightings`); its drones are `Scout`\\ s: each flies at
  ``altitude`` over its band of the arena, above the outermost free target it knows of (where the net
  needs eyes: targets left outside it, hidden behind an obstacle), or sweeps its band when it knows none,
  and reports every target in its camera's cone. With ``scouting = false`` the drones stay on the floor:
  the ground team alone, the baseline.
* ``evade`` (`Evader`): the ``flee`` targets, which also keep off obstacles and slide round them, and flee
  only from what moves on the ground (a drone overhead is no threat to them).
"""

from __future__ import annotations

import math

from pydantic import Field

from ...msgs.game_commands import MatchMode
from ..base import Command, RobotContext, RobotStrategy, TeamStrategy
from ..encirclement import Chaser, ChaserParams, Target, TargetParams
from ..encirclement.game import Captures
from ..encirclement.net import prison_distance
from .avoid import body_frame, clear_spot, steer, velocity_to
from .reports import Sightings, TeamKnowledge, encode, team_opponents

NAN = math.nan


class AerialChasersParams(ChaserParams):
    memory: float = Field(3.0, ge=0.0, le=60.0, description="a target nobody sees any more is remembered this long [s]")
    scouting: bool = Field(True, description="the drones fly and report; false: they stay landed (ground team alone)")
    altitude: float = Field(3.5, gt=0.3, le=30.0, description="the drones' flying height [m]")
    drone_speed: float = Field(3.0, gt=0.0, le=20.0, description="the drones' speed cap [m/s]")
    patrol_margin: float = Field(
        2.5, ge=0.0, le=20.0, description="a sweeping drone turns this far from the arena's ends [m]"
    )


class AerialChasers(TeamStrategy):
    Params = AerialChasersParams

    def __init__(self, ctx):
        super().__init__(ctx)
        self.knowledge = TeamKnowledge(ctx.params.memory)  # shared by the team's robots in this process

    def make_robot(self, ctx: RobotContext) -> RobotStrategy:
        return Scout(ctx, self.knowledge) if ctx.aerial else GroundChaser(ctx, self.knowledge)


def _ground_ids(ctx: RobotContext) -> set[int]:
    from ..base import is_aerial

    return {rid for rid, model in ctx.models.items() if not is_aerial(model)} or set(ctx.ids)


class GroundChaser(Chaser):
    """A chaser of the paper's net that knows what its team sees and steers round obstacles."""

    def __init__(self, ctx: RobotContext, knowledge: TeamKnowledge | None = None):
        super().__init__(ctx)
        self.sightings = Sightings(knowledge or TeamKnowledge(ctx.params.memory))
        self.ground = _ground_ids(ctx)
        self.radius_m = 0.25
        self.own: list[tuple[float, float]] = []

    def decide(self, world) -> Command:
        self.own = team_opponents(world)
        return super().decide(world)

    def seen(self, world) -> list[tuple[float, float]]:
        return self.sightings.update(world.time, self.own, world)

    def net_members(self, world) -> list:
        return [r for r in world.vision.robots if r.id in self.ground]

    def hold(self, world) -> Command:
        return Command(user=encode((NAN, NAN), self.own))

    def go(self, world, station, r: float, slack: float) -> Command:
        me = world.me
        field = self.ctx.field
        sx, sy = clear_spot(*station, field, self.radius_m)
        vx, vy = velocity_to(me.x, me.y, sx, sy, self.ctx.params.max_speed)
        vx, vy = steer(me.x, me.y, vx, vy, field, self.radius_m)
        bx, by = body_frame(vx, vy, me.yaw)
        return Command(vx=bx, vy=by, intent=(sx, sy), user=encode((r, slack), self.own))


class Scout(RobotStrategy):
    """A drone over its band of the arena, above the outermost target it knows of, reporting what it sees."""

    Params = AerialChasersParams

    def __init__(self, ctx: RobotContext, knowledge: TeamKnowledge | None = None):
        super().__init__(ctx)
        p = ctx.params
        field = ctx.field
        self.prison = field.area(p.prison)
        drones = sorted(rid for rid in ctx.ids if rid not in _ground_ids(ctx))
        k, n = drones.index(ctx.id), len(drones)
        w = 2 * field.reach_y / n
        self.band = (-field.reach_y + k * w, -field.reach_y + (k + 1) * w)
        self.x_ends = (-field.reach_x + p.patrol_margin, field.reach_x - p.patrol_margin)
        self.sweep = -1.0  # heading of the sweep along x
        self.captures = Captures()
        self.sightings = Sightings(knowledge or TeamKnowledge(p.memory))

    def decide(self, world) -> Command:
        p = self.ctx.params
        if not p.scouting:
            return Command()  # on the floor, motors off
        own = team_opponents(world)
        user = encode((NAN, NAN), own)
        if world.match_mode == MatchMode.STOPROBOT:
            return Command(altitude=p.altitude, user=user)
        me = world.me
        caps = self.captures.update(world)
        known = caps.free(self.sightings.update(world.time, own, world))
        lo, hi = self.band
        mine = [(x, y) for x, y in known if lo <= y <= hi and prison_distance(self.prison, x, y) > 0.0]
        if mine:
            tx, ty = max(mine, key=lambda q: prison_distance(self.prison, *q))
        else:
            x0, x1 = self.x_ends
            if me.x <= x0 + 0.3:
                self.sweep = 1.0
            elif me.x >= x1 - 0.3:
                self.sweep = -1.0
            tx, ty = (x1 if self.sweep > 0 else x0), 0.5 * (lo + hi)
        vx, vy = velocity_to(me.x, me.y, tx, ty, p.drone_speed, gain=1.5)
        bx, by = body_frame(vx, vy, me.yaw)
        return Command(vx=bx, vy=by, altitude=p.altitude, max_vz=1.5, intent=(tx, ty), user=user)


class EvaderParams(TargetParams):
    ignore_above: float = Field(1.0, ge=0.0, le=100.0, description="opponents higher than this are no threat [m]")
    obstacle_margin: float = Field(0.8, gt=0.0, le=10.0, description="obstacles nearer than this push away [m]")
    obstacle_weight: float = Field(0.6, ge=0.0, le=100.0, description="strength of the obstacles' push")


class Evader(Target):
    """A ``flee`` target that keeps off obstacles and flees only from chasers on the ground."""

    Params = EvaderParams

    def threats(self, world) -> list[tuple[float, float]]:
        o = world.vision.obstacles
        high = {
            (float(x), float(y))
            for x, y, z in zip(o.x.tolist(), o.y.tolist(), o.z.tolist())
            if z > self.ctx.params.ignore_above
        }
        found = team_opponents(world)
        return [p for p in found if p not in high] if high else found

    def _pushes(self, world, caps, x: float, y: float) -> tuple[float, float]:
        px, py = super()._pushes(world, caps, x, y)
        p = self.ctx.params
        m, k = p.obstacle_margin, p.obstacle_weight
        for ob in self.ctx.field.obstacles:
            if not ob.near(x, y, p.wall_clearance + m):
                continue
            gap = ob.distance(x, y) - p.wall_clearance
            if gap < m:
                nx, ny = ob.away(x, y)
                f = k * (m - max(gap, 0.0)) / m * (1.0 + 1.0 / max(gap, 0.1))
                px += nx * f
                py += ny * f
        return px, py

    def _slide(self, x: float, y: float, wx: float, wy: float) -> tuple[float, float]:
        wx, wy = super()._slide(x, y, wx, wy)
        clearance = self.ctx.params.wall_clearance + 0.05
        for ob in self.ctx.field.obstacles:
            if ob.near(x, y, clearance) and ob.distance(x, y) < clearance:
                nx, ny = ob.away(x, y)
                inward = -(wx * nx + wy * ny)
                if inward > 0.0:
                    wx, wy = wx + nx * inward, wy + ny * inward
        return wx, wy
