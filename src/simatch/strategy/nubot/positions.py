"""Where the robots without the ball stand: the areas they must respect and the points of each role.

All in the team frame (own goal at -x). Areas: a field robot's centre stays out of its own penalty area
(only the goalkeeper lives there) and out of the opponents' goal area; only the robot playing the ball
enters the opponents' penalty area.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ...exactmath import hypot, pymax, pymin
from .geometry import _clamp, box_exit, clamp, push_out_of_box, segment_hits_box


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
        self.own_pa = (-L2 - 5.0, -L2 + self.pa_depth + margin, self.pa_half + margin)
        self.opp_pa = (L2 - self.pa_depth - margin, L2 + 5.0, self.pa_half + margin)
        self.opp_ga = (L2 - self.ga_depth - margin, L2 + 5.0, self.ga_half + margin)
        self._with_opp_area = (self.own_pa, self.opp_ga)
        self._without_opp_area = (self.own_pa, self.opp_pa)
        # the same boxes as (K, 3) arrays, for the compiled route (see box_array)
        self._arrays = {
            id(boxes): np.array(boxes, dtype=np.float64) for boxes in (self._with_opp_area, self._without_opp_area)
        }
        # what the compiled points read (see _passive_point): L2, W2, our and their penalty areas' boxes
        self.geo = np.array((L2, self.W2, *self.own_pa, *self.opp_pa))

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
        """The point moved out of the areas a field robot may not stand in."""
        # (push_out_of_box returns a point outside the box unchanged: the test first, inline, saves the call)
        if own_pa:
            x0, x1, hw = self.own_pa
            if x0 < x < x1 and -hw < y < hw:
                x, y = push_out_of_box(x, y, x0, x1, hw)
        x0, x1, hw = self.opp_pa if opp_pa else self.opp_ga
        if x0 < x < x1 and -hw < y < hw:
            x, y = push_out_of_box(x, y, x0, x1, hw)
        return x, y

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
        # (clamp, inline)
        lo, hi = -self.L2 + margin, self.L2 - margin
        x = lo if x < lo else hi if x > hi else x
        lo, hi = -self.W2 + margin, self.W2 - margin
        return x, (lo if y < lo else hi if y > hi else y)


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
            da = hypot(cx - px, ya - py) + hypot(tx - cx, ty - ya)
            db = hypot(cx - px, yb - py) + hypot(tx - cx, ty - yb)
            return (cx, yb) if db < da else (cx, ya)
    return tx, ty


def guard_point(areas: Areas, bx: float, by: float, fraction: float, min_s: float, gap: float) -> tuple[float, float]:
    """A point on the way from the middle of our goal to the ball: ``fraction`` of the way, at least
    ``min_s`` from the goal, at least ``gap`` short of the ball, and outside our penalty area."""
    gx = -areas.L2
    dx, dy = bx - gx, by
    D = math.hypot(dx, dy)
    if D < 1e-6:
        return gx + min_s, 0.0
    ux, uy = dx / D, dy / D
    s = max(min_s, fraction * D)
    s_out = box_exit(0.0, 0.0, ux, uy, -5.0, areas.own_pa[1] - gx, areas.own_pa[2])
    s = max(s, s_out)
    s = min(s, max(s_out, D - gap))
    return gx + ux * s, uy * s


def passive_point(areas: Areas, bx: float, by: float, attacking: bool) -> tuple[float, float]:
    """The passive defender: between the ball and our goal; a last line further up when we attack."""
    if attacking and bx > -3.0:
        return clamp(bx - 6.5, -areas.L2 + 4.0, -0.5), 0.35 * by
    return guard_point(areas, bx, by, 0.45, 3.2, 1.8)


def midfield_point(
    areas: Areas, bx: float, by: float, attacking: bool, opps: list[tuple[float, float, float, float]]
) -> tuple[float, float]:
    """The midfielder: marks the most dangerous opponent away from the ball (between it and the ball)
    when we defend; supports the attack from behind the ball, on the inner side, when we attack."""
    L2, W2 = areas.L2, areas.W2
    if attacking:
        x = clamp(bx - 3.5, -L2 + 4.0, L2 - 4.5)
        y = by - 3.0 if by > 0.0 else by + 3.0
        return areas.keep_out(x, clamp(y, -W2 + 1.0, W2 - 1.0))
    best, best_d = None, math.inf
    for ox, oy, _, _ in opps:
        if math.hypot(ox - bx, oy - by) < 2.0 or ox > 3.0:
            continue
        d = math.hypot(ox + L2, oy)
        if d < best_d:
            best, best_d = (ox, oy), d
    if best is None:
        x, y = clamp(bx - 4.0, -L2 + 4.0, 1.0), -0.4 * by
        return areas.keep_out(x, y)
    ox, oy = best
    # stand on the line from the opponent towards our goal, a little towards the ball: cuts the pass
    gx = -L2
    ux, uy = gx - ox, -oy
    n = math.hypot(ux, uy) or 1.0
    vx, vy = bx - ox, by - oy
    m = math.hypot(vx, vy) or 1.0
    wx, wy = 0.6 * ux / n + 0.4 * vx / m, 0.6 * uy / n + 0.4 * vy / m
    k = math.hypot(wx, wy) or 1.0
    return areas.keep_out(ox + 1.0 * wx / k, oy + 1.0 * wy / k)


def outlet_point(areas: Areas, bx: float, by: float) -> tuple[float, float]:
    """The assistant when we defend: a free point up the field, away from the ball's side, ready to break."""
    x = clamp(bx + 5.0, -2.0, 3.0)
    y = -3.5 if by > 0.5 else 3.5
    return x, y


