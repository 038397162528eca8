"""The drill judge (``judge.kind = "drill"``): short practice runs on the soccer world, for learning.

A drill is one attempt: the ball is in play from the first instant (STARTROBOT to every team, no kick-off),
and the attempt ends at the first of the decisions the scene lists in ``end_on``:

* ``goal``: the whole ball over a goal line, between the posts and under the bar (the referee's test), a goal
  for the team that attacks that goal (``team`` "" if no team of the scene attacks it);
* ``ball_out``: the whole ball over a side line or a goal line outside the goal;
* ``ball_lost``: a robot of another team than ``keepers`` touches or holds the ball (keepaway);
* ``area_left``: the ball's centre leaves the world area ``area`` (keepaway);

or at ``time_limit``. Every decision is a GameEvent, as the referee's are (so a learning environment rewards
them and may end its episode on them). With ``ball_scatter`` and ``robot_scatter`` each run begins at random
places drawn from the run's seed, so that every seed is another attempt. What is not judged here — restarts,
fouls, the 3 m dribbling limit — is the referee's (``msl_referee``), which the full matches use.
"""

from __future__ import annotations

import json
import math

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from ... import msgs
from ...bus import NodeContext, topics
from ...config.loader import SceneError
from .base import PlayJudge

DECISIONS = ("goal", "ball_out", "ball_lost", "area_left")
Rect = tuple[float, float, float, float]


class DrillParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    time_limit: float = Field(20.0, gt=0.0, le=86400.0, description="an attempt lasts at most this long [s]")
    end_on: list[str] = Field(default_factory=lambda: ["goal", "ball_out"], description="decisions that end it")
    keepers: str | None = Field(None, description="team that must keep the ball (ball_lost); none: not judged")
    area: str | None = Field(None, description="world area the ball must stay in (area_left); none: not judged")
    ball_scatter: Rect | None = Field(
        None, description="x0, y0, x1, y1 (world frame): the ball starts at a random place here; none: ball.position"
    )
    robot_scatter: dict[str, Rect] = Field(
        default_factory=dict,
        description="team -> x0, y0, x1, y1 (world frame): its robots start at random places and headings here",
    )
    scatter_spacing: float = Field(
        0.8, gt=0.0, le=20.0, description="least distance between scattered robots, the ball and other robots [m]"
    )

    @model_validator(mode="after")
    def _check(self):
        unknown = sorted(set(self.end_on) - set(DECISIONS))
        if unknown:
            raise ValueError(f"end_on: unknown decision(s) {', '.join(unknown)}; decisions are {', '.join(DECISIONS)}")
        for rect in [self.ball_scatter, *self.robot_scatter.values()]:
            if rect is not None and not (rect[0] < rect[2] and rect[1] < rect[3]):
                raise ValueError("a scatter rectangle needs x0 < x1 and y0 < y1")
        return self


