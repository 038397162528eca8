"""The encirclement judge (paper section VII-C): chasers drive targets into a prison area.

A target whose centre is in the prison (a named area of the world, ``world.areas``) is captured: the judge
freezes it where it stands (``set_frozen``: nothing can move it any more), logs a ``capture`` event and
tells everybody on ``game_state`` (the GameState's ``result`` lists every capture, with where it stands).
The run ends when every target is captured (an ``all_captured`` event) or at the time limit. The judge looks
at the world every control period, as often as the robots decide.

It gives the game commands itself (STARTROBOT to both teams from the start, STOPROBOT at the end), so a
run needs no coach. With ``scatter`` it also sets up each run: the targets start at random places of a
rectangle, drawn from the run's seed, so that every seed is another encirclement.
"""

from __future__ import annotations

import json
import math

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from ... import msgs
from ...bus import NodeContext, topics
from ...config.loader import SceneError
from ...field import Area
from .base import PlayJudge, require_team

#: a scattered target starts at least this far from every obstacle (centre to outline) [m]
OBSTACLE_CLEARANCE = 0.5


class EncirclementParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    chasers: str = Field("cyan", description="the team that rounds the targets up")
    targets: str = Field("magenta", description="the team whose robots are captured in the prison")
    prison: str = Field("prison", description="name of the world area that is the prison")
    time_limit: float = Field(300.0, gt=0.0, le=86400.0, description="the run ends after this long [s]")
    scatter: tuple[float, float, float, float] | None = Field(
        None,
        description="x0, y0, x1, y1 (world frame): the targets start at random places in this rectangle, "
        "drawn from the run's seed, scatter_spacing or more from the prison (each axis) and clear of "
        "obstacles; none: at their start poses",
    )
    scatter_spacing: float = Field(
        1.2, gt=0.0, le=20.0, description="least distance between a scattered target and any other robot [m]"
    )
    stow: bool = Field(
        False,
        description="captured targets are led to the back of the prison (the side farthest from the arena's "
        "centre), so that they do not block its entrance; false: frozen where they were caught",
    )

    @model_validator(mode="after")
    def _check(self):
        if self.chasers == self.targets:
            raise ValueError("chasers and targets must be different teams")
        if self.scatter is not None:
            x0, y0, x1, y1 = self.scatter
            if not (x0 < x1 and y0 < y1):
                raise ValueError("scatter: expected x0 < x1 and y0 < y1")
        return self