@numba.njit(cache=True)
def _outlet_point(bx, by):
    """`outlet_point`, for compiled callers."""
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
    """score_spots, compiled: a hundred candidates times five opponents are tiny loops, costly as NumPy
    calls (about a microsecond each) and cheap as machine code."""
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


# --- the positional roles' points, compiled (open play's slots, see picture._open_slots) ------------------
# `geo`: the fixed numbers they read, from `Areas.geo`: L2, W2, then our penalty area's and the opponents'
# penalty area's boxes (x0, x1, half width)


@numba.njit(cache=True)
def _keep_out(x, y, geo):
    """`Areas.keep_out` (both penalty areas)."""
    x0, x1, hw = geo[2], geo[3], geo[4]
    if x0 < x < x1 and -hw < y < hw:
        x, y = push_out_of_box(x, y, x0, x1, hw)
    x0, x1, hw = geo[5], geo[6], geo[7]
    if x0 < x < x1 and -hw < y < hw:
        x, y = push_out_of_box(x, y, x0, x1, hw)
    return x, y


@numba.njit(cache=True)
def _passive_point(bx, by, attacking, geo):
    """`passive_point`, compiled (with `guard_point` inline, Python's min and max)."""
    L2 = geo[0]
    if attacking and bx > -3.0:
        return _clamp(bx - 6.5, -L2 + 4.0, -0.5), 0.35 * by
    fraction, min_s, gap = 0.45, 3.2, 1.8
    gx = -L2
    dx, dy = bx - gx, by
    D = hypot(dx, dy)
    if D < 1e-6:
        return gx + min_s, 0.0
    ux, uy = dx / D, dy / D
    s = pymax(min_s, fraction * D)
    s_out = box_exit(0.0, 0.0, ux, uy, -5.0, geo[3] - gx, geo[4])
    s = pymax(s, s_out)
    s = pymin(s, pymax(s_out, D - gap))
    return gx + ux * s, uy * s


@numba.njit(cache=True)
def _midfield_point(bx, by, attacking, opps, geo):
    """`midfield_point`, compiled, over the opponents' (M, 4) array."""
    L2, W2 = geo[0], geo[1]
    if attacking:
        x = _clamp(bx - 3.5, -L2 + 4.0, L2 - 4.5)
        y = by - 3.0 if by > 0.0 else by + 3.0
        return _keep_out(x, _clamp(y, -W2 + 1.0, W2 - 1.0), geo)
    found = False
    ox = oy = 0.0
    best_d = math.inf
    for k in range(opps.shape[0]):
        px, py = opps[k, 0], opps[k, 1]
        if hypot(px - bx, py - by) < 2.0 or px > 3.0:
            continue
        d = hypot(px + L2, py)
        if d < best_d:
            found, ox, oy, best_d = True, px, py, d
    if not found:
        x, y = _clamp(bx - 4.0, -L2 + 4.0, 1.0), -0.4 * by
        return _keep_out(x, y, geo)
    gx = -L2
    ux, uy = gx - ox, -oy
    n = hypot(ux, uy)
    if n == 0.0:  # (`or 1.0`)
        n = 1.0
    vx, vy = bx - ox, by - oy
    m = hypot(vx, vy)
    if m == 0.0:
        m = 1.0
    wx, wy = 0.6 * ux / n + 0.4 * vx / m, 0.6 * uy / n + 0.4 * vy / m
    k = hypot(wx, wy)
    if k == 0.0:
        k = 1.0
    return _keep_out(ox + 1.0 * wx / k, oy + 1.0 * wy / k, geo)