class Drill(PlayJudge):
    Params = DrillParams
    name = "drill"

    def __init__(self, scene, params: DrillParams, world):
        super().__init__(scene, params, world)
        spec = scene.spec
        for team in [params.keepers, *params.robot_scatter]:
            if team is not None and team not in spec.teams:
                raise SceneError(
                    f"{scene.source}: judge: the scene has no team {team!r} (teams: {', '.join(self.teams)})"
                )
        self.field = geo = spec.world.geometry()
        self.area = None
        if params.area is not None:
            try:
                self.area = geo.area(params.area)
            except KeyError as exc:
                raise SceneError(f"{scene.source}: judge.area: {exc.args[0]}") from None
        self.ball_radius = spec.ball.radius
        self.period = spec.control.period
        self.attacker = {spec.team_sign(t): t for t in reversed(self.teams)}  # side -> team attacking it
        self.team_of = {name: name.partition("/")[0] for name in spec.robot_names()}
        self.score = dict.fromkeys(self.teams, 0)
        self.decisions: list[dict] = []
        self.end: str | None = None
        self._lost_by = ""  # robot of another team than the keepers that touched the ball since the last tick
        self._out = False

    @property
    def duration(self) -> float:
        return self.params.time_limit

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        self.subs = []
        if self.params.keepers is not None:
            self.subs.append(ctx.bus.subscribe(topics.BALL_CONTACTS, msgs.BallContacts, self._on_contacts))
        self._scatter(ctx.rng("judge", "scatter"))

    def stop(self) -> None:
        for sub in self.subs:
            sub.close()

    # --- set-up ---------------------------------------------------------------------------------------------
    def _scatter(self, rng: np.random.Generator) -> None:
        p = self.params
        spec = self.scene.spec
        placed: list[tuple[float, float]] = []
        for team, tspec in spec.teams.items():
            if team not in p.robot_scatter:
                placed += [(x, y) for x, y, _ in tspec.start]
        if p.ball_scatter is not None:
            x, y = self._free_spot(rng, p.ball_scatter, placed, "ball_scatter")
            self.world.set_model_state("ball", x=x, y=y, z=self.ball_radius, vx=0.0, vy=0.0, vz=0.0)
        else:
            x, y = spec.ball.position
        placed.append((x, y))
        for team, rect in p.robot_scatter.items():
            for rid in spec.teams[team].robot_ids():
                x, y = self._free_spot(rng, rect, placed, f"robot_scatter.{team}")
                placed.append((x, y))
                yaw = float(rng.uniform(-math.pi, math.pi))
                self.world.set_model_state(f"{team}/{rid}", x=x, y=y, yaw=yaw, vx=0.0, vy=0.0, wz=0.0)

    def _free_spot(self, rng, rect: Rect, placed: list, key: str) -> tuple[float, float]:
        spacing = self.params.scatter_spacing
        x0, y0, x1, y1 = rect
        for _ in range(10000):
            x, y = float(rng.uniform(x0, x1)), float(rng.uniform(y0, y1))
            if all(math.hypot(x - px, y - py) >= spacing for px, py in placed):
                return x, y
        raise SceneError(
            f"{self.scene.source}: judge.{key}: no free spot {spacing:g} m from the others in {list(rect)}"
        )

    # --- judging ------------------------------------------------------------------------------------------------
    def _on_contacts(self, msg) -> None:
        keepers = self.params.keepers
        for name in [*msg.touching, msg.holder]:
            if name and self.team_of.get(name, keepers) != keepers:
                self._lost_by = name

    def tick(self, now: float) -> None:
        if not self.done:
            self._judge(now)
            if not self.done and now >= self.params.time_limit - 1e-9:
                self._finish(now, "time_limit")
        self.publish(now)

    def _judge(self, now: float) -> None:
        x, y, z = self.world.ball_array()[:3].tolist()
        f, r = self.field, self.ball_radius
        over_goal_line = abs(x) > f.outer_half_length + r  # the whole ball past the line's outer edge,
        over_side_line = abs(y) > f.outer_half_width + r  # as the referee judges it (lines belong to the field)
        if over_goal_line and f.goals and abs(y) < 0.5 * f.goal_width and z < f.goal_height:
            team = self.attacker.get(1 if x > 0 else -1, "")
            if team:
                self.score[team] += 1
            self._decide(now, "goal", team, x, y, f"goal for {team or 'nobody'}: the whole ball is over the goal line")
        elif f.markings != "none" and (over_goal_line or over_side_line):
            if not self._out:
                self._out = True
                self._decide(now, "ball_out", "", x, y, "the whole ball is over a line")
        else:
            self._out = False
        if self.area is not None and not self.area.contains(x, y):
            self._decide(now, "area_left", self.params.keepers or "", x, y, f"the ball left the {self.area.name}")
        if self._lost_by:
            team, rid = topics.split_robot_name(self._lost_by)
            self._decide(now, "ball_lost", team, x, y, f"{self._lost_by} took the ball from {self.params.keepers}", rid)
            self._lost_by = ""

    def _decide(self, now: float, kind: str, team: str, x: float, y: float, detail: str, rid: int = 0) -> None:
        if self.done:
            return
        self.decisions.append({"t": round(now, 6), "type": kind, "team": team})
        self.event(now, kind, detail, team=team, robot=rid, x=x, y=y)
        if kind in self.params.end_on:
            self._finish(now, kind)

    def _finish(self, now: float, reason: str) -> None:
        self.done = True
        self.end = reason
        detail = f"the drill ends: {reason.replace('_', ' ')} after {now:.2f} s"
        self.event(now, "drill_end", detail, value=round(now, 6), limit=self.params.time_limit)

    # --- what the judge tells ---------------------------------------------------------------------------------
    def game_state(self, now: float):
        none = np.zeros(len(self.teams), dtype=np.int32)
        return msgs.new(
            msgs.GameState,
            stamp=now,
            stage="ended" if self.done else "drill",
            phase="ended" if self.done else "play",
            clock=now,
            stage_time_left=max(0.0, self.params.time_limit - now),
            command=int(self.command()),
            teams=list(self.teams),
            score=np.array([self.score[t] for t in self.teams], dtype=np.int32),
            yellow_cards=none,
            red_cards=none,
            fouls=none,
            ball_in_play=not self.done,
            result=json.dumps(self.result()),
        )

    def game(self) -> dict:
        return {"stage": "ended" if self.done else "drill", "score": dict(self.score), "end": self.end}

    def result(self) -> dict:
        end = self.end
        if end is None and hasattr(self, "ctx") and self.ctx.now() >= self.params.time_limit - 1e-9:
            end = "time_limit"
        return {"score": dict(self.score), "end": end, "decisions": list(self.decisions)}
