"""Judging options with the ball: the open part of the goal, a pass lane, a dribbling direction.

Opponents block what they can reach before the ball gets there: each one's shadow is widened by how far it
can move (from rest, at the assumed acceleration) while the ball travels to it.
"""

from __future__ import annotations

import math

BALL_RADIUS = 0.11
ROBOT_RADIUS = 0.25
REACT_ACC = 3.0  # how fast an opponent starts moving to block [m/s^2]
MAX_REACH = 0.9  # an opponent covers at most this much beyond its body during a shot [m]
#: a shot is seen only once it is under way: a defender (a goalkeeper fitting the ball's path) starts to
#: move this long after the kick [s]
SHOT_REACTION = 0.15


def reach(t: float) -> float:
    return min(MAX_REACH, 0.5 * REACT_ACC * t * t)


def shot_window(
    bx: float, by: float, opps: list, goal_x: float, goal_half: float, speed: float, post_margin: float = 0.22
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
    free = [(lo, hi)]
    for ox, oy, _, _ in opps:
        rx, ry = ox - bx, oy - by
        if rx < -0.2:
            continue
        d = math.hypot(rx, ry)
        if d < 1e-6:
            continue
        r = ROBOT_RADIUS + BALL_RADIUS + reach(max(0.0, d / speed - SHOT_REACTION))
        half = math.asin(min(1.0, r / d))
        c = math.atan2(ry, rx)
        a0, a1 = c - half, c + half
        out = []
        for f0, f1 in free:
            if a1 <= f0 or a0 >= f1:
                out.append((f0, f1))
                continue
            if a0 > f0:
                out.append((f0, a0))
            if a1 < f1:
                out.append((a1, f1))
        free = out
        if not free:
            return 0.0, 0.0
    f0, f1 = max(free, key=lambda f: f[1] - f[0])
    aim = 0.5 * (f0 + f1)
    return by + math.tan(aim) * dx, f1 - f0


def lane_clear(
    bx: float, by: float, cx: float, cy: float, opps: list, speed: float, exclude_near_end: float = 0.0
) -> float:
    """Smallest margin (m) by which opponents miss the ball on its way from B to C at ``speed`` (negative
    when one can get in the way). Opponents that can reach the lane while the ball passes count."""
    worst = math.inf
    length = math.hypot(cx - bx, cy - by)
    # (segment_distance and reach inline, the same float operations: this runs for every candidate of
    # every decision with the ball)
    dx, dy = cx - bx, cy - by
    ll = dx * dx + dy * dy
    v = max(speed, 0.5)
    body = ROBOT_RADIUS + BALL_RADIUS
    for ox, oy, _, _ in opps:
        if ll < 1e-12:
            d, s = math.hypot(ox - bx, oy - by), 0.0
        else:
            s = ((ox - bx) * dx + (oy - by) * dy) / ll
            s = 0.0 if s < 0.0 else 1.0 if s > 1.0 else s
            d = math.hypot(ox - bx - s * dx, oy - by - s * dy)
        along = s * length
        if exclude_near_end and (1.0 - s) * length < exclude_near_end and d > 0.6:
            continue
        t = along / v
        margin = d - (body + min(MAX_REACH, 0.5 * REACT_ACC * t * t))
        if margin < worst:
            worst = margin
    return worst


def pressure(x: float, y: float, opps: list, radius: float = 2.2) -> float:
    """How crowded a point is: the sum of how far each opponent is inside ``radius`` of it."""
    total = 0.0
    for ox, oy, _, _ in opps:
        d = math.hypot(ox - x, oy - y)
        if d < radius:
            total += radius - d
    return total


def position_value(x: float, y: float, opps: list, goal_x: float) -> float:
    """How good a place is to have the ball: near the opponents' goal, in the middle, with room."""
    return -0.45 * math.hypot(goal_x - x, y) - 0.8 * pressure(x, y, opps)


def pass_speed(distance: float, arrival: float, decel: float, lo: float = 1.6, hi: float = 7.5) -> float:
    """Kick speed for a ground pass that arrives at ``arrival`` after rolling ``distance``."""
    return min(hi, max(lo, math.sqrt(arrival * arrival + 2.0 * decel * distance)))
