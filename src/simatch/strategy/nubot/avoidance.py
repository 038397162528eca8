"""Obstacle avoidance by sub-targets (after NuBot's method, simatch-original.md section 6.6).

A robot that heads for a target checks the straight way there. If a robot (or the ball, with a smaller
clearance) stands across it, the first one met and every obstacle near it (closer together than a robot
can pass between) form a group; each member blocks the arc of headings that would bring the robot within
its clearance. The robot heads instead for a sub-target in the free heading closest to the target's
direction, at the group's distance. Re-planned every control period, this bends the path smoothly around
groups; a small preference for the side chosen last time keeps a robot from hesitating between two
equal ways round, and an obstacle the robot already touches blocks only the half-plane towards it.
"""

from __future__ import annotations

import math

#: two obstacles whose centres are closer than this form one group: a robot cannot pass between them [m]
GROUP_GAP = 1.15
#: how much smaller (in radians) the other side's turn must be before the robot switches sides
SIDE_HYSTERESIS = 0.25
MAX_TURN = 0.6 * math.pi


def sub_target(px: float, py: float, tx: float, ty: float, obstacles: list[tuple[float, float, float]],
               prefer_side: int = 0) -> tuple[float, float, int]:
    """(x, y, side) of the point to head for on the way from P to T around ``obstacles`` (x, y, clearance);
    side is +1 (turning left), -1 (right), or 0 when the way is free and the sub-target is T itself."""
    dx, dy = tx - px, ty - py
    length = math.hypot(dx, dy)
    if length < 1e-6 or not obstacles:
        return tx, ty, 0
    ux, uy = dx / length, dy / length
    first = None
    first_a = math.inf
    near = []          # (x, y, a, b, d, clearance)
    for ox, oy, clear in obstacles:
        rx, ry = ox - px, oy - py
        d = math.hypot(rx, ry)
        if d > length + clear or math.hypot(ox - tx, oy - ty) < clear:
            continue                        # beyond the target, or standing at it (the robot must go there)
        a = rx * ux + ry * uy
        b = ry * ux - rx * uy
        o = (ox, oy, a, b, d, clear)
        near.append(o)
        if (0.0 < a < length and abs(b) < clear) or (d < clear and a > 0.0):
            if a < first_a:
                first, first_a = o, a
    if first is None:
        return tx, ty, 0
    group = [first]
    rest = [o for o in near if o is not first]
    grew = True
    while grew and rest:
        grew = False
        for o in rest[:]:
            for g in group:
                if (o[0] - g[0]) ** 2 + (o[1] - g[1]) ** 2 < GROUP_GAP * GROUP_GAP:
                    group.append(o)
                    rest.remove(o)
                    grew = True
                    break
    arcs = []
    reach = 0.0
    for _, _, a, b, d, clear in group:
        phi = math.atan2(b, a)
        delta = 0.5 * math.pi if d <= clear else math.asin(clear / d)
        arcs.append((phi - delta, phi + delta))
        if a > 0.0:
            reach = max(reach, d)

    def free(angle: float) -> bool:
        for lo, hi in arcs:
            if lo < angle < hi or lo < angle - 2 * math.pi < hi or lo < angle + 2 * math.pi < hi:
                return False
        return True

    candidates = [e + (1e-3 if k else -1e-3) for lo, hi in arcs for k, e in enumerate((lo, hi))]
    best, best_cost = None, math.inf
    for angle in candidates:
        angle = math.remainder(angle, 2 * math.pi)
        if abs(angle) > MAX_TURN or not free(angle):
            continue
        cost = abs(angle)
        if prefer_side and (angle > 0) == (prefer_side > 0):
            cost -= SIDE_HYSTERESIS
        if cost < best_cost:
            best, best_cost = angle, cost
    if best is None:
        # boxed in: slide along the nearest obstacle, away from it
        _, _, a, b, d, _ = min(group, key=lambda o: o[4])
        best = -MAX_TURN if b > 0 else MAX_TURN
    reach = max(min(reach or length, length), 0.5)
    c, s = math.cos(best), math.sin(best)
    return px + reach * (c * ux - s * uy), py + reach * (s * ux + c * uy), 1 if best > 0 else -1
