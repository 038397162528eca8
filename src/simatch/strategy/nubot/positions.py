"""Where the robots without the ball stand: the areas they must respect and the points of each role.

All in the team frame (own goal at -x). Areas: a field robot's centre stays out of its own penalty area
(only the goalkeeper lives there) and out of the opponents' goal area; only the robot playing the ball
enters the opponents' penalty area.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np

from ...compiled import Array, Bool, Float, bind, kernel
from .geometry import _clamp, box_exit, push_out_of_box, segment_hits_box


class Box(NamedTuple):
    """An area of the field as a field robot must respect it: x from ``x0`` to ``x1``, y within
    +-``half_width`` (widened by the margin of `Areas`)."""

    x0: float
    x1: float
    half_width: float


class Pitch(NamedTuple):
    """The fixed numbers of the field the kernels read, in the team frame: the field's half length and half
    width, the penalty areas' depth and half width (their lines), and the boxes a field robot keeps out of
    (our penalty area, theirs, their goal area; widened by the margin of `Areas`)."""

    half_length: float
    half_width: float
    penalty_depth: float
    penalty_half_width: float
    own_penalty: Box
    opp_penalty: Box
    opp_goal: Box


#: the numba type of a `Pitch`, for the kernels' declarations
PitchType = numba.typeof(Pitch(0.0, 0.0, 0.0, 0.0, Box(0.0, 0.0, 0.0), Box(0.0, 0.0, 0.0), Box(0.0, 0.0, 0.0)))


class Areas:
    """The penalty and goal areas, widened by a margin so that a robot's centre stays clearly out."""

    def __init__(self, field, margin: float):
        L2 = field.half_length
        self.L2, self.W2 = L2, field.half_width
        self.margin = margin
        self.pa_depth = field.penalty_area_depth
        self.pa_half = 0.5 * field.penalty_area_width
        self.ga_depth = field.goal_area_depth
        self.ga_half = 0.5 * field.goal_area_width
        self.goal_half = 0.5 * field.goal_width
        self.own_pa = Box(-L2 - 5.0, -L2 + self.pa_depth + margin, self.pa_half + margin)
        self.opp_pa = Box(L2 - self.pa_depth - margin, L2 + 5.0, self.pa_half + margin)
        self.opp_ga = Box(L2 - self.ga_depth - margin, L2 + 5.0, self.ga_half + margin)
        self.pitch = Pitch(L2, self.W2, self.pa_depth, self.pa_half, self.own_pa, self.opp_pa, self.opp_ga)
        self._with_opp_area = (self.own_pa, self.opp_ga)
        self._without_opp_area = (self.own_pa, self.opp_pa)
        # the same boxes as (K, 3) arrays, for the compiled route (see box_array)
        self._arrays = {
            id(boxes): np.array(boxes, dtype=np.float64) for boxes in (self._with_opp_area, self._without_opp_area)
        }
        self._keep_out = bind(keep_out)
        self._inside_field = bind(inside_field)

    # exact lines (robot centre over the line counts as inside)
    def in_own_penalty_area(self, x: float, y: float) -> bool:
        return x <= -self.L2 + self.pa_depth and abs(y) <= self.pa_half

    def in_opp_penalty_area(self, x: float, y: float) -> bool:
        return x >= self.L2 - self.pa_depth and abs(y) <= self.pa_half

    def in_own_goal_area(self, x: float, y: float) -> bool:
        return x <= -self.L2 + self.ga_depth and abs(y) <= self.ga_half

    def near_own_penalty_area(self, x: float, y: float, extra: float = 0.0) -> bool:
        return x <= -self.L2 + self.pa_depth + extra and abs(y) <= self.pa_half + extra

    def keep_out(self, x: float, y: float, own_pa: bool = True, opp_pa: bool = True) -> tuple[float, float]:
        """The point moved out of the areas a field robot may not stand in (`keep_out`)."""
        return self._keep_out(self.pitch, x, y, own_pa, opp_pa)

    def forbidden(self, opp_area: bool) -> tuple[tuple[float, float, float], ...]:
        """The boxes (x0, x1, half width) a field robot's path must avoid: our penalty area, the opponents'
        goal area, and their penalty area unless ``opp_area`` (the robot playing the ball may enter it)."""
        return self._with_opp_area if opp_area else self._without_opp_area  # (shared: read only)

    def box_array(self, boxes) -> np.ndarray:
        """``boxes`` (x0, x1, half width) as a (K, 3) array (the ones `forbidden` gives are made once)."""
        arr = self._arrays.get(id(boxes))
        if arr is None:
            return np.array(boxes, dtype=np.float64).reshape(-1, 3)
        return arr

    def route(
        self, px: float, py: float, tx: float, ty: float, boxes: list[tuple[float, float, float]]
    ) -> tuple[float, float]:
        """The next point on the way from P to T that keeps out of ``boxes``: the way out of a box the robot
        is in, or the nearer field-side corner of a box the straight way would cross."""
        return route(px, py, tx, ty, self.box_array(boxes), self.L2, self.goal_half)

    def inside_field(self, x: float, y: float, margin: float) -> tuple[float, float]:
        """The point moved inside the lines, at least ``margin`` from them (`inside_field`)."""
        return self._inside_field(self.pitch, x, y, margin)


