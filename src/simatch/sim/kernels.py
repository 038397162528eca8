"""Compiled kernels of the simulator's per-control-period work (numba, cached on disk).

Why compiled: these loops touch a few numbers per robot, and numpy's cost per call (about a microsecond
per operation, some forty operations per plan) was larger than the physics step it prepares. numba
turns them into one machine-code call of about a microsecond; results are the same IEEE arithmetic,
so runs stay deterministic.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def plan_drive(M, P, cmd, dirty, due, U_target, up, down, max_speed, act, window, actrange, ctrl, bias, kv,
               ramping, dt):
    """Plan the wheel ramps of the robots marked in ``due`` for the next ``window`` physics steps.

    M (N, W, 3) rim-speed matrices, P (N, 3, W) their pseudo-inverses, cmd (N, 3) body-frame commands,
    dirty (N,) commands not yet turned into U_target (N, W) rim-speed targets; up/down (N,) per-step
    bounds of speeding up / slowing down; act (N, 3) the servos' current set points.
    Writes, for each due robot: actrange (N, 3, 2) the set point's bounds (it stops at the target),
    ctrl (N, 3) its rate of change [per s], bias (N, 3) the exact-arc correction force, ramping (N,)."""
    n, W = U_target.shape
    inv_dt = 1.0 / dt
    for i in range(n):
        if not due[i]:
            continue
        if dirty[i]:
            peak = 0.0
            for w in range(W):
                u = M[i, w, 0] * cmd[i, 0] + M[i, w, 1] * cmd[i, 1] + M[i, w, 2] * cmd[i, 2]
                U_target[i, w] = u
                if abs(u) > peak:
                    peak = abs(u)
            if peak > max_speed[i]:
                scale = max_speed[i] / peak
                for w in range(W):
                    U_target[i, w] *= scale
            dirty[i] = False
        # largest common fraction of the remaining change that respects every wheel's bound
        c = np.inf
        for w in range(W):
            u = M[i, w, 0] * act[i, 0] + M[i, w, 1] * act[i, 1] + M[i, w, 2] * act[i, 2]
            d = U_target[i, w] - u
            ad = abs(d)
            if ad > 0.0:
                b = down[i] if u * d < 0.0 else up[i]
                if b / ad < c:
                    c = b / ad
        # a slowing wheel that would pass through zero inside the window (its target lies beyond zero)
        # speeds up afterwards: then the window keeps its speeding-up bound throughout
        c2 = np.inf
        crossing = False
        for w in range(W):
            u = M[i, w, 0] * act[i, 0] + M[i, w, 1] * act[i, 1] + M[i, w, 2] * act[i, 2]
            d = U_target[i, w] - u
            ad = abs(d)
            if ad > 0.0:
                slowing = u * d < 0.0
                if slowing and U_target[i, w] * u < 0.0 and abs(u) < window * c * ad:
                    crossing = True
                    b = up[i]
                else:
                    b = down[i] if slowing else up[i]
                if b / ad < c2:
                    c2 = b / ad
        if crossing:
            c = c2
        if c > 1.0:
            c = 1.0
        ramping[i] = c * window < 1.0
        vm = np.empty(3)
        for k in range(3):
            vt = 0.0
            for w in range(W):
                vt += P[i, k, w] * U_target[i, w]
            v0 = act[i, k]
            rate = (vt - v0) * c
            lo = min(v0, vt)
            hi = max(v0, vt)
            actrange[i, k, 0] = lo
            actrange[i, k, 1] = hi
            ctrl[i, k] = rate * inv_dt
            mid = v0 + 0.5 * (window + 1) * rate
            vm[k] = min(max(mid, lo), hi)
        # exact arcs: turn the set point by half a step's rotation (first order), as a force offset
        theta = vm[2] * 0.5 * dt
        bias[i, 0] = -kv[i, 0] * theta * vm[1]
        bias[i, 1] = kv[i, 1] * theta * vm[0]
        bias[i, 2] = 0.0


@numba.njit(cache=True, nogil=True)
def equality_force(efc_type, efc_id, efc_force, nefc, eq, eq_type):
    """Horizontal magnitude of the force of equality constraint ``eq`` (its first two rows) [N]."""
    fx = 0.0
    fy = 0.0
    row = 0
    for r in range(nefc):
        if efc_type[r] == eq_type and efc_id[r] == eq:
            if row == 0:
                fx = efc_force[r]
            elif row == 1:
                fy = efc_force[r]
                break
            row += 1
    return (fx * fx + fy * fy) ** 0.5


@numba.njit(cache=True, nogil=True)
def catch_candidate(qpos, qvel, robot_q, robot_v, ball_q, ball_v, candidates, hold_dist, hold_cos, mouth_x,
                    catch_speed):
    """The robot (index) that can take the ball now: among ``candidates`` (dribbler on, usable), those
    with the ball within ``hold_dist`` and within the bearing cone, arriving no faster than
    ``catch_speed`` relative to the mouth; the nearest wins (ties: lowest index). Returns
    (robot, forward, lateral, nearest distance) with robot = -1 if none."""
    bx = qpos[ball_q]
    by = qpos[ball_q + 1]
    best = -1
    best_d = np.inf
    best_f = 0.0
    best_l = 0.0
    nearest = np.inf
    for i in candidates:
        x = qpos[robot_q + 3 * i]
        y = qpos[robot_q + 3 * i + 1]
        yaw = qpos[robot_q + 3 * i + 2]
        dx = bx - x
        dy = by - y
        dist = (dx * dx + dy * dy) ** 0.5
        if dist < nearest:
            nearest = dist
        if dist > hold_dist or dist >= best_d:
            continue
        c = np.cos(yaw)
        s = np.sin(yaw)
        fwd = c * dx + s * dy
        if fwd < hold_cos * dist:
            continue
        vx = qvel[robot_v + 3 * i]
        vy = qvel[robot_v + 3 * i + 1]
        w = qvel[robot_v + 3 * i + 2]
        mx = mouth_x[i]
        rvx = qvel[ball_v] - (vx - w * s * mx)
        rvy = qvel[ball_v + 1] - (vy + w * c * mx)
        if (rvx * rvx + rvy * rvy) ** 0.5 > catch_speed:
            continue
        best = i
        best_d = dist
        best_f = fwd
        best_l = -s * dx + c * dy
    return best, best_f, best_l, nearest


@numba.njit(cache=True, nogil=True)
def keep_ball(eq_data, eq, qpos, robot_q, ball_q, robot, target_x, pull_step, check_grip, efc_type, efc_id,
              efc_force, nefc, eq_type, grip):
    """One physics step of a held ball: draw the dribble constraint's anchor (robot frame) towards the mouth
    point at the rollers' speed, then measure the constraint's horizontal force. Returns (status, force):
    status 0 = still held, 1 = the force exceeds the grip, 2 = the ball was pulled away from the anchor."""
    ax = eq_data[eq, 0]
    ay = eq_data[eq, 1]
    dx = target_x - ax
    dy = -ay
    gap = (dx * dx + dy * dy) ** 0.5
    if gap > 1e-9:
        f = min(1.0, pull_step / gap)
        ax += f * dx
        ay += f * dy
        eq_data[eq, 0] = ax
        eq_data[eq, 1] = ay
    force = 0.0
    if check_grip:
        force = equality_force(efc_type, efc_id, efc_force, nefc, eq, eq_type)
        if force > grip:
            return 1, force
    x = qpos[robot_q + 3 * robot]
    y = qpos[robot_q + 3 * robot + 1]
    yaw = qpos[robot_q + 3 * robot + 2]
    bx = qpos[ball_q] - x
    by = qpos[ball_q + 1] - y
    c = np.cos(yaw)
    s = np.sin(yaw)
    fx = c * bx + s * by
    fy = -s * bx + c * by
    if ((fx - ax) ** 2 + (fy - ay) ** 2) ** 0.5 > 0.1:
        return 2, force
    return 0, force
