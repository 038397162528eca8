"""The paper's robot: the NuBot base with four omnidirectional wheels (Table II)."""

from __future__ import annotations

import math

from .base import OmniParams, RobotModel


class Omni4(RobotModel):
    """Four wheels at alpha = pi/4, 3pi/4, -3pi/4, -pi/4, beta = pi/2, d = 0.203 m (paper Table II)."""

    name = "omni4"
    Params = OmniParams
    wheel_angles = (math.pi / 4, 3 * math.pi / 4, -3 * math.pi / 4, -math.pi / 4)
