"""World frame and team frames.

World frame: origin at the field centre, +x towards magenta's goal, z up. A team's frame is the world
frame if the team attacks +x (sign +1), and the world turned by pi about z if it attacks -x (sign -1,
magenta by default), so every team believes it attacks +x. The transform is its own inverse.
"""

from __future__ import annotations

import math


def point(sign: int, x: float, y: float) -> tuple[float, float]:
    """A point (or a velocity) from world to team frame, or back."""
    return (sign * x, sign * y)


def yaw(sign: int, heading: float) -> float:
    """A heading from world to team frame, or back, wrapped to [-pi, pi]."""
    return heading if sign > 0 else math.remainder(heading + math.pi, 2.0 * math.pi)


def wrap(angle: float) -> float:
    """An angle wrapped to [-pi, pi]."""
    return math.remainder(angle, 2.0 * math.pi)