@numba.njit(cache=True)
def route(px, py, tx, ty, boxes, L2, goal_half):
    """`Areas.route`, compiled (the motion's kernel calls it): ``boxes`` (K, 3) of x0, x1, half width."""
    for k in range(boxes.shape[0]):
        x0, x1, hw = boxes[k, 0], boxes[k, 1], boxes[k, 2]
        if x0 < px < x1 and -hw < py < hw:
            if abs(px) > L2 - 0.1 and abs(py) < goal_half + 0.3:
                # in a goal (behind its line): sideways it would meet the net and the posts, so first
                # clear of the posts towards the middle, then straight out into the field
                inner = goal_half - 0.45
                if abs(py) > inner:
                    return px, (-inner if py < -inner else inner if py > inner else py)
                return (x0 - 0.3 if x1 > 0.0 else x1 + 0.3), py
            ex, ey = push_out_of_box(px, py, x0, x1, hw)
            return ex + (ex - px) * 0.5, ey + (ey - py) * 0.5
    for k in range(boxes.shape[0]):
        x0, x1, hw = boxes[k, 0], boxes[k, 1], boxes[k, 2]
        if (px <= x0 and tx <= x0) or (px >= x1 and tx >= x1) or (py <= -hw and ty <= -hw) or (py >= hw and ty >= hw):
            continue  # both ends on the same side of the box: the way cannot cross it
        if segment_hits_box(px, py, tx, ty, x0, x1, hw):
            # the nearer of the corners on the field side (the first of equals)
            cx = x1 + 0.15 if x1 < 0.0 else x0 - 0.15
            ya, yb = hw + 0.15, -hw - 0.15
            da = math.hypot(cx - px, ya - py) + math.hypot(tx - cx, ty - ya)
            db = math.hypot(cx - px, yb - py) + math.hypot(tx - cx, ty - yb)
            return (cx, yb) if db < da else (cx, ya)
    return tx, ty


# --- the positional roles' points ------------------------------------------------------------------------
# Compiled kernels: open play (picture.Analyst) and the set pieces (setpieces.formation) call them from Python,
# each time through this module (`as_called`), so that a replacement assigned to this module's name (a user's
# own passive point) is the one both follow.


def as_called(point):
    """What Python calls for the role point ``point`` (a module attribute looked up at the call): a kernel's
    compiled version for its declared signature (bound once), or ``point`` itself when it is a plain function
    (a replacement)."""
    fast = _BOUND.get(point)
    if fast is None:
        fast = _BOUND[point] = bind(point) if getattr(point, "declared", ()) else point
    return fast


_BOUND: dict = {}


@kernel(pitch=PitchType, x=Float, y=Float, own_pa=Bool, opp_pa=Bool)
def keep_out(pitch, x, y, own_pa, opp_pa):
    """The point moved out of the areas a field robot may not stand in: our penalty area (if ``own_pa``),
    and the opponents' penalty area (if ``opp_pa``) or else their goal area."""
    if own_pa:
        x, y = push_out_of_box(x, y, pitch.own_penalty.x0, pitch.own_penalty.x1, pitch.own_penalty.half_width)
    box = pitch.opp_penalty if opp_pa else pitch.opp_goal
    return push_out_of_box(x, y, box.x0, box.x1, box.half_width)


