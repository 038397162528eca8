"""The pursuit judge (``judge.kind = "pursuit"``): pursuers try to catch an evader; in the shipped scene
(``pursuit_evasion_3d``) they are all drones, in 3D among obstacles, under a ceiling.

**Capture.** The evader is caught when a pursuer's centre comes within ``capture_radius`` of its centre
(a 3D distance): the judge logs a ``capture`` event naming the pursuer, freezes the evader where it is
(``set_frozen``) and ends the run. Otherwise the run ends at ``time_limit``.

**Collisions.** Every ``collision`` event of the simulator (a drone's frame meeting a wall, the floor, the
ceiling, an obstacle, a robot or another drone; once per meeting) is counted, per robot and per kind of
thing hit: flying among obstacles without touching them is part of the task.

Like the encirclement judge it gives the game commands itself (STARTROBOT from the start, STOPROBOT at
the end) and publishes its result on ``game_state``. With ``scatter`` the evader starts at a random free
place of a box (drawn from the run's seed), every run another chase; a flying evader's frame must fit in
the box's heights between the floor and the ceiling, a ground evader is scattered over the box's floor.
"""

from __future__ import annotations

import json
import math
from collections import Counter

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from ... import msgs
from ...bus import NodeContext, topics
from ...config.loader import SceneError
from ...robots import model_class
from .base import PlayJudge, require_team


class PursuitParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    pursuers: str = Field("cyan", description="the pursuing team")
    evader: str = Field("magenta/1", description="the robot to catch")
    capture_radius: float = Field(0.35, gt=0.0, le=10.0, description="centre to centre, in 3D [m]")
    time_limit: float = Field(120.0, gt=0.0, le=86400.0, description="[s]")
    scatter: tuple[float, float, float, float, float, float] | None = Field(
        None,
        description="x0, y0, z0, x1, y1, z1 (world frame): the evader starts at a random free place of this box, "
        "drawn from the run's seed; none: at its start pose",
    )
    scatter_clearance: float = Field(
        0.6, ge=0.0, le=10.0, description="least distance of the scattered evader from obstacles [m]"
    )

    @model_validator(mode="after")
    def _check(self):
        if self.scatter is not None:
            x0, y0, z0, x1, y1, z1 = self.scatter
            if not (x0 < x1 and y0 < y1 and 0.0 < z0 < z1):
                raise ValueError("scatter: expected x0 < x1, y0 < y1 and 0 < z0 < z1")
        return self


