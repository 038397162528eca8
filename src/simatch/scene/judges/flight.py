"""The flight test of an aerial robot (``judge.kind = "flight_test"``), as the locomotion test is the wheeled
robot's: the judge is the test bench. It flies one drone through a fixed programme with the commands any
strategy sends (VelCmd on the drone's topic), measures the drone's exact states every physics step and
reports, in SI units:

1. **take-off and hover**: from the floor, motors off, climb at ``climb`` m/s to ``altitude``, then hold
   still for ``hover`` seconds: the largest height error and horizontal drift from the hold point, after
   ``settle`` seconds;
2. **steps**: a ``step`` m/s command along x (forward), y (left) and z (up), each held ``step_time``
   seconds then released: rise time (10 % to 90 % of the step), overshoot, settling time (within 5 %), and
   the largest tilt on the way;
3. **full-thrust climb**: the largest upward command for ``full_climb`` seconds: the steady climb rate
   (mean over the last second) against what thrust-to-weight and rotor drag allow,
   (thrust_to_weight m g0 - m g) / drag_z;
4. **cut rotor**: back down at ``altitude``, hover, then rotor 1 is cut (`set_rotor`): how long the drone
   takes to fall ``fall_height`` metres, and how low it ever gets (it lands on the floor, never through).

The drone's team plays no strategy (``strategy = "none"``): nothing but the test commands it.
"""

from __future__ import annotations

import math

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from ... import msgs
from ...bus import NodeContext, topics
from ...config.loader import SceneError
from ...robots import model_class
from ...robots.quadrotor import STANDARD_GRAVITY
from .base import Judge


class FlightTestParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    robot: str = Field("", description="drone under test (default: the scene's first robot)")
    altitude: float = Field(1.5, gt=0.2, le=50.0, description="hover height [m]")
    climb: float = Field(1.0, gt=0.0, le=10.0, description="take-off climb rate [m/s]")
    hover: float = Field(60.0, gt=0.0, le=3600.0, description="hover hold [s]")
    settle: float = Field(2.0, ge=0.0, le=60.0, description="hover measured from this long after reaching it [s]")
    step: float = Field(1.0, gt=0.0, le=10.0, description="size of each velocity step [m/s]")
    step_time: float = Field(4.0, gt=0.5, le=60.0, description="each step held this long, then as long at rest [s]")
    full_climb: float = Field(6.0, gt=1.0, le=60.0, description="full-thrust climb [s]")
    fall_height: float = Field(1.0, gt=0.1, le=20.0, description="the cut-rotor fall is timed over this [m]")
    cut_after: float = Field(3.0, gt=0.0, le=60.0, description="hover this long before the rotor is cut [s]")
    fall_time: float = Field(4.0, gt=0.5, le=60.0, description="watch the fall this long [s]")


