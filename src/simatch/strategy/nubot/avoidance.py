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

Both are compiled kernels (numba, cached on disk, as the simulator's): a handful of obstacles per robot and
tick are cheap loops as machine code and costly as Python.
"""

from __future__ import annotations

import math

import numba
import numpy as np

#: two obstacles whose centres are closer than this form one group: a robot cannot pass between them [m]
GROUP_GAP = 1.15
#: how much smaller (in radians) the other side's turn must be before the robot switches sides
SIDE_HYSTERESIS = 0.25
MAX_TURN = 0.6 * math.pi
TWO_PI = 2.0 * math.pi


@numba.njit(cache=True)
def _wrap(a):
    return (a + math.pi) % TWO_PI - math.pi


@numba.njit(cache=True)
def sub_target(px, py, tx, ty, opps, mates, me_id, ball_x, ball_y, ball_clear, clear, look, prefer_side):
    """(x, y, side) of the point to head for on the way from P to T: side +1 (turning left), -1 (right),
    0 when the way is free and the sub-target is T itself. ``opps`` (M, 4) and ``mates`` (K, 5: x, y, vx,
    vy, id; the robot itself, id ``me_id``, is skipped) are avoided ``clear`` apart where they will be in
    ``look`` seconds, the ball ``ball_clear`` apart (not at all if that is <= 0)."""
    dx, dy = tx - px, ty - py
    length = math.sqrt(dx * dx + dy * dy)
    n = opps.shape[0] + mates.shape[0] + 1
    if length < 1e-6:
        return tx, ty, 0
    ux, uy = dx / length, dy / length
    # every per-obstacle number in the rows of one array (one allocation instead of ten): the obstacles'
    # x, y and clearance, whether near (1.0) with its a, b, d, whether in the group (1.0), its angles' bounds
    work = np.empty((10, n))
    ox = work[0]
    oy = work[1]
    oc = work[2]
    cnt = 0
    for k in range(opps.shape[0]):
        ox[cnt] = opps[k, 0] + look * opps[k, 2]
        oy[cnt] = opps[k, 1] + look * opps[k, 3]
        oc[cnt] = clear
        cnt += 1
    for k in range(mates.shape[0]):
        if mates[k, 4] == me_id:
            continue
        ox[cnt] = mates[k, 0] + look * mates[k, 2]
        oy[cnt] = mates[k, 1] + look * mates[k, 3]
        oc[cnt] = clear
        cnt += 1
    if ball_clear > 0.0:
        ox[cnt], oy[cnt], oc[cnt] = ball_x, ball_y, ball_clear
        cnt += 1
    work[3:8, :cnt] = 0.0
    near = work[3]
    A = work[4]
    B = work[5]
    D = work[6]
    first, first_a = -1, 1e18
    for k in range(cnt):
        rx, ry = ox[k] - px, oy[k] - py
        d = math.sqrt(rx * rx + ry * ry)
        if d > length + oc[k] or math.sqrt((ox[k] - tx) ** 2 + (oy[k] - ty) ** 2) < oc[k]:
            continue  # beyond the target, or standing at it (the robot must go there)
        a = rx * ux + ry * uy
        b = ry * ux - rx * uy
        near[k] = 1.0
        A[k], B[k], D[k] = a, b, d
        if (0.0 < a < length and abs(b) < oc[k]) or (d < oc[k] and a > 0.0):
            if a < first_a:
                first, first_a = k, a
    if first < 0:
        return tx, ty, 0
    group = work[7]
    group[first] = 1.0
    grew = True
    while grew:
        grew = False
        for k in range(cnt):
            if near[k] != 0.0 and group[k] == 0.0:
                for g in range(cnt):
                    if group[g] != 0.0 and (ox[k] - ox[g]) ** 2 + (oy[k] - oy[g]) ** 2 < GROUP_GAP * GROUP_GAP:
                        group[k] = 1.0
                        grew = True
                        break
    lo = work[8]
    hi = work[9]
    m = 0
    reach = 0.0
    nearest, nearest_d = first, 1e18
    for k in range(cnt):
        if group[k] == 0.0:
            continue
        phi = math.atan2(B[k], A[k])
        delta = 0.5 * math.pi if D[k] <= oc[k] else math.asin(oc[k] / D[k])
        lo[m], hi[m] = phi - delta, phi + delta
        m += 1
        if A[k] > 0.0 and D[k] > reach:
            reach = D[k]
        if D[k] < nearest_d:
            nearest, nearest_d = k, D[k]
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
        # boxed in: slide along the nearest obstacle, away from it
        best = -MAX_TURN if B[nearest] > 0.0 else MAX_TURN
    if reach <= 0.0:
        reach = length
    reach = max(min(reach, length), 0.5)
    c, s = math.cos(best), math.sin(best)
    return px + reach * (c * ux - s * uy), py + reach * (s * ux + c * uy), 1 if best > 0.0 else -1


@numba.njit(cache=True)
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
