"""Where the ball will be, and who can get there first.

The ball rolls straight, slowing at the rolling deceleration until it stops (a lob flies without slowing
until it lands), and the boards stop it at the edge of the floor. Its path is sampled every 0.1 s for 4 s;
a robot's time to reach each sample (from its current velocity, with limited speed and acceleration) is
computed for several robots at once, and the first sample a robot reaches before the ball is its
interception point: a robot runs to where the ball will be, not where it is.
"""

from __future__ import annotations

import math

import numpy as np

GRAVITY = 9.8
STEP = 0.1
TIMES = np.arange(0.0, 4.0 + 1e-9, STEP)          # (K,)
K = len(TIMES)
#: a robot is given this much time to line up and take the ball when it arrives [s]
CATCH_MARGIN = 0.15


class BallPath:
    __slots__ = ("x", "y", "vx", "vy", "speed", "xs", "ys", "stop_t", "stop_x", "stop_y", "land_t", "decel")

    def __init__(self, x: float, y: float, z: float, vx: float, vy: float, vz: float, decel: float,
                 radius: float, xlim: float, ylim: float):
        self.x, self.y, self.vx, self.vy = x, y, vx, vy
        self.decel = decel
        speed = math.hypot(vx, vy)
        self.speed = speed
        # flight: no rolling resistance until it lands
        h = z - radius
        if h > 0.03 or vz > 0.3:
            self.land_t = (vz + math.sqrt(max(0.0, vz * vz + 2.0 * GRAVITY * max(h, 0.0)))) / GRAVITY
        else:
            self.land_t = 0.0
        if speed < 0.05:
            self.xs = np.full(K, x)
            self.ys = np.full(K, y)
            self.stop_t, self.stop_x, self.stop_y = 0.0, x, y
            return
        ux, uy = vx / speed, vy / speed
        roll_t = speed / decel if decel > 0 else math.inf
        self.stop_t = self.land_t + roll_t
        t = TIMES
        tr = np.clip(t - self.land_t, 0.0, roll_t if math.isfinite(roll_t) else None)
        s = speed * np.minimum(t, self.land_t) + speed * tr - 0.5 * decel * tr * tr
        xs, ys = x + ux * s, y + uy * s
        # the boards stop the ball (it bounces back a little; standing still at the edge is close enough)
        np.clip(xs, -xlim, xlim, out=xs)
        np.clip(ys, -ylim, ylim, out=ys)
        self.xs, self.ys = xs, ys
        s_stop = speed * self.land_t + (speed * roll_t - 0.5 * decel * roll_t * roll_t if math.isfinite(roll_t)
                                        else 1e3)
        self.stop_x = min(max(x + ux * s_stop, -xlim), xlim)
        self.stop_y = min(max(y + uy * s_stop, -ylim), ylim)

    def at(self, t: float) -> tuple[float, float]:
        """The ball's predicted position (x, y) in t seconds."""
        if self.speed < 0.05 or t <= 0.0:
            return self.x, self.y
        if t >= self.stop_t:
            return self.stop_x, self.stop_y
        tr = max(0.0, t - self.land_t)
        s = self.speed * (min(t, self.land_t) + tr) - 0.5 * self.decel * tr * tr
        return self.x + self.vx / self.speed * s, self.y + self.vy / self.speed * s

    def speed_at(self, t: float) -> float:
        if t <= self.land_t:
            return self.speed
        return max(0.0, self.speed - self.decel * (t - self.land_t))


def reach_times(px: np.ndarray, py: np.ndarray, vx: np.ndarray, vy: np.ndarray, tx: np.ndarray, ty: np.ndarray,
                vmax: float, acc: float) -> np.ndarray:
    """(R, K) time for each robot (R,) to reach each point (K,), starting from its velocity, speeding up
    at ``acc`` to ``vmax``; the part of its velocity across the way costs time to cancel."""
    dx = tx[None, :] - px[:, None]
    dy = ty[None, :] - py[:, None]
    d = np.hypot(dx, dy) + 1e-9
    vxc, vyc = vx[:, None], vy[:, None]
    vpar = (vxc * dx + vyc * dy) / d
    vperp = np.sqrt(np.maximum(0.0, (vxc * vxc + vyc * vyc) - vpar * vpar))
    v0 = np.clip(vpar, -vmax, vmax)
    back = np.minimum(v0, 0.0)
    t_stop = -back / acc
    D = d + back * back / (2.0 * acc)
    v0 = np.maximum(v0, 0.0)
    d_acc = (vmax * vmax - v0 * v0) / (2.0 * acc)
    t_short = (np.sqrt(v0 * v0 + 2.0 * acc * D) - v0) / acc
    t_long = (vmax - v0) / acc + (D - d_acc) / vmax
    return np.where(D <= d_acc, t_short, t_long) + t_stop + 0.5 * vperp / acc


def intercepts(path: BallPath, px: np.ndarray, py: np.ndarray, vx: np.ndarray, vy: np.ndarray, vmax: float,
               acc: float, extra: np.ndarray | float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For each robot: (time, x, y) of the earliest point of the ball's path it reaches no later than the
    ball (plus its ``extra`` delay, e.g. to turn); the ball's resting point if it reaches none."""
    T = reach_times(px, py, vx, vy, path.xs, path.ys, vmax, acc)
    T += CATCH_MARGIN
    T += np.asarray(extra, dtype=float).reshape(-1, 1) if np.ndim(extra) else extra
    ok = T <= TIMES[None, :]
    k = np.where(ok.any(axis=1), ok.argmax(axis=1), K - 1)
    rows = np.arange(len(px))
    t = np.maximum(TIMES[k], T[rows, k])
    return t, path.xs[k], path.ys[k]
