"""Obstacle avoidance by sub-targets (after NuBot's method, simatch-original.md section 6.6), and the cap
on closing in on opponents (no charging).

Sub-targets: a robot that heads for a target checks the straight way there. If a robot (where it will be
``look`` seconds on: a robot cannot swerve at once) or the ball (with a smaller clearance) stands across
it, the first one met and every obstacle near it (closer together than a robot can pass between) form a
group; each member blocks the arc of headings that would bring the robot within its clearance. The robot
heads instead for a sub-target in the free heading closest to the target's direction, at the group's
distance. Re-planned every control period, this bends the path smoothly around groups; a small preference
for the side chosen last time keeps a robot from hesitating between two equal ways round, and an obstacle
the robot already touches blocks only the half-plane towards it.

Both are compiled kernels, called from the motion's kernel (motion.steer) for every robot at every tick.
"""

from __future__ import annotations

import math

import numpy as np

from ...compiled import kernel
from .geometry import TWO_PI, _wrap

#: two obstacles whose centres are closer than this form one group: a robot cannot pass between them [m]
GROUP_GAP = 1.15
#: how much smaller (in radians) the other side's turn must be before the robot switches sides
SIDE_HYSTERESIS = 0.25
MAX_TURN = 0.6 * math.pi


@kernel
def sub_target(px, py, tx, ty, opps, mates, me_id, ball_x, ball_y, ball_clear, clear, look, prefer_side):
    """(x, y, side) of the point to head for on the way from P to T: side +1 (turning left), -1 (right),
    0 when the way is free and the sub-target is T itself. ``opps`` (M, 4) and ``mates`` (K, 5: x, y, vx,
    vy, id; the robot itself, id ``me_id``, is skipped) are avoided ``clear`` apart where they will be in
    ``look`` seconds, the ball ``ball_clear`` apart (not at all if that is <= 0).

    The first obstacle in the way and those grouped with it (too close together to pass between) are gone
    round on the side that turns the robot least (the side it took before is preferred)."""
    dx, dy = tx - px, ty - py
    length = math.sqrt(dx * dx + dy * dy)
    if length < 1e-6:
        return tx, ty, 0
    ux, uy = dx / length, dy / length
    obstacles = np.empty((opps.shape[0] + mates.shape[0] + 1, _COLUMNS))
    cnt = _gather(obstacles, opps, mates, me_id, ball_x, ball_y, ball_clear, clear, look)
    first = _first_in_the_way(obstacles, cnt, px, py, tx, ty, ux, uy, length)
    if first < 0:
        return tx, ty, 0
    _group(obstacles, cnt, first)
    best, reach = _way_round(obstacles, cnt, first, prefer_side)
    if reach <= 0.0:
        reach = length
    reach = max(min(reach, length), 0.5)
    c, s = math.cos(best), math.sin(best)
    return px + reach * (c * ux - s * uy), py + reach * (s * ux + c * uy), 1 if best > 0.0 else -1


# the columns of `sub_target`'s obstacle rows: where it will be and how far to keep from it; whether it is
# near the way (1.0), its distance along the way (a), across it (b) and from the robot (d); whether it is in
# the group gone round (1.0)
_X, _Y, _CLEAR, _NEAR, _ALONG, _ACROSS, _DIST, _GROUPED = range(8)
_COLUMNS = 8


@kernel
def _gather(obstacles, opps, mates, me_id, ball_x, ball_y, ball_clear, clear, look):
    """Writes the obstacles' rows (x, y, clearance; the rest zero): the opponents and the team-mates where
    they will be in ``look`` seconds, and the ball if ``ball_clear`` > 0. Returns how many."""
    cnt = 0
    for k in range(opps.shape[0]):
        obstacles[cnt, _X] = opps[k, 0] + look * opps[k, 2]
        obstacles[cnt, _Y] = opps[k, 1] + look * opps[k, 3]
        obstacles[cnt, _CLEAR] = clear
        cnt += 1
    for k in range(mates.shape[0]):
        if mates[k, 4] == me_id:
            continue
        obstacles[cnt, _X] = mates[k, 0] + look * mates[k, 2]
        obstacles[cnt, _Y] = mates[k, 1] + look * mates[k, 3]
        obstacles[cnt, _CLEAR] = clear
        cnt += 1
    if ball_clear > 0.0:
        obstacles[cnt, _X], obstacles[cnt, _Y], obstacles[cnt, _CLEAR] = ball_x, ball_y, ball_clear
        cnt += 1
    obstacles[:cnt, _NEAR:] = 0.0
    return cnt


