"""Where the ball will be, and who can get there first.

The ball rolls straight, slowing at the rolling deceleration until it stops (a lob flies without slowing
until it lands), and the boards stop it at the edge of the floor. Its path is sampled every 0.1 s for 4 s;
a robot's time to reach each sample (from its current velocity, with limited speed and acceleration) is
computed for all robots at once, and the first sample a robot reaches before the ball is its
interception point: a robot runs to where the ball will be, not where it is.

Where the ball is at a given time is one compiled function, `ball_at`: `BallPath.at` and the sampling
use it. The sampling is a compiled kernel (`_team_intercepts`), run once per team picture for every robot.
"""

from __future__ import annotations

import math

import numpy as np

from ...compiled import Float, Matrix, kernel
from .geometry import _wrap

GRAVITY = 9.8
STEP = 0.1
SAMPLES = 41  # 0 to 4 s
#: a robot is given this much time to line up and take the ball when it arrives [s]
CATCH_MARGIN = 0.15
#: `_intercepts` passes over a sample whose lower bound of the reach time exceeds its time by this much [s]
SKIP_MARGIN = 1e-3


#: the path as the kernels take it (`BallPath.kernel_args`, their first ten parameters)
PATH = dict(
    x=Float,
    y=Float,
    speed=Float,
    ux=Float,
    uy=Float,
    land_t=Float,
    stop_t=Float,
    decel=Float,
    xlim=Float,
    ylim=Float,
)


class BallPath:
    """The ball's predicted path from its current state (team frame)."""

    __slots__ = (
        "x",
        "y",
        "vx",
        "vy",
        "speed",
        "ux",
        "uy",
        "stop_t",
        "land_t",
        "decel",
        "xlim",
        "ylim",
    )

    def __init__(
        self,
        x: float,
        y: float,
        z: float,
        vx: float,
        vy: float,
        vz: float,
        decel: float,
        radius: float,
        xlim: float,
        ylim: float,
    ):
        self.x, self.y, self.vx, self.vy = x, y, vx, vy
        self.decel = decel
        self.xlim, self.ylim = xlim, ylim
        speed = math.hypot(vx, vy)
        self.speed = speed
        # flight: no rolling resistance until it lands
        h = z - radius
        if h > 0.03 or vz > 0.3:
            self.land_t = (vz + math.sqrt(max(0.0, vz * vz + 2.0 * GRAVITY * max(h, 0.0)))) / GRAVITY
        else:
            self.land_t = 0.0
        if speed < 0.05:
            self.ux = self.uy = self.stop_t = 0.0
            return
        self.ux, self.uy = vx / speed, vy / speed
        self.stop_t = self.land_t + (speed / decel if decel > 0 else 1e3)

    def at(self, t: float) -> tuple[float, float]:
        """The ball's predicted position (x, y) in t seconds (`ball_at`)."""
        return ball_at(*self.kernel_args(), t)

    def kernel_args(self) -> tuple:
        """The path as the intercept kernels take it (their first ten arguments, in their order)."""
        return (
            self.x,
            self.y,
            self.speed,
            self.ux,
            self.uy,
            self.land_t,
            self.stop_t,
            self.decel,
            self.xlim,
            self.ylim,
        )


@kernel(**PATH, t=Float)
def ball_at(x, y, speed, ux, uy, land_t, stop_t, decel, xlim, ylim, t):
    """Where the ball of the path (`BallPath.kernel_args`) is in ``t`` seconds: (x, y). It flies straight at
    its speed until ``land_t``, then rolls slowing at ``decel`` until ``stop_t``, and stays; the boards
    (``xlim``, ``ylim``) hold it on the floor. A ball slower than 5 cm/s is taken as lying still."""
    if speed < 0.05:
        return x, y
    tt = min(t, stop_t)
    tr = max(0.0, tt - land_t)
    s = speed * (min(tt, land_t) + tr) - 0.5 * decel * tr * tr
    return min(max(x + ux * s, -xlim), xlim), min(max(y + uy * s, -ylim), ylim)


