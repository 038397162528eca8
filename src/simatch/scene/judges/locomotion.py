"""The paper's omnidirectional locomotion test (section VII-A) as a judge.

A robot starting at rest at (0, 0, 0) is commanded a constant body-frame velocity (vx, vy, w); with w != 0
the given circle has radius |v|/w and centre (-vy, vx)/w. Its pose is sampled every physics step and two
indicators are reported in the paper's units:

* position_error_cm: mean | distance to the circle's centre - radius |;
* orientation_error_rad: mean | actual heading - w t | (wrapped).

A robot that speeds up from rest under the wheel acceleration limit necessarily lags w t by a constant,
so the judge also integrates the ideal kinematic model with the same wheel limits (no physics) and reports
its orientation error as orientation_error_expected_rad: the physics is right when the two agree.
"""

from __future__ import annotations

import math

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from ... import msgs
from ...bus import NodeContext, topics
from ...robots import model_class
from ...robots.drive import OmniDrive
from .base import Judge

PAPER = {"samples": 1704, "position_error_cm": 2.2481, "orientation_error_rad": 0.4401}


class LocomotionParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    robot: str = Field("", description="robot under test (default: the scene's first robot)")
    vx: float = Field(2.0, description="commanded forward speed [m/s] (paper: 200 cm/s)")
    vy: float = Field(0.0, description="commanded leftward speed [m/s]")
    w: float = Field(2.0, description="commanded turn rate [rad/s]")
    duration: float = Field(25.56, gt=0.0, description="length of the test [s]")


class LocomotionTest(Judge):
    Params = LocomotionParams
    name = "locomotion_test"

    def __init__(self, scene, params, world):
        super().__init__(scene, params, world)
        spec = scene.spec
        self.robot = params.robot or spec.robot_names()[0]
        team, _, rid = self.robot.partition("/")
        tspec = spec.teams[team]
        self.dt = spec.physics.timestep
        self.control_steps = round(spec.control.period / self.dt)
        self.period = self.dt
        self.n_samples = int(round(params.duration / self.dt))
        self.samples: list[tuple[float, float, float, float]] = []  # (t, x, y, yaw)
        self._model = model_class(tspec.model)(tspec.model_params)
        self._index = None
        self._latest = None

    @property
    def duration(self):
        return self.n_samples * self.dt  # samples at t = 0, dt, ..., duration - dt

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        self.sub = ctx.bus.subscribe(topics.MODEL_STATES, msgs.ModelStates, self._on_states)

    def _on_states(self, msg) -> None:
        self._latest = msg

    def tick(self, now: float) -> None:
        msg = self._latest
        if msg is None or self.done:
            return
        if self._index is None:
            self._index = list(msg.name).index(self.robot)
        k = self._index
        x, y, _, qw, _, _, qz = msg.pose[7 * k : 7 * k + 7]
        self.samples.append((msg.stamp, float(x), float(y), 2.0 * math.atan2(qz, qw)))
        if len(self.samples) >= self.n_samples:
            self.done = True

    def stop(self) -> None:
        self.sub.close()

    # --- indicators ----------------------------------------------------------------------------------------
    def _circle(self) -> tuple[float, float, float] | None:
        p = self.params
        if abs(p.w) < 1e-12:
            return None
        return (-p.vy / p.w, p.vx / p.w, math.hypot(p.vx, p.vy) / abs(p.w))

    def ideal_trajectory(self) -> np.ndarray:
        """(K, 4): t, x, y, yaw of the ideal kinematic robot with the same wheel limits (no physics)."""
        m = self._model
        q = m.params
        drive = OmniDrive([m.rim_matrix()], q.max_wheel_speed, q.max_acceleration, q.max_deceleration, self.dt)
        drive.command(0, self.params.vx, self.params.vy, self.params.w)
        window = self.control_steps
        due = np.ones(1, dtype=bool)
        V = np.zeros((1, 3))
        bounds, rate, bias = np.zeros((1, 3, 2)), np.zeros((1, 3)), np.zeros((1, 3))
        x = y = yaw = 0.0
        out = np.empty((self.n_samples, 4))
        for k in range(self.n_samples):
            out[k] = (k * self.dt, x, y, yaw)
            if k % window == 0:
                drive.plan(due, V, window, bounds, rate, bias, np.ones((1, 3)))
            V = np.clip(V + rate * self.dt, bounds[:, :, 0], bounds[:, :, 1])
            vx, vy, w = V[0]
            mid = yaw + 0.5 * w * self.dt  # exact arc of a constant twist, to second order
            c, s = math.cos(mid), math.sin(mid)
            x += (c * vx - s * vy) * self.dt
            y += (s * vx + c * vy) * self.dt
            yaw += w * self.dt
        return out

    def _indicators(self, traj: np.ndarray) -> tuple[float, float]:
        t, x, y, yaw = traj[:, 0], traj[:, 1], traj[:, 2], traj[:, 3]
        circle = self._circle()
        if circle is None:
            pos = float(np.mean(np.hypot(x, y))) * 100.0
        else:
            cx, cy, r = circle
            pos = float(np.mean(np.abs(np.hypot(x - cx, y - cy) - r))) * 100.0
        err = np.abs((yaw - self.params.w * t + np.pi) % (2 * np.pi) - np.pi)
        return pos, float(np.mean(err))

    def result(self) -> dict:
        if not self.samples:
            return {"samples": 0}
        actual = np.array(self.samples)
        pos, ori = self._indicators(actual)
        ideal = self.ideal_trajectory()[: len(actual)]
        ideal_pos, ideal_ori = self._indicators(ideal)
        p = self.params
        circle = self._circle()
        return {
            "samples": len(actual),
            "position_error_cm": pos,
            "orientation_error_rad": ori,
            "orientation_error_expected_rad": ideal_ori,
            "position_error_expected_cm": ideal_pos,
            "orientation_error_vs_ideal_rad": abs(ori - ideal_ori),
            "robot": self.robot,
            "command": {"vx": p.vx, "vy": p.vy, "w": p.w},
            "circle": None if circle is None else {"cx": circle[0], "cy": circle[1], "radius": circle[2]},
            "duration_s": len(actual) * self.dt,
            "paper": PAPER,
        }
