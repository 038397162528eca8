"""Aerial robot models written outside simatch (named in a scene as tests.aerial.plugin_drone:Class): a
quadrotor flown in the "+" layout (rotors on the nose, the left, the tail and the right) with a longer arm
and a heavier frame, which flies; and a hexarotor, which the simulator cannot fly and refuses by name."""

from __future__ import annotations

import math

from pydantic import Field

from simatch.robots.base import RobotModel
from simatch.robots.quadrotor import Quadrotor, QuadrotorParams


class PlusParams(QuadrotorParams):
    mass: float = Field(0.05, gt=0.005, le=50.0, description="[kg]")
    arm_length: float = Field(0.06, gt=0.01, le=2.0, description="[m]")


class PlusQuad(Quadrotor):
    name = "plus_quad"
    Params = PlusParams
    rotor_angles = (0.0, math.pi / 2, math.pi, -math.pi / 2)


class Hexarotor(Quadrotor):
    name = "hexarotor"
    rotor_angles = tuple(math.pi / 6 + k * math.pi / 3 for k in range(6))
    rotor_spin = (1, -1, 1, -1, 1, -1)


class Hovercraft(RobotModel):
    name = "hovercraft"
    locomotion = "floating"
