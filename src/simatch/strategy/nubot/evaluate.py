"""Judging options with the ball: the open part of the goal, a pass lane, a dribbling direction.

Opponents block what they can reach before the ball gets there: each one's shadow is widened by how far it
can move (from rest, at the assumed acceleration) while the ball travels to it.

The judges are compiled kernels: the robot with the ball scores sixteen dribbling directions and every pass
each control tick, a few hundred small loops over the opponents. ``opps`` is the observation's (M, 4) array
of x, y, vx, vy (`Observation.opp_array`).
"""

from __future__ import annotations

import math

import numpy as np

from ...compiled import Float, Matrix, kernel

BALL_RADIUS = 0.11
ROBOT_RADIUS = 0.25
REACT_ACC = 3.0  # how fast an opponent starts moving to block [m/s^2]
MAX_REACH = 0.9  # an opponent covers at most this much beyond its body during a shot [m]
#: a shot is seen only once it is under way: a defender (a goalkeeper fitting the ball's path) starts to
#: move this long after the kick [s]
SHOT_REACTION = 0.15
#: the goal posts are kept this far out of a shot's window [m]
POST_MARGIN = 0.22
#: opponents this close to a point crowd it [m]
PRESSURE_RADIUS = 2.2


@kernel
def reach(t: float) -> float:
    return min(MAX_REACH, 0.5 * REACT_ACC * t * t)


@kernel(bx=Float, by=Float, opps=Matrix, goal_x=Float, goal_half=Float, speed=Float, post_margin=Float)
def shot_window(
    bx: float, by: float, opps: np.ndarray, goal_x: float, goal_half: float, speed: float, post_margin: float
) -> tuple[float, float]:
    """(aim y on the goal line, width in radians) of the widest part of the goal mouth that no opponent
    can cover before a shot at ``speed`` from (bx, by) passes it; width 0 if none is open."""
    dx = goal_x - bx
    if dx < 0.3:
        return 0.0, 0.0
    lo = math.atan2(-goal_half + post_margin - by, dx)
    hi = math.atan2(goal_half - post_margin - by, dx)
    if hi <= lo:
        return 0.0, 0.0
    # the open intervals of headings, in order (each opponent splits one in two at most)
    size = opps.shape[0] + 2
    free0 = np.empty(size)
    free1 = np.empty(size)
    out0 = np.empty(size)
    out1 = np.empty(size)
    free0[0], free1[0] = lo, hi
    n = 1
    for k in range(opps.shape[0]):
        rx, ry = opps[k, 0] - bx, opps[k, 1] - by
        if rx < -0.2:
            continue
        d = math.hypot(rx, ry)
        if d < 1e-6:
            continue
        r = ROBOT_RADIUS + BALL_RADIUS + reach(max(0.0, d / speed - SHOT_REACTION))
        half = math.asin(min(1.0, r / d))
        c = math.atan2(ry, rx)
        a0, a1 = c - half, c + half
        m = 0
        for j in range(n):
            f0, f1 = free0[j], free1[j]
            if a1 <= f0 or a0 >= f1:
                out0[m], out1[m] = f0, f1
                m += 1
                continue
            if a0 > f0:
                out0[m], out1[m] = f0, a0
                m += 1
            if a1 < f1:
                out0[m], out1[m] = a1, f1
                m += 1
        free0, out0 = out0, free0
        free1, out1 = out1, free1
        n = m
        if n == 0:
            return 0.0, 0.0
    # the widest (the first of equals)
    best = 0
    for j in range(1, n):
        if free1[j] - free0[j] > free1[best] - free0[best]:
            best = j
    f0, f1 = free0[best], free1[best]
    aim = 0.5 * (f0 + f1)
    return by + math.tan(aim) * dx, f1 - f0


@kernel(bx=Float, by=Float, cx=Float, cy=Float, opps=Matrix, speed=Float, exclude_near_end=Float)
def lane_clear(
    bx: float, by: float, cx: float, cy: float, opps: np.ndarray, speed: float, exclude_near_end: float
) -> float:
    """Smallest margin (m) by which opponents miss the ball on its way from B to C at ``speed`` (negative
    when one can get in the way). Opponents that can reach the lane while the ball passes count."""
    worst = math.inf
    length = math.hypot(cx - bx, cy - by)
    # (segment_distance and reach inline, the same float operations)
    dx, dy = cx - bx, cy - by
    ll = dx * dx + dy * dy
    v = max(speed, 0.5)
    body = ROBOT_RADIUS + BALL_RADIUS
    for k in range(opps.shape[0]):
        ox, oy = opps[k, 0], opps[k, 1]
        if ll < 1e-12:
            d, s = math.hypot(ox - bx, oy - by), 0.0
        else:
            s = ((ox - bx) * dx + (oy - by) * dy) / ll
            s = 0.0 if s < 0.0 else 1.0 if s > 1.0 else s
            d = math.hypot(ox - bx - s * dx, oy - by - s * dy)
        along = s * length
        if exclude_near_end != 0.0 and (1.0 - s) * length < exclude_near_end and d > 0.6:
            continue
        t = along / v
        margin = d - (body + min(MAX_REACH, 0.5 * REACT_ACC * t * t))
        if margin < worst:
            worst = margin
    return worst


@kernel
def pressure(x: float, y: float, opps: np.ndarray, radius: float) -> float:
    """How crowded a point is: the sum of how far each opponent is inside ``radius`` of it."""
    total = 0.0
    for k in range(opps.shape[0]):
        d = math.hypot(opps[k, 0] - x, opps[k, 1] - y)
        if d < radius:
            total += radius - d
    return total


@kernel(x=Float, y=Float, opps=Matrix, goal_x=Float)
def position_value(x: float, y: float, opps: np.ndarray, goal_x: float) -> float:
    """How good a place is to have the ball: near the opponents' goal, in the middle, with room."""
    return -0.45 * math.hypot(goal_x - x, y) - 0.8 * pressure(x, y, opps, PRESSURE_RADIUS)


def pass_speed(distance: float, arrival: float, decel: float, lo: float = 1.6, hi: float = 7.5) -> float:
    """Kick speed for a ground pass that arrives at ``arrival`` after rolling ``distance``."""
    # (min(hi, max(lo, v)), inline: Python's max keeps lo unless v > lo, min keeps hi unless that is smaller)
    v = math.sqrt(arrival * arrival + 2.0 * decel * distance)
    v = v if v > lo else lo
    return v if v < hi else hi
