"""A three-wheel omnidirectional base (wheels 120 degrees apart), the second robot model that proves robot
models are plug-ins: with three wheels the wheel matrix is square and every limit acts on three wheels."""

from __future__ import annotations

import math

from pydantic import Field

from .base import OmniParams, RobotModel


class Omni3Params(OmniParams):
    wheel_radius: float = Field(0.05, gt=0.0, le=0.5)
    wheel_distance: float = Field(0.2, gt=0.0, le=2.0)
    mass: float = Field(30.0, gt=1.0, le=500.0)
    radius: float = Field(0.24, gt=0.05, le=2.0)
    height: float = Field(0.7, gt=0.1, le=3.0)
    max_force: float = Field(270.0, gt=0.0, le=1e5)
    max_torque: float = Field(90.0, gt=0.0, le=1e5)


class Omni3(RobotModel):
    """Three wheels at alpha = pi/3, pi, -pi/3 (one wheel at the back), beta = pi/2."""

    name = "omni3"
    Params = Omni3Params
    wheel_angles = (math.pi / 3, math.pi, -math.pi / 3)
