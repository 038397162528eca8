"""The drones of the 3D pursuit-evasion (scene ``pursuit_evasion_3d``): pursuers that close in on an evading
drone among pillars and boxes, under a ceiling.

* ``pincer`` (`Pincer`): the pursuer nearest the evader flies at where the evader is heading (its position
  a moment ahead); the others fly to the far side of the evader, on either flank of it as the lead
  pursuer sees it and a little above or below, and close in once they are there: the evader, fleeing
  the lead, flies into them. Every pursuer decides from its own perception; the roles follow from the
  distances, which all of them see alike.
* ``chase`` (`Chase`), the baseline: every pursuer flies straight at where the evader is.
* ``evade_3d`` (`Evader3D`): the evading drone flees from the pursuers it sees (the nearest weigh most),
  keeps off walls, floor, ceiling and obstacles, and jinks (a random turn of its course, drawn from the
  run's seed, changing every second).

All of them fly round obstacles that reach up to their height and over those that do not.
"""

from __future__ import annotations

import math

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from ...msgs.game_commands import MatchMode
from ..base import Command, RobotContext, RobotStrategy
from .avoid import body_frame, steer

#: a flying robot keeps this far from the floor and the ceiling [m]
HEADROOM = 0.5


class PursuitParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    max_speed: float = Field(2.5, gt=0.0, le=20.0, description="speed cap [m/s]")
    max_vz: float = Field(1.5, gt=0.0, le=10.0, description="climb and descent cap [m/s]")
    lead_time: float = Field(0.6, ge=0.0, le=5.0, description="the lead pursuer aims this far ahead of the evader [s]")
    flank: float = Field(1.5, ge=0.0, le=10.0, description="how far beyond the evader the flankers take post [m]")
    flank_angle: float = Field(60.0, ge=0.0, le=90.0, description="the flankers' posts, off the far side [deg]")
    close_in: float = Field(0.6, gt=0.0, le=10.0, description="a flanker this near its post closes in [m]")
    radius: float = Field(0.15, gt=0.0, le=2.0, description="room kept round the frame when steering [m]")


def _evader(world, sign_z: float = 1.0):
    """(x, y, z, vx, vy) of the nearest robot I see that is not a team-mate (team frame), or None."""
    o = world.vision.obstacles
    if not len(o.x):
        return None
    mates = {(r.x, r.y) for r in world.vision.robots}
    me = world.me
    best, best_d = None, math.inf
    for x, y, z, vx, vy in zip(o.x.tolist(), o.y.tolist(), o.z.tolist(), o.vx.tolist(), o.vy.tolist()):
        if (x, y) in mates:
            continue
        d = math.dist((x, y, z), (me.x, me.y, me.z))
        if d < best_d:
            best, best_d = (x, y, z, vx, vy), d
    return best


class _Flyer(RobotStrategy):
    """What pursuers and evaders share: flying to a point round obstacles, inside the walls and the ceiling."""

    def __init__(self, ctx: RobotContext):
        super().__init__(ctx)
        field = ctx.field
        self.top = (field.ceiling or 6.0) - HEADROOM
        self.half_x, self.half_y = field.reach_x - 0.4, field.reach_y - 0.4

    def fly(self, world, vx: float, vy: float, vz: float, intent=None) -> Command:
        """Fly at world velocity (vx, vy, vz), capped, round obstacles, inside the arena's box."""
        p = self.ctx.params
        me = world.me
        speed = math.hypot(vx, vy)
        if speed > p.max_speed:
            vx, vy = vx / speed * p.max_speed, vy / speed * p.max_speed
        vx, vy = steer(me.x, me.y, vx, vy, self.ctx.field, p.radius, z=me.z)
        # the box: no course out of the walls, into the floor or the ceiling
        if (me.x > self.half_x and vx > 0) or (me.x < -self.half_x and vx < 0):
            vx = 0.0
        if (me.y > self.half_y and vy > 0) or (me.y < -self.half_y and vy < 0):
            vy = 0.0
        vz = max(-p.max_vz, min(p.max_vz, vz))
        if (me.z > self.top and vz > 0) or (me.z < HEADROOM and vz < 0):
            vz = 0.0
        bx, by = body_frame(vx, vy, me.yaw)
        return Command(vx=bx, vy=by, vz=vz, intent=intent)

    def toward(self, world, tx: float, ty: float, tz: float, gain: float = 2.0) -> Command:
        me = world.me
        tz = min(max(tz, HEADROOM), self.top)
        dx, dy, dz = tx - me.x, ty - me.y, tz - me.z
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        if d < 1e-9:
            return self.fly(world, 0.0, 0.0, 0.0, intent=(tx, ty))
        v = min(self.ctx.params.max_speed, gain * d) / d
        return self.fly(world, dx * v, dy * v, dz * v, intent=(tx, ty))


