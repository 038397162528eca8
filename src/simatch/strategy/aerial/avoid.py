"""Getting round the world's static obstacles (`FieldGeometry.obstacles`, team frame), reactively.

A ground robot's wished velocity loses the part that would take it into an obstacle it is closing on, and
gains as much along the obstacle's surface, on the side the wish leans to: it slides round a box or a
pillar instead of pushing into it. A place to stand that lies in or against an obstacle is moved out to
where a robot fits. Aerial robots fly over obstacles lower than their altitude and ignore them.
"""

from __future__ import annotations

import math

from ...field import FieldGeometry


def steer(x: float, y: float, vx: float, vy: float, field: FieldGeometry, radius: float, reach: float = 0.8, z=None):
    """(vx, vy) turned round every obstacle within ``reach`` of the robot's outline (radius ``radius``); for a
    robot flying at height ``z``, round those that reach up to it (with ``radius`` to spare)."""
    for ob in field.obstacles:
        if (z is not None and ob.height < z - radius) or not ob.near(x, y, radius + reach):
            continue
        gap = ob.distance(x, y) - radius
        if gap > reach:
            continue
        nx, ny = ob.away(x, y)
        inward = -(vx * nx + vy * ny)
        if inward <= 0.0:
            continue
        w = min(1.0, (reach - max(gap, 0.0)) / reach)
        tx, ty = -ny, nx
        if vx * tx + vy * ty < 0.0:
            tx, ty = -tx, -ty
        vx += (nx + tx) * inward * w
        vy += (ny + ty) * inward * w
    return vx, vy


def clear_spot(x: float, y: float, field: FieldGeometry, radius: float) -> tuple[float, float]:
    """(x, y), or the nearest point outside every obstacle where a robot of ``radius`` fits."""
    for _ in range(4):
        ob = field.obstacle_at(x, y, radius + 0.05)
        if ob is None:
            break
        nx, ny = ob.away(x, y)
        push = radius + 0.05 - ob.distance(x, y)
        x, y = x + nx * push, y + ny * push
    return x, y


def velocity_to(x, y, tx, ty, speed, gain: float = 2.5) -> tuple[float, float]:
    """World velocity towards (tx, ty): proportional to the distance, capped at ``speed``."""
    dx, dy = tx - x, ty - y
    d = math.hypot(dx, dy)
    if d < 1e-9:
        return 0.0, 0.0
    v = min(speed, gain * d)
    return dx / d * v, dy / d * v


def body_frame(vx: float, vy: float, yaw: float) -> tuple[float, float]:
    c, s = math.cos(yaw), math.sin(yaw)
    return c * vx + s * vy, -s * vx + c * vy
