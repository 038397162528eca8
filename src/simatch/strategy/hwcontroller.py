"""The robot's low-level controller (the original's nubot_hwcontroller): from a target pose to a
body-frame velocity command, with a proportional law on position and on heading, capped by the limits
the strategy (or the coach) allows."""

from __future__ import annotations

import math

POSITION_GAIN = 5.0  # [1/s]: speed = gain x distance, capped
HEADING_GAIN = 2.0  # [1/s]
ALTITUDE_GAIN = 1.5  # [1/s]: an aerial robot's climb towards a commanded altitude


def velocity_towards(x: float, y: float, yaw: float, cmd, max_vel: float, max_w: float) -> tuple[float, float, float]:
    """Body-frame (vx, vy, w) that drives a robot at (x, y, yaw) (team frame) towards ``cmd.target`` and
    ``cmd.target_ori``, with the feed-forward ``cmd.target_vel``."""
    vx_w = vy_w = 0.0
    if cmd.target is not None:
        dx, dy = cmd.target[0] - x, cmd.target[1] - y
        dist = math.hypot(dx, dy)
        speed = min(POSITION_GAIN * dist, max_vel)
        if dist > 1e-9:
            vx_w, vy_w = dx / dist * speed, dy / dist * speed
        vx_w += cmd.target_vel[0]
        vy_w += cmd.target_vel[1]
        norm = math.hypot(vx_w, vy_w)
        if norm > max_vel:
            vx_w, vy_w = vx_w / norm * max_vel, vy_w / norm * max_vel
    w = 0.0
    if cmd.target_ori is not None:
        err = math.remainder(cmd.target_ori - yaw, 2 * math.pi)
        w = max(-max_w, min(max_w, HEADING_GAIN * err))
    c, s = math.cos(yaw), math.sin(yaw)
    return (c * vx_w + s * vy_w, -s * vx_w + c * vy_w, w)


def climb_towards(z: float, altitude: float, max_vz: float) -> float:
    """Upward speed that takes an aerial robot at height ``z`` to ``altitude``, capped at ``max_vz``."""
    return max(-max_vz, min(max_vz, ALTITUDE_GAIN * (altitude - z)))