@kernel
def _first_in_the_way(obstacles, cnt, px, py, tx, ty, ux, uy, length):
    """Marks the obstacles near the way from P to T (along (ux, uy), ``length`` long; not beyond T, not
    standing at T, where the robot must go) with their distances along it, across it and from P; returns the
    first one in the way (the nearest along it whose clearance the way enters), -1 if none."""
    first, first_a = -1, 1e18
    for k in range(cnt):
        x, y, oc = obstacles[k, _X], obstacles[k, _Y], obstacles[k, _CLEAR]
        rx, ry = x - px, y - py
        d = math.sqrt(rx * rx + ry * ry)
        if d > length + oc or math.sqrt((x - tx) ** 2 + (y - ty) ** 2) < oc:
            continue
        a = rx * ux + ry * uy
        b = ry * ux - rx * uy
        obstacles[k, _NEAR] = 1.0
        obstacles[k, _ALONG], obstacles[k, _ACROSS], obstacles[k, _DIST] = a, b, d
        if (0.0 < a < length and abs(b) < oc) or (d < oc and a > 0.0):
            if a < first_a:
                first, first_a = k, a
    return first


@kernel
def _group(obstacles, cnt, first):
    """Marks ``first`` and the near obstacles linked to it by gaps under GROUP_GAP: the group to go round."""
    obstacles[first, _GROUPED] = 1.0
    grew = True
    while grew:
        grew = False
        for k in range(cnt):
            if obstacles[k, _NEAR] != 0.0 and obstacles[k, _GROUPED] == 0.0:
                for g in range(cnt):
                    if (
                        obstacles[g, _GROUPED] != 0.0
                        and (obstacles[k, _X] - obstacles[g, _X]) ** 2 + (obstacles[k, _Y] - obstacles[g, _Y]) ** 2
                        < GROUP_GAP * GROUP_GAP
                    ):
                        obstacles[k, _GROUPED] = 1.0
                        grew = True
                        break


@kernel
def _way_round(obstacles, cnt, first, prefer_side):
    """(heading relative to the way, how far to go) round the group: the free edge of the headings the
    group's obstacles cover that turns least (within MAX_TURN; the ``prefer_side`` earns SIDE_HYSTERESIS),
    or, boxed in, a slide along the nearest obstacle, away from it; as far as the farthest obstacle ahead."""
    lo = np.empty(cnt)
    hi = np.empty(cnt)
    m = 0
    reach = 0.0
    nearest, nearest_d = first, 1e18
    for k in range(cnt):
        if obstacles[k, _GROUPED] == 0.0:
            continue
        a, b, d, oc = obstacles[k, _ALONG], obstacles[k, _ACROSS], obstacles[k, _DIST], obstacles[k, _CLEAR]
        phi = math.atan2(b, a)
        delta = 0.5 * math.pi if d <= oc else math.asin(oc / d)
        lo[m], hi[m] = phi - delta, phi + delta
        m += 1
        if a > 0.0 and d > reach:
            reach = d
        if d < nearest_d:
            nearest, nearest_d = k, d
    best, best_cost, found = 0.0, 1e18, False
    for j in range(2 * m):
        angle = _wrap(lo[j // 2] - 1e-3 if j % 2 == 0 else hi[j // 2] + 1e-3)
        if abs(angle) > MAX_TURN:
            continue
        free = True
        for i in range(m):
            if lo[i] < angle < hi[i] or lo[i] < angle - TWO_PI < hi[i] or lo[i] < angle + TWO_PI < hi[i]:
                free = False
                break
        if not free:
            continue
        cost = abs(angle)
        if prefer_side != 0 and (angle > 0.0) == (prefer_side > 0):
            cost -= SIDE_HYSTERESIS
        if cost < best_cost:
            best, best_cost, found = angle, cost, True
    if not found:
        best = -MAX_TURN if obstacles[nearest, _ACROSS] > 0.0 else MAX_TURN
    return best, reach


@kernel
def no_charging(x, y, vx_now, vy_now, vx, vy, opps, touch, contact_speed, braking):
    """The velocity (vx, vy) with its part towards every opponent capped so that the robot could still slow
    to ``contact_speed`` before touching it (an opponent coming towards it shortens the way). A robot
    already closing in too fast is commanded its current velocity with the closing part cut hard, so that
    all the wheels' effort goes into braking along that line, not into turning its course."""
    worst, bx, by, ballowed = 0.0, 0.0, 0.0, 0.0
    braking_needed = False
    for k in range(opps.shape[0]):
        rx, ry = opps[k, 0] - x, opps[k, 1] - y
        d = math.sqrt(rx * rx + ry * ry)
        if d > 3.5 or d < 1e-6:
            continue
        nx, ny = rx / d, ry / d
        now = vx_now * nx + vy_now * ny
        towards_me = max(0.0, -(opps[k, 2] * nx + opps[k, 3] * ny))
        mine = max(now, 0.2)
        gap = max(0.0, d - touch) * mine / (mine + towards_me)
        allowed = math.sqrt(contact_speed * contact_speed + 2.0 * braking * gap)
        if now > allowed and now - allowed > worst:
            worst, bx, by, ballowed = now - allowed, nx, ny, allowed
            braking_needed = True
        closing = vx * nx + vy * ny
        if closing > allowed:
            vx -= (closing - allowed) * nx
            vy -= (closing - allowed) * ny
    if braking_needed:
        cut = vx_now * bx + vy_now * by - max(-1.5, ballowed - 2.0 * worst)
        vx, vy = vx_now - cut * bx, vy_now - cut * by
    return vx, vy