@kernel(pitch=PitchType, x=Float, y=Float, margin=Float)
def inside_field(pitch, x, y, margin):
    """The point moved inside the lines, at least ``margin`` from them."""
    return (
        _clamp(x, -pitch.half_length + margin, pitch.half_length - margin),
        _clamp(y, -pitch.half_width + margin, pitch.half_width - margin),
    )


@kernel(pitch=PitchType, bx=Float, by=Float, fraction=Float, min_s=Float, gap=Float)
def guard_point(pitch, bx, by, fraction, min_s, gap):
    """A point on the way from the middle of our goal to the ball: ``fraction`` of the way, at least
    ``min_s`` from the goal, at least ``gap`` short of the ball, and outside our penalty area."""
    gx = -pitch.half_length
    dx, dy = bx - gx, by
    D = math.hypot(dx, dy)
    if D < 1e-6:
        return gx + min_s, 0.0
    ux, uy = dx / D, dy / D
    s = max(min_s, fraction * D)
    s_out = box_exit(0.0, 0.0, ux, uy, -5.0, pitch.own_penalty.x1 - gx, pitch.own_penalty.half_width)
    s = max(s, s_out)
    s = min(s, max(s_out, D - gap))
    return gx + ux * s, uy * s


@kernel(pitch=PitchType, bx=Float, by=Float, attacking=Bool)
def passive_point(pitch, bx, by, attacking):
    """The passive defender: between the ball and our goal; a last line further up when we attack."""
    if attacking and bx > -3.0:
        return _clamp(bx - 6.5, -pitch.half_length + 4.0, -0.5), 0.35 * by
    return guard_point(pitch, bx, by, 0.45, 3.2, 1.8)


@kernel(pitch=PitchType, bx=Float, by=Float, attacking=Bool, opps=Array(np.float64, 2, readonly=True))
def midfield_point(pitch, bx, by, attacking, opps):
    """The midfielder: marks the most dangerous opponent away from the ball (between it and the ball)
    when we defend; supports the attack from behind the ball, on the inner side, when we attack.
    ``opps``: the opponents' (M, 4+) rows, x and y first."""
    L2, W2 = pitch.half_length, pitch.half_width
    if attacking:
        x = _clamp(bx - 3.5, -L2 + 4.0, L2 - 4.5)
        y = by - 3.0 if by > 0.0 else by + 3.0
        return keep_out(pitch, x, _clamp(y, -W2 + 1.0, W2 - 1.0), True, True)
    found = False
    ox = oy = 0.0
    best_d = math.inf
    for k in range(opps.shape[0]):
        px, py = opps[k, 0], opps[k, 1]
        if math.hypot(px - bx, py - by) < 2.0 or px > 3.0:
            continue
        d = math.hypot(px + L2, py)
        if d < best_d:
            found, ox, oy, best_d = True, px, py, d
    if not found:
        return keep_out(pitch, _clamp(bx - 4.0, -L2 + 4.0, 1.0), -0.4 * by, True, True)
    # stand on the line from the opponent towards our goal, a little towards the ball: cuts the pass
    ux, uy = -L2 - ox, -oy
    n = _length_or_one(ux, uy)
    vx, vy = bx - ox, by - oy
    m = _length_or_one(vx, vy)
    wx, wy = 0.6 * ux / n + 0.4 * vx / m, 0.6 * uy / n + 0.4 * vy / m
    k = _length_or_one(wx, wy)
    return keep_out(pitch, ox + 1.0 * wx / k, oy + 1.0 * wy / k, True, True)


@kernel
def _length_or_one(x, y):
    """The length of (x, y), or 1 for (0, 0) (a direction of no length divides nothing)."""
    n = math.hypot(x, y)
    return 1.0 if n == 0.0 else n