class _Pursuer(_Flyer):
    Params = PursuitParams

    def decide(self, world) -> Command:
        if world.match_mode == MatchMode.STOPROBOT:
            return Command()
        e = _evader(world)
        return Command() if e is None else self.pursue(world, e)

    def pursue(self, world, e) -> Command:
        raise NotImplementedError


class Chase(_Pursuer):
    """The baseline: fly straight at the evader."""

    def pursue(self, world, e) -> Command:
        x, y, z, _, _ = e
        return self.toward(world, x, y, z, gain=10.0)


class Pincer(_Pursuer):
    """Lead and flankers: one flies at the evader's course, the others cut off its escape."""

    def pursue(self, world, e) -> Command:
        p = self.ctx.params
        ex, ey, ez, evx, evy = e
        team = sorted(world.vision.robots, key=lambda r: (math.dist((r.x, r.y, r.z), (ex, ey, ez)), r.id))
        lead = team[0]
        me = world.me
        if lead.id == me.id:
            t = p.lead_time
            return self.toward(world, ex + evx * t, ey + evy * t, ez, gain=10.0)
        # flankers, in the order of their distance: posts beyond the evader as the lead sees it
        k = next(i for i, r in enumerate(team) if r.id == me.id)
        ax, ay = ex - lead.x, ey - lead.y
        n = math.hypot(ax, ay)
        ax, ay = (ax / n, ay / n) if n > 1e-6 else (1.0, 0.0)
        side = 1.0 if k % 2 else -1.0
        turn = math.radians(p.flank_angle) * side * ((k + 1) // 2)
        c, s = math.cos(turn), math.sin(turn)
        ux, uy = c * ax - s * ay, s * ax + c * ay
        post = (ex + p.flank * ux, ey + p.flank * uy, ez + 0.4 * side)
        if math.dist((me.x, me.y, me.z), post) < p.close_in or math.dist((me.x, me.y, me.z), (ex, ey, ez)) < p.flank:
            return self.toward(world, ex, ey, ez, gain=10.0)
        return self.toward(world, *post, gain=10.0)


class Evader3DParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    max_speed: float = Field(2.5, gt=0.0, le=20.0, description="speed cap [m/s]")
    max_vz: float = Field(1.5, gt=0.0, le=10.0, description="climb and descent cap [m/s]")
    horizon: float = Field(1.0, gt=0.0, le=10.0, description="how far ahead each course is judged [s]")
    margin: float = Field(1.0, gt=0.0, le=10.0, description="walls, floor, ceiling, obstacles nearer are avoided [m]")
    headings: int = Field(24, ge=4, le=360, description="courses tried in the horizontal plane")
    randomness: float = Field(0.15, ge=0.0, le=10.0, description="spread of the random preference among courses [m]")
    openness: float = Field(
        0.5, ge=0.0, le=10.0, description="weight of the free run a course leaves ahead (no flight into corners)"
    )
    reach: float = Field(4.0, gt=0.0, le=50.0, description="free run counted up to this far [m]")
    radius: float = Field(0.15, gt=0.0, le=2.0, description="room kept round the frame when steering [m]")


class Evader3D(_Flyer):
    """Of the courses it could fly (headings all round, level, climbing or diving), the one that a moment
    ahead leaves the most room to the nearest pursuer, the longest free run ahead and enough room to walls,
    floor, ceiling and obstacles; a little random preference, drawn from the run's seed, keeps it
    unpredictable."""

    Params = Evader3DParams

    def __init__(self, ctx: RobotContext):
        super().__init__(ctx)
        p = ctx.params
        az = np.linspace(0.0, 2 * np.pi, p.headings, endpoint=False)
        dirs = [(0.0, 0.0, 0.0)]
        for el in (-0.5, 0.0, 0.5):
            dirs += [(math.cos(a) * math.cos(el), math.sin(a) * math.cos(el), math.sin(el)) for a in az]
        self.courses = np.array(dirs)

    def decide(self, world) -> Command:
        if world.match_mode == MatchMode.STOPROBOT:
            return Command()
        p = self.ctx.params
        me = world.me
        o = world.vision.obstacles
        if not len(o.x):
            return Command()
        pos = np.array((me.x, me.y, me.z))
        v = self.courses * np.array((p.max_speed, p.max_speed, p.max_vz))
        ahead = pos + v * p.horizon
        # the room a course leaves to the nearest pursuer where it is now: a pursuer turns after me, so its
        # own course says little of where it will be
        hunters = np.stack((o.x, o.y, o.z), axis=1).astype(float)
        gap = ahead[:, None, :] - hunters[None, :, :]
        room = np.sqrt((gap * gap).sum(axis=2)).min(axis=1)
        score = room - self._cramped(ahead) + p.openness * self._free_run(pos)
        score += self.ctx.rng.normal(0.0, p.randomness, len(ahead))
        best = v[int(np.argmax(score))]
        return self.fly(world, float(best[0]), float(best[1]), float(best[2]))

    def _free_run(self, pos: np.ndarray) -> np.ndarray:
        """How far each course runs from here before it meets a wall, the floor, the ceiling or an obstacle
        (sampled every half metre, up to ``reach``): a corner offers none."""
        p = self.ctx.params
        steps = np.arange(0.5, p.reach + 1e-9, 0.5)
        pts = pos[None, None, :] + self.courses[:, None, :] * steps[None, :, None]
        free = ~self._blocked(pts.reshape(-1, 3)).reshape(len(self.courses), len(steps))
        run = np.where(free.all(axis=1), p.reach, steps[np.argmin(free, axis=1)] - 0.5)
        run[0] = 0.0  # standing still runs nowhere
        return run

    def _blocked(self, pts: np.ndarray) -> np.ndarray:
        field = self.ctx.field
        r = self.ctx.params.radius
        x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
        out = (
            (np.abs(x) > field.reach_x - r) | (np.abs(y) > field.reach_y - r) | (z < r) | (z > self.top + HEADROOM - r)
        )
        for ob in field.obstacles:
            near = (np.abs(x - ob.x) < ob.bounding_radius + r) & (np.abs(y - ob.y) < ob.bounding_radius + r)
            for k in np.flatnonzero(near & (z < ob.height + r)):
                out[k] |= ob.distance(float(x[k]), float(y[k])) < r
        return out

    def _cramped(self, pts: np.ndarray) -> np.ndarray:
        """How much each point lacks of ``margin`` to the walls, floor, ceiling and obstacles (weighted)."""
        p = self.ctx.params
        field = self.ctx.field
        m = p.margin
        x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
        gaps = [field.reach_x - np.abs(x), field.reach_y - np.abs(y), z, self.top + HEADROOM - z]
        lack = sum(np.clip(m - g, 0.0, None) ** 2 for g in gaps) * 4.0
        for ob in field.obstacles:
            d = np.array([ob.distance(a, b) for a, b in zip(x, y)]) - p.radius
            over = z - ob.height - p.radius  # above its top?
            gap = np.where(over > 0.0, np.maximum(over, d), d)
            lack = lack + np.clip(m - gap, 0.0, None) ** 2 * 4.0
        return lack
