"""Robot models: what the simulator needs to know about a kind of robot.

A robot model is a plug-in (chosen per team in the scene) that describes an omnidirectional base by its
wheel layout (paper Eq. 2-3), its limits and its body. The simulator builds the physics from it and uses
its wheel matrix to turn every velocity command into wheel speeds, and back.

Collision shapes (chosen for cheap scrums, all analytic colliders in MuJoCo):
* robot against robot, goal or wall: one sphere of the footprint radius, centred at the same height on
  every robot, so robot-robot contacts are horizontal circle-circle contacts (one contact per pair);
* robot against ball: a vertical capsule pushed back from the front, so the front is flattened into a
  mouth where the ball sits partly inside the footprint, as on a real MSL robot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

HULL_HEIGHT = 0.4  # height of every robot's hull sphere centre [m]: keeps robot-robot contacts planar


class OmniParams(BaseModel):
    """Parameters shared by omnidirectional bases (every value can be set per team in the scene)."""

    model_config = ConfigDict(extra="forbid")
    wheel_radius: float = Field(0.0625, gt=0.0, le=0.5, description="[m]")
    wheel_distance: float = Field(0.203, gt=0.0, le=2.0, description="d: wheel centre to robot centre [m]")
    beta: float = Field(math.pi / 2, gt=0.0, lt=math.pi, description="roller deflection angle [rad]")
    max_wheel_speed: float = Field(5.0, gt=0.0, le=50.0, description="rim speed limit [m/s]")
    max_acceleration: float = Field(2.5, gt=0.0, le=100.0, description="rim speeding-up limit [m/s^2]")
    max_deceleration: float = Field(5.0, gt=0.0, le=100.0, description="rim slowing-down limit [m/s^2]")
    mass: float = Field(39.0, gt=1.0, le=500.0, description="[kg]")
    radius: float = Field(0.25, gt=0.05, le=2.0, description="footprint radius [m]")
    height: float = Field(0.8, gt=0.1, le=3.0, description="[m]")
    mouth_depth: float = Field(
        0.07, ge=0.0, le=0.2, description="how far the ball sits inside the footprint when held [m]"
    )
    max_force: float = Field(350.0, gt=0.0, le=1e5, description="largest traction force of the base [N]")
    max_torque: float = Field(120.0, gt=0.0, le=1e5, description="largest turning torque of the base [N m]")
    response_time: float | None = Field(
        None,
        gt=0.0,
        le=1.0,
        description="time constant of the base's velocity servo [s]; default one physics "
        "step (the base follows its wheel speeds at once, as far as traction "
        "allows); must be at least one physics step",
    )


@dataclass(frozen=True)
class Wheel:
    alpha: float  # angle of the wheel centre around the robot centre [rad]
    distance: float  # d [m]


class RobotModel:
    """Base of robot models. Subclasses give ``name``, ``Params`` and ``wheel_angles`` (a wheeled base), or
    set ``locomotion = "aerial"`` (a flying robot, see `simatch.robots.quadrotor`)."""

    name: ClassVar[str] = "robot"
    Params: ClassVar[type[BaseModel]] = OmniParams
    wheel_angles: ClassVar[tuple[float, ...]] = ()
    #: "ground": a planar base driven by its wheels (x, y, yaw); "aerial": a free rigid body in 3D
    locomotion: ClassVar[str] = "ground"

    def __init__(self, params: BaseModel | dict | None = None):
        if params is None:
            params = self.Params()
        elif isinstance(params, dict):
            params = self.Params.model_validate(params)
        self.params = params

    # --- kinematics (paper Eq. 2-3) -------------------------------------------------------------------
    @property
    def wheels(self) -> list[Wheel]:
        return [Wheel(a, self.params.wheel_distance) for a in self.wheel_angles]

    def rim_matrix(self) -> np.ndarray:
        """M with rim speeds u = M v for a body-frame velocity v = (vx, vy, w); M = r A of Eq. (3)."""
        p = self.params
        b, d = p.beta, p.wheel_distance
        rows = [[-math.cos(a + b) / math.sin(b), -math.sin(a + b) / math.sin(b), -d] for a in self.wheel_angles]
        return np.array(rows, dtype=np.float64)

    def wheel_matrix(self) -> np.ndarray:
        """A of Eq. (3): wheel angular speeds W = A v [rad/s]."""
        return self.rim_matrix() / self.params.wheel_radius

    # --- body -------------------------------------------------------------------------------------------
    @property
    def aerial(self) -> bool:
        return self.locomotion == "aerial"

    @property
    def radius(self) -> float:
        """Footprint radius [m] (what others see and avoid)."""
        return self.params.radius

    @property
    def height(self) -> float:
        return self.params.height

    @property
    def mass(self) -> float:
        return self.params.mass

    def inertia(self) -> tuple[float, float, float]:
        """Principal inertia of a uniform box of the footprint and height."""
        p = self.params
        w = 2 * p.radius
        ixx = p.mass * (w * w + p.height * p.height) / 12.0
        izz = p.mass * (w * w + w * w) / 12.0
        return (ixx, ixx, izz)

    def mouth_x(self, ball_radius: float) -> float:
        """Distance from the robot centre to a held ball's centre, along the kicker axis [m]."""
        return self.params.radius - self.params.mouth_depth + ball_radius + self.ball_gap

    ball_gap: ClassVar[float] = 0.004  # air between a held ball and the robot's front [m]

    def ball_collider(self, ball_radius: float) -> tuple[float, float]:
        """(x offset, radius) of the vertical capsule the ball collides with: its front is the mouth."""
        p = self.params
        front = p.radius - p.mouth_depth
        r = p.radius - 0.5 * p.mouth_depth
        return (front - r, r)