@kernel(pitch=PitchType, bx=Float, by=Float)
def outlet_point(pitch, bx, by):
    """The assistant when we defend: a free point up the field, away from the ball's side, ready to break."""
    return _clamp(bx + 5.0, -2.0, 3.0), (-3.5 if by > 0.5 else 3.5)


# --- receiving spots, scored for all candidates at once -----------------------------------------------


def spot_grid(areas: Areas) -> tuple[np.ndarray, np.ndarray]:
    """Candidate points a receiver may offer itself at (the whole field, outside the areas)."""
    xs = np.linspace(-areas.L2 + 3.0, areas.L2 - 1.5, 13)
    ys = np.linspace(-areas.W2 + 1.2, areas.W2 - 1.2, 9)
    gx, gy = np.meshgrid(xs, ys)
    gx, gy = gx.ravel(), gy.ravel()
    keep = np.ones(gx.shape, dtype=bool)
    for x0, x1, hw in (areas.own_pa, areas.opp_pa):
        keep &= ~((gx > x0) & (gx < x1) & (np.abs(gy) < hw))
    return gx[keep].copy(), gy[keep].copy()


def score_spots(
    cx: np.ndarray,
    cy: np.ndarray,
    bx: float,
    by: float,
    ox: np.ndarray,
    oy: np.ndarray,
    L2: float,
    dmin: float,
    dmax: float,
    near: tuple[float, float] | None,
) -> np.ndarray:
    """Value of each candidate receiving spot: close to the opponents' goal, far from opponents, a pass
    lane from the ball that no opponent covers, within passing range, and (for stability) near where the
    receiver already is."""
    out = np.empty(len(cx))
    nx, ny = near if near is not None else (math.nan, math.nan)
    _score_spots(
        cx,
        cy,
        bx,
        by,
        np.ascontiguousarray(ox, dtype=float),
        np.ascontiguousarray(oy, dtype=float),
        L2,
        dmin,
        dmax,
        nx,
        ny,
        out,
    )
    return out


@numba.njit(cache=True)
def _score_spots(cx, cy, bx, by, ox, oy, L2, dmin, dmax, nx, ny, out):
    """`score_spots` into ``out``: the kernel the receiving spots' choices (`assignment.assist_spots`) call;
    (nx, ny) NaN: no place to stay near."""
    for i in range(cx.shape[0]):
        x, y = cx[i], cy[i]
        score = -0.45 * math.sqrt((L2 - x) ** 2 + y * y)
        if abs(y) < 3.0:
            score += 0.4 * min(x, 2.0)
        dball = math.sqrt((x - bx) ** 2 + (y - by) ** 2)
        score -= 3.0 * max(0.0, dmin - dball) + 1.0 * max(0.0, dball - dmax)
        sx, sy = x - bx, y - by
        ll = sx * sx + sy * sy + 1e-9
        # (square roots only where they count, the same numbers: an opponent 2.5 m away or more takes nothing
        # off (sqrt(d2) >= 2.5 exactly when d2 >= 6.25: score -= 0.0), and the nearest lane is the root of the
        # least square (sqrt is correctly rounded, so monotonic; 1e18 = 1e9 squared exactly; NaN squares are
        # passed over by min as their roots were, and a NaN distance still takes the long way)
        lane2 = 1e18
        for k in range(ox.shape[0]):
            d2 = (x - ox[k]) ** 2 + (y - oy[k]) ** 2
            if not d2 >= 6.25:
                score -= 2.0 * max(0.0, 2.5 - math.sqrt(d2))
            t = min(max(((ox[k] - bx) * sx + (oy[k] - by) * sy) / ll, 0.0), 1.0)
            lane2 = min(lane2, (bx + t * sx - ox[k]) ** 2 + (by + t * sy - oy[k]) ** 2)
        if ox.shape[0] > 0:
            lane = math.sqrt(lane2)
            if lane < 0.85:
                score -= 4.0
            score -= 1.5 * max(0.0, 1.4 - lane)
        if nx == nx:  # not NaN: a place to stay near
            score -= 0.12 * math.sqrt((x - nx) ** 2 + (y - ny) ** 2)
        out[i] = score
