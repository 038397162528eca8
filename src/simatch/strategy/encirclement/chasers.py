"""The chasers: a net that sweeps the arena and closes around the prison (strategy ``encircle``).

Every chaser computes, from its own WorldModel only, the same picture: the free targets (perceived
opponents that the judge has not announced as captured), the net radius ``r`` = the distance of the
outermost free target from the prison plus a slack, and the net at that radius (`net.make_net`). It then
takes its station on the net by its order along it, so that no two chasers cross. Targets flee from the
chasers, that is inwards, towards the prison; as they give way the net follows them in.

* The radius shrinks at most at ``contract_speed`` (the net keeps its shape while it advances) and grows at
  up to ``expand_speed`` when a target has slipped out, so the net goes round it again.
* Chasers share their radius through StrategyInfo (``user[0]``) and each takes the median of the team's, so
  that noisy perceptions still agree on one net.
* If nothing gives way for ``squeeze_after`` seconds (no capture, no target nearer the prison), the slack
  shrinks at ``squeeze_rate`` down to ``min_slack``: the net closes in until the chasers touch the
  targets and push them.
"""

from __future__ import annotations

import math
import statistics

from pydantic import BaseModel, ConfigDict, Field

from ...config.loader import SceneError
from ...msgs.game_commands import MatchMode
from ..base import Command, RobotContext, RobotStrategy
from .game import Captures
from .net import Arena, make_net, prison_distance
from .view import opponents


class ChaserParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    prison: str = Field("prison", description="name of the world area the targets are driven into")
    max_speed: float = Field(3.5, gt=0.0, le=10.0, description="speed cap of a chaser [m/s]")
    slack: float = Field(
        1.4, gt=0.0, le=10.0, description="how far outside the outermost free target the net stays [m]"
    )
    min_slack: float = Field(0.6, gt=0.0, le=10.0, description="the closest the net comes when squeezing [m]")
    squeeze_after: float = Field(
        4.0, ge=0.0, le=600.0, description="seconds without progress before the net squeezes [s]"
    )
    squeeze_rate: float = Field(0.2, ge=0.0, le=10.0, description="how fast the slack shrinks then [m/s]")
    contract_speed: float = Field(0.6, gt=0.0, le=10.0, description="fastest the net closes in [m/s]")
    expand_speed: float = Field(2.0, gt=0.0, le=10.0, description="fastest the net backs off [m/s]")
    wall_clearance: float = Field(
        0.3, ge=0.0, le=5.0, description="how close to a wall a station may be (centre to wall) [m]"
    )


class Chaser(RobotStrategy):
    Params = ChaserParams

    def __init__(self, ctx: RobotContext):
        super().__init__(ctx)
        p = ctx.params
        field = ctx.field
        try:
            self.prison = field.area(p.prison)
        except KeyError as exc:
            raise SceneError(f"teams.{ctx.team}.strategy_params.prison: {exc.args[0]}") from None
        self.arena = Arena.of(field, p.wall_clearance)
        self.max_radius = max(
            prison_distance(self.prison, sx * self.arena.half_x, sy * self.arena.half_y)
            for sx in (-1, 1)
            for sy in (-1, 1)
        )
        self.captures = Captures()
        self.radius: float | None = None
        self.progress_mark = math.inf  # outermost free target's distance at the last progress
        self.progress_time = 0.0
        self.captured_seen = 0

    def decide(self, world) -> Command:
        if world.match_mode == MatchMode.STOPROBOT:
            return Command()
        me = world.me
        prison = self.prison
        caps = self.captures.update(world)
        free = [d for x, y in caps.free(self.seen(world)) if (d := prison_distance(prison, x, y)) > 0.0]
        if not free:  # (a target in the prison is captured at the judge's next look)
            return self.hold(world)
        outermost = max(free)
        slack = self._slack(world.time, outermost, len(caps.names))
        r = self._radius(world, min(outermost + slack, self.max_radius))
        team = self.net_members(world)
        net = make_net(prison, self.arena, round(r, 6), len(team))
        if net is None:
            return self.hold(world)
        mine = next(i for i, m in enumerate(team) if m.id == me.id)
        sx, sy = net.station(tuple((m.x, m.y) for m in team), mine)
        return self.go(world, (sx, sy), r, slack)

    # --- what a variant may change (see simatch.strategy.aerial) -------------------------------------------------
    def seen(self, world) -> list[tuple[float, float]]:
        """The targets this chaser knows of (team frame): the opponents it perceives."""
        return opponents(world)

    def net_members(self, world) -> list:
        """The team's robots that stand on the net (RobotInfo, in the same order for every chaser)."""
        return world.vision.robots

    def hold(self, world) -> Command:
        """Stay where I am (no free target, or no net in the arena)."""
        me = world.me
        return Command(target=(me.x, me.y), max_vel=self.ctx.params.max_speed)

    def go(self, world, station: tuple[float, float], r: float, slack: float) -> Command:
        """Drive to my station on the net; tell the team the net's radius and slack."""
        return Command(target=station, max_vel=self.ctx.params.max_speed, intent=station, user=(r, slack))

    def _slack(self, now: float, outermost: float, captured: int) -> float:
        """The nominal slack, shrinking while the encirclement makes no progress."""
        p = self.ctx.params
        if captured > self.captured_seen or outermost < self.progress_mark - 0.25:
            self.captured_seen = captured
            self.progress_mark = outermost
            self.progress_time = now
        stalled = now - self.progress_time - p.squeeze_after
        return max(p.min_slack, p.slack - p.squeeze_rate * max(0.0, stalled))

    def _radius(self, world, goal: float) -> float:
        """The team's net radius (median of what the chasers said last tick), moved towards ``goal``."""
        p = self.ctx.params
        said = [
            float(s.user[0])
            for aid, s in world.strategies.items()
            if aid != world.id and len(s.user) and math.isfinite(s.user[0])
        ]
        if self.radius is None and not said:
            r = goal
        else:
            r = statistics.median(said + ([self.radius] if self.radius is not None else []))
            dt = self.ctx.control_period
            r = min(max(goal, r - p.contract_speed * dt), r + p.expand_speed * dt)
        self.radius = r
        return r