@kernel
def _intercepts(x, y, speed, ux, uy, land_t, stop_t, decel, xlim, ylim, px, py, vx, vy, extra, vmax, acc, out):
    """For each robot r: out[r] = (time, x, y) of the first sampled point of the ball's path it reaches no
    later than the ball, or of the last sample if it reaches none. Reach time: from velocity (vx, vy),
    the part towards the point kept (cancelled first if away), speeding up at ``acc`` to ``vmax``; the part
    across the way costs half its cancelling time; plus ``extra`` and CATCH_MARGIN.

    A sample the robot cannot reach in time even straight at top speed (its reach time is at least
    d / vmax + CATCH_MARGIN + extra, whatever its velocity) is passed over after its distance, by a margin
    (SKIP_MARGIN) far beyond the rounding of either side: the same samples reached, the same numbers."""
    bounded = vmax > 0.0 and acc > 0.0
    last = SAMPLES - 1
    # the ball's samples, once for all the robots
    sx = np.empty(SAMPLES)
    sy = np.empty(SAMPLES)
    for k in range(SAMPLES):
        sx[k], sy[k] = ball_at(x, y, speed, ux, uy, land_t, stop_t, decel, xlim, ylim, k * STEP)
    for r in range(px.shape[0]):
        for k in range(SAMPLES):
            t = k * STEP
            bx, by = sx[k], sy[k]
            dx, dy = bx - px[r], by - py[r]
            d = math.sqrt(dx * dx + dy * dy) + 1e-9
            if bounded and k < last and d > (t + SKIP_MARGIN - CATCH_MARGIN - extra[r]) * vmax:
                continue  # (out of reach at this sample: reach > t)
            vpar = (vx[r] * dx + vy[r] * dy) / d
            vperp = math.sqrt(max(0.0, vx[r] * vx[r] + vy[r] * vy[r] - vpar * vpar))
            v0 = min(max(vpar, -vmax), vmax)
            t_stop = 0.0
            if v0 < 0.0:
                t_stop = -v0 / acc
                d += v0 * v0 / (2.0 * acc)
                v0 = 0.0
            d_acc = (vmax * vmax - v0 * v0) / (2.0 * acc)
            if d <= d_acc:
                reach = (math.sqrt(v0 * v0 + 2.0 * acc * d) - v0) / acc
            else:
                reach = (vmax - v0) / acc + (d - d_acc) / vmax
            reach += t_stop + 0.5 * vperp / acc + CATCH_MARGIN + extra[r]
            if reach <= t or k == SAMPLES - 1:
                out[r, 0] = max(t, reach)
                out[r, 1] = bx
                out[r, 2] = by
                break


def intercepts(
    path: BallPath,
    px: np.ndarray,
    py: np.ndarray,
    vx: np.ndarray,
    vy: np.ndarray,
    vmax: float,
    acc: float,
    extra: np.ndarray | None = None,
) -> np.ndarray:
    """(R, 3): for each robot, (time, x, y) of the earliest point of the ball's path it reaches no later
    than the ball (plus its ``extra`` delay, e.g. to turn); the last sampled point if it reaches none."""
    n = len(px)
    out = np.empty((n, 3))
    if extra is None:
        extra = np.zeros(n)
    _intercepts(
        *path.kernel_args(),
        px,
        py,
        vx,
        vy,
        extra,
        vmax,
        acc,
        out,
    )
    return out


@kernel
def _team_rows(us, opps, bx, by, turn):
    """The rows of `team_intercepts`: x, y, vx, vy and the extra delay of each robot, ours first (the time
    to turn to face the ball at (bx, by): ``turn`` seconds per radian), then theirs (none)."""
    n, m = us.shape[0], opps.shape[0]
    px = np.empty(n + m)
    py = np.empty(n + m)
    vx = np.empty(n + m)
    vy = np.empty(n + m)
    extra = np.empty(n + m)
    for k in range(n):
        px[k], py[k], vx[k], vy[k] = us[k, 0], us[k, 1], us[k, 2], us[k, 3]
        extra[k] = turn * abs(_wrap(math.atan2(by - us[k, 1], bx - us[k, 0]) - us[k, 5]))
    for k in range(m):
        px[n + k], py[n + k], vx[n + k], vy[n + k] = opps[k, 0], opps[k, 1], opps[k, 2], opps[k, 3]
        extra[n + k] = 0.0
    return px, py, vx, vy, extra


def team_intercepts(
    path: BallPath,
    us: np.ndarray,
    opps: np.ndarray,
    bx: float,
    by: float,
    turn: float,
    vmax: float,
    acc: float,
) -> np.ndarray:
    """`intercepts` of our robots ``us`` ((K, 6+): x, y, vx, vy, id, yaw first: the team view's table), who
    first turn to face the ball at (bx, by) at ``turn`` seconds per radian, then of the opponents ``opps`` ((M, 4):
    x, y, vx, vy): (K + M, 3). One kernel call (`_team_intercepts`): the rows and the reach times, no arrays
    handed back and forth."""
    out = np.empty((us.shape[0] + opps.shape[0], 3))
    _team_intercepts(
        *path.kernel_args(),
        us,
        opps,
        bx,
        by,
        turn,
        vmax,
        acc,
        out,
    )
    return out


@kernel(
    **PATH,
    us=Matrix,
    opps=Matrix,
    bx=Float,
    by=Float,
    turn=Float,
    vmax=Float,
    acc=Float,
    out=Matrix,
)
def _team_intercepts(x, y, speed, ux, uy, land_t, stop_t, decel, xlim, ylim, us, opps, bx, by, turn, vmax, acc, out):
    """`team_intercepts` compiled: `_team_rows`, then `_intercepts` of them into ``out``."""
    px, py, vx, vy, extra = _team_rows(us, opps, bx, by, turn)
    _intercepts(x, y, speed, ux, uy, land_t, stop_t, decel, xlim, ylim, px, py, vx, vy, extra, vmax, acc, out)