class Pursuit(PlayJudge):
    Params = PursuitParams
    name = "pursuit"

    def __init__(self, scene, params: PursuitParams, world):
        super().__init__(scene, params, world)
        spec = scene.spec
        require_team(scene, "pursuers", params.pursuers)
        names = spec.robot_names()
        if params.evader not in names:
            raise SceneError(f"{scene.source}: judge.evader: the scene has no robot {params.evader!r}")
        if params.evader.partition("/")[0] == params.pursuers:
            raise SceneError(f"{scene.source}: judge.evader: {params.evader} is one of the pursuers")
        self.pursuer_names = [n for n in names if n.partition("/")[0] == params.pursuers]
        self.period = spec.control.period
        self.geometry = spec.world.geometry()
        member = spec.member(params.evader)
        evader = model_class(member.model)(member.model_params)
        self.evader_flies = evader.aerial
        if params.scatter is not None and evader.aerial:
            _check_scatter_heights(scene.source, params.scatter, evader.height / 2, spec.world.ceiling)
        self.capture: dict | None = None
        self.closest = math.inf
        self.collisions: Counter = Counter()
        self.hits: Counter = Counter()  # by kind of thing hit

    @property
    def duration(self) -> float:
        return self.params.time_limit

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        self.sub_events = ctx.bus.subscribe(topics.EVENTS, msgs.GameEvent, self._on_event)
        if self.params.scatter is not None:
            self._scatter(ctx.rng("judge", "scatter"))

    def stop(self) -> None:
        self.sub_events.close()

    def _scatter(self, rng: np.random.Generator) -> None:
        x0, y0, z0, x1, y1, z1 = self.params.scatter
        clear = self.params.scatter_clearance
        for _ in range(10000):
            x, y, z = rng.uniform(x0, x1), rng.uniform(y0, y1), rng.uniform(z0, z1)
            ob = self.geometry.obstacle_at(x, y, clear)
            if ob is None or (self.evader_flies and ob.height < z - clear):
                break
        else:
            raise SceneError(f"{self.scene.source}: judge.scatter: no free place for the evader")
        place = {"x": float(x), "y": float(y), "yaw": 0.0}
        if self.evader_flies:  # a ground evader stays on the floor: the box's heights are not its
            place["z"] = float(z)
        self.world.set_model_state(self.params.evader, **place)

    def _on_event(self, ev) -> None:
        if ev.type == "collision":
            self.collisions[f"{ev.team}/{ev.robot}"] += 1
            self.hits[_kind(ev.detail.rpartition(" hit ")[2], self.geometry)] += 1
            self.changed()

    # --- judging ---------------------------------------------------------------------------------------------
    def tick(self, now: float) -> None:
        if not self.done:
            states = self.world.model_states()
            e = states[self.params.evader]
            near, who = math.inf, ""
            for name in self.pursuer_names:
                s = states[name]
                d = math.dist((s.x, s.y, s.z), (e.x, e.y, e.z))
                if d < near:
                    near, who = d, name
            self.closest = min(self.closest, near)
            if near <= self.params.capture_radius:
                self._caught(now, who, e)
        self.publish(now)

    def _caught(self, now: float, who: str, e) -> None:
        self.world.set_frozen(self.params.evader, True)
        self.capture = {"by": who, "t": round(now, 6), "x": round(e.x, 4), "y": round(e.y, 4), "z": round(e.z, 4)}
        team, rid = topics.split_robot_name(self.params.evader)
        self.done = True
        detail = f"{self.params.evader} caught by {who} at height {e.z:.2f} m after {now:.2f} s"
        self.event(
            now,
            "capture",
            detail,
            team=team,
            robot=rid,
            x=e.x,
            y=e.y,
            value=round(now, 6),
            limit=self.params.time_limit,
        )

    def game_state(self, now: float):
        caught = 1 if self.capture else 0
        none = np.zeros(len(self.teams), dtype=np.int32)  # no cards, no fouls in this game
        return msgs.new(
            msgs.GameState,
            stamp=now,
            stage="ended" if self.done else "pursuit",
            phase="ended" if self.done else "play",
            clock=now,
            stage_time_left=max(0.0, self.params.time_limit - now),
            command=int(self.command()),
            teams=list(self.teams),
            score=np.array([caught if t == self.params.pursuers else 0 for t in self.teams], dtype=np.int32),
            yellow_cards=none,
            red_cards=none,
            fouls=none,
            result=json.dumps(self.result()),
        )

    def game(self) -> dict:
        return {"stage": "ended" if self.done else "pursuit", "command": self.command().name}

    def result(self) -> dict:
        now = self.ctx.now() if hasattr(self, "ctx") else 0.0
        end = "captured" if self.capture else ("time_limit" if now >= self.params.time_limit - 1e-9 else None)
        return {
            "captured": self.capture is not None,
            "capture_time_s": self.capture["t"] if self.capture else None,
            "captured_by": self.capture["by"] if self.capture else None,
            "capture": self.capture,
            "closest_m": round(self.closest, 4) if math.isfinite(self.closest) else None,
            "time_limit_s": self.params.time_limit,
            "pursuers": self.params.pursuers,
            "evader": self.params.evader,
            "collisions": {
                "total": sum(self.collisions.values()),
                "by_robot": dict(sorted(self.collisions.items())),
                "by_kind": dict(sorted(self.hits.items())),
            },
            "end": end,
        }


def _check_scatter_heights(source: str, box, half_height: float, ceiling: float | None) -> None:
    """A flying evader scattered anywhere in the box must fit between the floor and the ceiling."""
    z0, z1 = box[2], box[5]
    if z0 - half_height <= 0.0:
        raise SceneError(
            f"{source}: judge.scatter: its bottom z0 = {z0:g} m puts the evader's frame (half height "
            f"{half_height:g} m) into the floor"
        )
    if ceiling is not None and z1 + half_height >= ceiling:
        raise SceneError(
            f"{source}: judge.scatter: its top z1 = {z1:g} m puts the evader's frame (half height {half_height:g} m) "
            f"at or above the ceiling (world.ceiling = {ceiling:g} m)"
        )


def _kind(label: str, geometry) -> str:
    """What a collision's other party is: wall, floor, ceiling, obstacle, ball, robot."""
    if label.startswith("board_"):
        return "wall"
    if label in ("floor", "ceiling", "ball"):
        return label
    if any(ob.name == label for ob in geometry.obstacles):
        return "obstacle"
    if "/" in label:
        return "robot"
    return "other"
