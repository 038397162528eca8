"""What each robot can see: sight lines blocked by obstacles, a drone camera's cone, a range (all switchable
in the scene's ``[perception]``, all off by default: then every robot sees everything).

* ``line_of_sight``: a robot sees another robot (or the ball) only if the straight line from its eye to
  the other's top (a drone's centre, the ball's centre) passes through no static obstacle of the world. A
  ground robot's eye is at its top; a drone's at its centre. Robots do not hide each other.
* ``camera_footprint``: a drone sees only what lies within the cone of its downward camera: below it, no
  farther out than its height above the thing times the tangent of the camera's half-angle
  (``model_params.camera_half_angle``).
* ``ground_range``: a ground robot sees nothing farther than this (3D distance from its eye): its camera's
  reach. A drone's reach is its cone.

The test is one compiled call per control period for all robots (segments against boxes and cylinders,
exact).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..compiled import kernel

BOX, CYLINDER = 0, 1
#: a static obstacle as the sight lines test it: its shape (`BOX` or `CYLINDER`), centre, heading, half sizes
#: (a cylinder's radius in ``half_x``) and height, solid from the floor up [m, rad]
OBSTACLE = np.dtype([(name, np.float64) for name in ("shape", "x", "y", "yaw", "half_x", "half_y", "height")])


@dataclass
class Sight:
    aerial: np.ndarray  # (N,) bool
    eye: np.ndarray  # (N,) height of the eye above the robot's origin [m]
    top: np.ndarray  # (N,) height of the point others look at above the robot's origin [m]
    cone: np.ndarray  # (N,) tangent of a drone camera's half-angle (0 for ground robots)
    obstacles: np.ndarray  # (K,) `OBSTACLE` records
    line_of_sight: bool
    footprint: bool
    ground_range: float  # 0: no limit

    @classmethod
    def of(cls, models, field, spec) -> Sight | None:
        """The sight rules of a scene's robots (``models``) in its world (``field``); None if every robot
        sees everything."""
        aerial = np.array([m.aerial for m in models], dtype=bool)
        los = bool(spec.line_of_sight and field.obstacles)
        footprint = bool(spec.camera_footprint and aerial.any())
        if not (los or footprint or spec.ground_range is not None):
            return None
        heights = np.array([0.0 if m.aerial else m.height for m in models])
        cone = np.array(
            [math.tan(math.radians(m.params.camera_half_angle)) if m.aerial else 0.0 for m in models], dtype=float
        )
        rows = [
            (CYLINDER, o.x, o.y, 0.0, o.radius, 0.0, o.height)
            if o.shape == "cylinder"
            else (BOX, o.x, o.y, o.yaw, o.half_x, o.half_y, o.height)
            for o in field.obstacles
        ]
        obstacles = np.array(rows, dtype=OBSTACLE)
        return cls(aerial, heights, heights, cone, obstacles, los, footprint, float(spec.ground_range or 0.0))

    def visible(self, R: np.ndarray, Z: np.ndarray, ball: np.ndarray, others: np.ndarray):
        """(n, n-1) whether each robot sees each other robot (in the order of ``others``), and (n,) whether it
        sees the ball; R (n, 6) planar states, Z (n,) heights of the robots' origins, ball (6,)."""
        return sight_lines(
            R,
            Z,
            ball,
            others,
            self.aerial,
            self.eye,
            self.top,
            self.cone,
            self.obstacles,
            self.line_of_sight,
            self.footprint,
            self.ground_range,
        )


@kernel
def _clip(t0, t1, p, d, lo, hi):
    """Narrow [t0, t1] to where p + t d lies in [lo, hi]."""
    if abs(d) < 1e-12:
        if p < lo or p > hi:
            return 1.0, 0.0
        return t0, t1
    a = (lo - p) / d
    b = (hi - p) / d
    if a > b:
        a, b = b, a
    return max(t0, a), min(t1, b)


@kernel
def blocked(x0, y0, z0, x1, y1, z1, obstacles):
    """Whether the segment from (x0, y0, z0) to (x1, y1, z1) passes through any obstacle (solid from the
    floor up to its height)."""
    dx, dy, dz = x1 - x0, y1 - y0, z1 - z0
    L2 = dx * dx + dy * dy
    for k in range(obstacles.shape[0]):
        o = obstacles[k]
        cx, cy, a, b = o.x, o.y, o.half_x, o.half_y
        # quick rejection: the segment's horizontal distance from the centre against the bounding circle
        reach = a if o.shape == CYLINDER else math.sqrt(a * a + b * b)
        if L2 > 0.0:
            t = min(max(((cx - x0) * dx + (cy - y0) * dy) / L2, 0.0), 1.0)
        else:
            t = 0.0
        ex, ey = x0 + t * dx - cx, y0 + t * dy - cy
        if ex * ex + ey * ey > reach * reach:
            continue
        t0, t1 = _clip(0.0, 1.0, z0, dz, 0.0, o.height)
        if t0 >= t1:
            continue
        px, py = x0 - cx, y0 - cy
        if o.shape == CYLINDER:
            # |p + t d|^2 <= r^2 (horizontal)
            qa = L2
            qb = 2.0 * (px * dx + py * dy)
            qc = px * px + py * py - a * a
            if qa < 1e-12:
                if qc > 0.0:
                    continue
            else:
                disc = qb * qb - 4.0 * qa * qc
                if disc <= 0.0:
                    continue
                sq = math.sqrt(disc)
                t0 = max(t0, (-qb - sq) / (2.0 * qa))
                t1 = min(t1, (-qb + sq) / (2.0 * qa))
        else:
            c, s = math.cos(o.yaw), math.sin(o.yaw)
            lx, ly = c * px + s * py, -s * px + c * py
            ldx, ldy = c * dx + s * dy, -s * dx + c * dy
            t0, t1 = _clip(t0, t1, lx, ldx, -a, a)
            t0, t1 = _clip(t0, t1, ly, ldy, -b, b)
        if t1 - t0 > 1e-9:
            return True
    return False


@kernel
def _sees(i, tx, ty, tz, R, Z, aerial, eye, cone, obstacles, los, footprint, max_range):
    ex, ey, ez = R[i, 0], R[i, 1], Z[i] + eye[i]
    dx, dy, dz = tx - ex, ty - ey, tz - ez
    if max_range > 0.0 and not aerial[i] and dx * dx + dy * dy + dz * dz > max_range * max_range:
        return False
    if footprint and aerial[i]:
        drop = -dz
        if drop <= 0.0 or dx * dx + dy * dy > (drop * cone[i]) ** 2:
            return False
    if los and blocked(ex, ey, ez, tx, ty, tz, obstacles):
        return False
    return True


@kernel
def sight_lines(R, Z, ball, others, aerial, eye, top, cone, obstacles, los, footprint, max_range):
    n, m = others.shape
    vis = np.empty((n, m), dtype=np.bool_)
    ball_vis = np.empty(n, dtype=np.bool_)
    for i in range(n):
        for k in range(m):
            j = others[i, k]
            vis[i, k] = _sees(
                i, R[j, 0], R[j, 1], Z[j] + top[j], R, Z, aerial, eye, cone, obstacles, los, footprint, max_range
            )
        ball_vis[i] = _sees(i, ball[0], ball[1], ball[2], R, Z, aerial, eye, cone, obstacles, los, footprint, max_range)
    return vis, ball_vis