class Encirclement(PlayJudge):
    Params = EncirclementParams
    name = "encirclement"

    def __init__(self, scene, params: EncirclementParams, world):
        super().__init__(scene, params, world)
        spec = scene.spec
        for key in ("chasers", "targets"):
            require_team(scene, key, getattr(params, key))
        self.geometry = geometry = spec.world.geometry()
        try:
            self.prison = geometry.area(params.prison)
        except KeyError as exc:
            raise SceneError(f"{scene.source}: judge.prison: {exc.args[0]}") from None
        if params.scatter is not None:
            x0, y0, x1, y1 = params.scatter
            reach_x, reach_y = geometry.half_length + geometry.margin, geometry.half_width + geometry.margin
            if x0 < -reach_x or x1 > reach_x or y0 < -reach_y or y1 > reach_y:
                raise SceneError(
                    f"{scene.source}: judge.scatter: {list(params.scatter)} is not inside the arena "
                    f"(|x| <= {reach_x:g}, |y| <= {reach_y:g})"
                )
        # the judge looks at the world as often as the robots decide: captures change no faster than their
        # decisions, and reading every model's state at every physics step would rival the physics itself
        self.period = spec.control.period
        tspec = spec.teams[params.targets]
        self.target_names = [f"{params.targets}/{rid}" for rid in tspec.robot_ids()]
        self.team_of = {name: name.partition("/")[0] for name in spec.robot_names()}
        self.top_speed = {team: 0.0 for team in self.teams}
        self.captures: list[dict] = []
        self.captured: set[str] = set()

    @property
    def duration(self) -> float:
        return self.params.time_limit

    # --- set-up -----------------------------------------------------------------------------------------------
    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        if self.params.scatter is not None:
            self._scatter(ctx.rng("judge", "scatter"))

    def _scatter(self, rng: np.random.Generator) -> None:
        """Place every target at a random free spot of the scatter rectangle (seeded by the run)."""
        x0, y0, x1, y1 = self.params.scatter
        spacing = self.params.scatter_spacing
        p = self.prison
        keep_out = Area("", p.x0 - spacing, p.y0 - spacing, p.x1 + spacing, p.y1 + spacing)
        spec = self.scene.spec
        placed = [
            (x, y) for team, tspec in spec.teams.items() if team != self.params.targets for x, y, _ in tspec.starts()
        ]
        clear = OBSTACLE_CLEARANCE
        for name in self.target_names:
            for _ in range(10000):
                x, y = rng.uniform(x0, x1), rng.uniform(y0, y1)
                if (
                    not keep_out.contains(x, y)
                    and all(math.hypot(x - px, y - py) >= spacing for px, py in placed)
                    and self.geometry.obstacle_at(x, y, clear) is None
                ):
                    break
            else:
                raise SceneError(
                    f"{self.scene.source}: judge.scatter: no room for {len(self.target_names)} targets "
                    f"{spacing:g} m apart in {list(self.params.scatter)}"
                )
            placed.append((x, y))
            self.world.set_model_state(
                name, x=float(x), y=float(y), yaw=float(rng.uniform(-math.pi, math.pi)), vx=0.0, vy=0.0, wz=0.0
            )

    # --- judging ---------------------------------------------------------------------------------------------
    def tick(self, now: float) -> None:
        if not self.done:
            states = self.world.model_states()
            self._measure_speeds(states)
            prison = self.prison
            for name in self.target_names:
                if name not in self.captured:
                    st = states[name]
                    if prison.contains(st.x, st.y):
                        self._capture(now, name, st.x, st.y)
            if len(self.captured) == len(self.target_names):
                self._end(now)
        self.publish(now)

    def _measure_speeds(self, states: dict) -> None:
        """Each team's top speed so far (captured targets excluded), so every run shows the speed ratio."""
        top = self.top_speed
        for name, team in self.team_of.items():
            if name not in self.captured:
                st = states[name]
                v = math.hypot(st.vx, st.vy)
                if v > top[team]:
                    top[team] = v

    def _capture(self, now: float, name: str, x: float, y: float) -> None:
        caught = (x, y)
        if self.params.stow:
            x, y = self._stow(name)
            self.world.set_model_state(name, x=x, y=y, vx=0.0, vy=0.0, wz=0.0)
        self.world.set_frozen(name, True)
        self.captured.add(name)
        capture = {"robot": name, "t": round(now, 6), "x": round(x, 4), "y": round(y, 4)}
        if self.params.stow:
            capture["caught_at"] = [round(caught[0], 4), round(caught[1], 4)]
        self.captures.append(capture)
        team, rid = topics.split_robot_name(name)
        n, total = len(self.captured), len(self.target_names)
        detail = f"{name} captured in the {self.prison.name} ({n} of {total})"
        cx, cy = caught  # the event is where it was caught
        self.event(now, "capture", detail, team=team, robot=rid, x=cx, y=cy, value=float(n), limit=float(total))

    def _stow(self, name: str, spacing: float = 0.55) -> tuple[float, float]:
        """A free place at the back of the prison (rows along its side farthest from the arena's centre, from
        the back forward): no other robot within ``spacing``."""
        p, inset = self.prison, 0.3
        cx, cy = p.center
        along_x = abs(cx) * (p.y1 - p.y0) >= abs(cy) * (p.x1 - p.x0)  # the back side is an x = const side
        states = self.world.model_states()
        others = [(s.x, s.y) for n, s in states.items() if n != name and n in self.team_of]
        rows = int(((p.x1 - p.x0) if along_x else (p.y1 - p.y0)) / spacing)
        for row in range(max(rows, 1)):
            if along_x:
                back = (p.x1 - inset - row * spacing) if cx >= 0 else (p.x0 + inset + row * spacing)
                spots = [(back, y) for y in np.arange(p.y0 + inset, p.y1 - inset + 1e-9, spacing)]
            else:
                back = (p.y1 - inset - row * spacing) if cy >= 0 else (p.y0 + inset + row * spacing)
                spots = [(x, back) for x in np.arange(p.x0 + inset, p.x1 - inset + 1e-9, spacing)]
            for x, y in spots:
                if all(math.hypot(x - ox, y - oy) >= spacing for ox, oy in others):
                    return float(x), float(y)
        st = states[name]
        return st.x, st.y  # the prison is full: where it stands

    def _end(self, now: float) -> None:
        self.done = True
        n = len(self.target_names)
        detail = f"all {n} targets captured in {now:.2f} s"
        self.event(
            now, "all_captured", detail, team=self.params.targets, value=round(now, 6), limit=self.params.time_limit
        )

    # --- what the judge tells ---------------------------------------------------------------------------------
    def game_state(self, now: float):
        n = len(self.captured)
        score = np.array([n if t == self.params.chasers else 0 for t in self.teams], dtype=np.int32)
        none = np.zeros(len(self.teams), dtype=np.int32)  # no cards, no fouls in this game
        return msgs.new(
            msgs.GameState,
            stamp=now,
            stage="ended" if self.done else "encirclement",
            phase="ended" if self.done else "play",
            clock=now,
            stage_time_left=max(0.0, self.params.time_limit - now),
            command=int(self.command()),
            teams=list(self.teams),
            score=score,
            yellow_cards=none,
            red_cards=none,
            fouls=none,
            result=json.dumps(self.result()),
        )

    def game(self) -> dict:
        return {
            "stage": "ended" if self.done else "encirclement",
            "command": self.command().name,
            "captured": len(self.captured),
            "targets": len(self.target_names),
            "time_left_s": max(0.0, self.params.time_limit - self.ctx.now()) if hasattr(self, "ctx") else None,
        }

    def _end_reason(self) -> str | None:
        if self.done:
            return "all_captured"
        if hasattr(self, "ctx") and self.ctx.now() >= self.params.time_limit - 1e-9:
            return "time_limit"
        return None

    def result(self) -> dict:
        last = self.captures[-1]["t"] if self.captures and len(self.captured) == len(self.target_names) else None
        p = self.prison
        return {
            "targets": len(self.target_names),
            "captured": len(self.captured),
            "capture_time_s": last,
            "time_limit_s": self.params.time_limit,
            "chasers": self.params.chasers,
            "target_team": self.params.targets,
            "prison": {"name": p.name, "x0": p.x0, "y0": p.y0, "x1": p.x1, "y1": p.y1},
            "captures": list(self.captures),
            "top_speed_m_s": {team: round(v, 3) for team, v in self.top_speed.items()},
            "end": self._end_reason(),
        }