class FlightTest(Judge):
    Params = FlightTestParams
    name = "flight_test"

    def __init__(self, scene, params, world):
        super().__init__(scene, params, world)
        spec = scene.spec
        self.robot = params.robot or spec.robot_names()[0]
        team, _, rid = self.robot.partition("/")
        member = spec.member(self.robot)
        if member is None:
            raise SceneError(f"{scene.source}: judge.robot: the scene has no robot {self.robot!r}")
        self.model = model_class(member.model)(member.model_params)
        if not self.model.aerial:
            raise SceneError(f"{scene.source}: judge.robot: {self.robot} is a {member.model}, not an aerial robot")
        self.team, self.rid = team, int(rid)
        self.dt = spec.physics.timestep
        self.period = self.dt
        self.g = spec.physics.gravity
        p = params
        # the programme: (phase, seconds, vx, vy, vz); the take-off lasts until the hover height is reached
        self.programme = [("takeoff", math.inf, 0.0, 0.0, p.climb), ("hover", p.hover, 0.0, 0.0, 0.0)]
        for axis, (vx, vy, vz) in (("x", (p.step, 0, 0)), ("y", (0, p.step, 0)), ("z", (0, 0, p.step))):
            self.programme += [(f"step_{axis}", p.step_time, vx, vy, vz), (f"rest_{axis}", p.step_time, 0, 0, 0)]
        top = self.model.params.max_climb
        self.programme += [
            ("full_climb", p.full_climb, 0.0, 0.0, top),
            ("brake", 4.0, 0.0, 0.0, 0.0),
            ("descend", math.inf, 0.0, 0.0, -self.model.params.max_descent),
            ("before_cut", p.cut_after, 0.0, 0.0, 0.0),
            ("cut", p.fall_time, 0.0, 0.0, 0.0),
        ]
        self.phase = 0
        self.phase_start = 0.0
        self.samples: dict[str, list] = {name: [] for name, *_ in self.programme}
        self.cut_at: float | None = None

    @property
    def duration(self) -> float | None:
        """A bound: the programme's timed phases plus a minute each for the take-off and the descent (the
        run ends when the programme is done)."""
        return sum(seconds for _, seconds, *_ in self.programme if math.isfinite(seconds)) + 120.0

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        self.pub_vel = ctx.bus.publisher(topics.robot_topic(self.team, self.rid, topics.VEL_CMD), msgs.VelCmd)

    def tick(self, now: float) -> None:
        if self.done:
            return
        st = self.world.model_states()[self.robot]
        name, seconds, vx, vy, vz = self.programme[self.phase]
        elapsed = now - self.phase_start
        reached = (name == "takeoff" and st.z >= self.params.altitude) or (
            name == "descend" and st.z <= self.params.altitude
        )
        if reached or elapsed >= seconds - 1e-9:
            self.phase += 1
            self.phase_start = now
            if self.phase == len(self.programme):
                self.done = True
                return
            name, seconds, vx, vy, vz = self.programme[self.phase]
            if name == "cut":
                self.world.set_rotor(self.robot, 1, False)
                self.cut_at = now
        tilt = math.degrees(math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (st.qx * st.qx + st.qy * st.qy)))))
        self.samples[name].append((now - self.phase_start, st.x, st.y, st.z, st.vx, st.vy, st.vz, tilt))
        # the command in the heading frame (the drone keeps its heading: no turn is commanded)
        c, s = math.cos(st.yaw), math.sin(st.yaw)
        bx, by = c * vx + s * vy, -s * vx + c * vy
        self.pub_vel.put(msgs.VelCmd(stamp=now, tick=0, vx=bx, vy=by, w=0.0, vz=vz))

    # --- figures ---------------------------------------------------------------------------------------------
    def _array(self, name: str) -> np.ndarray:
        return np.array(self.samples[name]).reshape(-1, 8)

    def _hover(self) -> dict:
        a = self._array("hover")
        a = a[a[:, 0] >= self.params.settle]
        if not len(a):
            return {}
        z0, x0, y0 = a[0, 3], a[0, 1], a[0, 2]
        return {
            "seconds": round(float(a[-1, 0] - a[0, 0]), 3),
            "height_error_max_m": float(np.abs(a[:, 3] - z0).max()),
            "drift_max_m": float(np.hypot(a[:, 1] - x0, a[:, 2] - y0).max()),
            "drift_per_minute_m": float(np.hypot(a[-1, 1] - x0, a[-1, 2] - y0) / max(a[-1, 0] - a[0, 0], 1e-9) * 60),
        }

    def _step(self, axis: str) -> dict:
        a = self._array(f"step_{axis}")
        rest = self._array(f"rest_{axis}")
        if not len(a):
            return {}
        col = {"x": 4, "y": 5, "z": 6}[axis]
        t, v, size = a[:, 0], a[:, col], self.params.step
        out: dict = {"command_m_s": size}
        up10, up90 = np.flatnonzero(v >= 0.1 * size), np.flatnonzero(v >= 0.9 * size)
        if len(up10) and len(up90):
            out["rise_time_s"] = round(float(t[up90[0]] - t[up10[0]]), 3)
        out["overshoot_pct"] = round(float(max(0.0, v.max() - size) / size * 100.0), 2)
        outside = np.flatnonzero(np.abs(v - size) > 0.05 * size)
        out["settling_time_s"] = round(
            float(t[outside[-1] + 1]) if len(outside) and outside[-1] + 1 < len(t) else 0.0, 3
        )
        out["final_m_s"] = round(float(v[-1]), 4)
        out["tilt_max_deg"] = round(float(a[:, 7].max()), 2)
        if len(rest):
            out["stop_overshoot_pct"] = round(float(max(0.0, -rest[:, col].min()) / size * 100.0), 2)
        return out

    def _climb(self) -> dict:
        a = self._array("full_climb")
        if not len(a):
            return {}
        p, m = self.model.params, self.model.mass
        lift = p.thrust_to_weight * m * STANDARD_GRAVITY
        expected = (lift - m * self.g) / p.drag_z if p.drag_z > 0 else math.inf
        last = a[a[:, 0] >= a[-1, 0] - 1.0]
        return {
            "command_m_s": p.max_climb,
            "climb_rate_m_s": round(float(last[:, 6].mean()), 4),
            "expected_m_s": round(expected, 4),
            "thrust_to_weight": p.thrust_to_weight,
        }

    def _cut(self) -> dict:
        a = self._array("cut")
        if not len(a):
            return {}
        z0 = a[0, 3]
        below = np.flatnonzero(a[:, 3] <= z0 - self.params.fall_height)
        return {
            "start_height_m": round(float(z0), 4),
            "fall_time_s": round(float(a[below[0], 0]), 3) if len(below) else None,
            "lowest_m": round(float(a[:, 3].min()), 4),
            "fell_m": round(float(z0 - a[:, 3].min()), 4),
            "frame_half_height_m": self.model.collision_half_sizes()[2],
        }

    def result(self) -> dict:
        takeoff = self._array("takeoff")
        return {
            "robot": self.robot,
            "done": self.done,
            "takeoff_s": round(float(takeoff[-1, 0]), 3) if len(takeoff) else None,
            "hover": self._hover(),
            "steps": {axis: self._step(axis) for axis in "xyz"},
            "full_climb": self._climb(),
            "cut_rotor": self._cut(),
        }
