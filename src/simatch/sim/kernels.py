"""Compiled kernels of the simulator's per-control-period work (numba, cached on disk).

Why compiled: these loops touch a few numbers per robot, and numpy's cost per call (about a microsecond
per operation, some forty operations per plan) was larger than the physics step it prepares. numba
turns them into one machine-code call of about a microsecond; results are the same IEEE arithmetic,
so runs stay deterministic.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
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


@numba.njit(cache=True)
def catch_candidate(
    qpos, qvel, robot_q, robot_v, ball_q, ball_v, candidates, hold_dist, hold_cos, mouth_x, catch_speed
):
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


@numba.njit(cache=True)
def keep_ball(
    eq_data,
    eq,
    qpos,
    robot_q,
    ball_q,
    robot,
    target_x,
    pull_step,
    check_grip,
    efc_type,
    efc_id,
    efc_force,
    nefc,
    eq_type,
    grip,
):
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


@numba.njit(cache=True)
def roll_held_ball(qpos, qvel, ball_q, ball_v, radius, spin, max_dw):
    """One physics step of the dribbler's rollers on a held ball: turn its horizontal spin towards ``spin``
    times rolling with its motion over the floor (w = z x v / r), by at most ``max_dw`` [rad/s] (the rollers'
    torque over a step, divided by the ball's moment of inertia). The free joint's angular velocity is in the
    ball's own frame: it is turned to the world frame, changed, and turned back (unit quaternion)."""
    qw = qpos[ball_q + 3]
    qx = qpos[ball_q + 4]
    qy = qpos[ball_q + 5]
    qz = qpos[ball_q + 6]
    lx = qvel[ball_v + 3]
    ly = qvel[ball_v + 4]
    lz = qvel[ball_v + 5]
    # world = q * local * q^-1: v + 2 qw (u x v) + 2 u x (u x v), u = (qx, qy, qz)
    cx = qy * lz - qz * ly
    cy = qz * lx - qx * lz
    cz = qx * ly - qy * lx
    wx = lx + 2.0 * (qw * cx + qy * cz - qz * cy)
    wy = ly + 2.0 * (qw * cy + qz * cx - qx * cz)
    wz = lz + 2.0 * (qw * cz + qx * cy - qy * cx)
    tx = -spin * qvel[ball_v + 1] / radius
    ty = spin * qvel[ball_v] / radius
    dx = tx - wx
    dy = ty - wy
    d = (dx * dx + dy * dy) ** 0.5
    if d > max_dw:
        dx *= max_dw / d
        dy *= max_dw / d
    wx += dx
    wy += dy
    # local = q^-1 * world * q: the same with u negated
    cx = -(qy * wz - qz * wy)
    cy = -(qz * wx - qx * wz)
    cz = -(qx * wy - qy * wx)
    qvel[ball_v + 3] = wx + 2.0 * (qw * cx - qy * cz + qz * cy)
    qvel[ball_v + 4] = wy + 2.0 * (qw * cy - qz * cx + qx * cz)
    qvel[ball_v + 5] = wz + 2.0 * (qw * cz - qx * cy + qy * cx)


@numba.njit(cache=True)
def _wrap(a):
    return (a + np.pi) % (2.0 * np.pi) - np.pi


@numba.njit(cache=True)
def _polar(dx, dy, heading):
    """Bearing from ``heading`` (wrapped) and distance of the offset (dx, dy): how a robot sees a thing."""
    return _wrap(np.arctan2(dy, dx) - heading), np.hypot(dx, dy)


@numba.njit(cache=True)
def perceive(R, ball, sign, others, own_noise, ball_noise, obs_noise):
    """The numbers of every robot's perception, in its team frame (see `perception.Perception.observe`).

    R (n, 6) robots' x y yaw vx vy w and ball (6,) x y z vx vy vz, world frame; sign (n,) +1 or -1 per
    robot's team frame; others (n, n-1) the other robots of each observer; noise added to the observer's own
    pose (n, 5: x y yaw vx vy), to the ball it sees (n, 4: x y vx vy) and to each obstacle (n, n-1, 4).
    Returns (own (n, 6): x y yaw vx vy w in the team frame; balls (n, 6): x y vx vy bearing distance;
    obstacles (6, n, n-1): x y vx vy bearing distance)."""
    n = R.shape[0]
    m = others.shape[1]
    own = np.empty((n, 6))
    balls = np.empty((n, 6))
    obs = np.empty((6, n, m))
    for i in range(n):
        s = sign[i]
        px = R[i, 0] + own_noise[i, 0]
        py = R[i, 1] + own_noise[i, 1]
        yaw = R[i, 2] + own_noise[i, 2]
        own[i, 0] = s * px
        own[i, 1] = s * py
        own[i, 2] = _wrap(yaw + (0.0 if s > 0 else np.pi))
        own[i, 3] = s * (R[i, 3] + own_noise[i, 3])
        own[i, 4] = s * (R[i, 4] + own_noise[i, 4])
        own[i, 5] = R[i, 5]
        bx = ball[0] + ball_noise[i, 0]
        by = ball[1] + ball_noise[i, 1]
        balls[i, 0] = s * bx
        balls[i, 1] = s * by
        balls[i, 2] = s * (ball[3] + ball_noise[i, 2])
        balls[i, 3] = s * (ball[4] + ball_noise[i, 3])
        balls[i, 4], balls[i, 5] = _polar(bx - px, by - py, yaw)
        for k in range(m):
            j = others[i, k]
            ox = R[j, 0] + obs_noise[i, k, 0]
            oy = R[j, 1] + obs_noise[i, k, 1]
            obs[0, i, k] = s * ox
            obs[1, i, k] = s * oy
            obs[2, i, k] = s * (R[j, 3] + obs_noise[i, k, 2])
            obs[3, i, k] = s * (R[j, 4] + obs_noise[i, k, 3])
            obs[4, i, k], obs[5, i, k] = _polar(ox - px, oy - py, yaw)
    return own, balls, obs


@numba.njit(cache=True)
def _stuck(i, vx, vy, act, slow_since, step, stuck_steps):
    """Robot i moving at (vx, vy) is stuck: commanded (set point ``act``) > 0.2 m/s but moving at less than
    half of it for ``stuck_steps`` (counted in ``slow_since``, updated)."""
    cmd2 = act[i, 0] * act[i, 0] + act[i, 1] * act[i, 1]
    slow = cmd2 > 0.04 and vx * vx + vy * vy < 0.25 * cmd2
    if not slow:
        slow_since[i] = -1
    elif slow_since[i] < 0:
        slow_since[i] = step
    return slow and step - slow_since[i] >= stuck_steps


@numba.njit(cache=True)
def robot_flags(R, act, M, n_wheels, enabled, slow_since, step, stuck_steps, half_length, half_width):
    """Per robot, from its state R (n, 6) and servo set point act (n, 3): measured rim speeds (n, W) from its
    actual motion (what encoders measure), 'valid' (on the field within 1 m, enabled) and 'stuck'
    (commanded > 0.2 m/s but moving at less than half of it for stuck_steps); updates slow_since."""
    n = R.shape[0]
    W = M.shape[1]
    wheels = np.zeros((n, W))
    valid = np.empty(n, dtype=np.bool_)
    stuck = np.empty(n, dtype=np.bool_)
    for i in range(n):
        c = np.cos(R[i, 2])
        s = np.sin(R[i, 2])
        bvx = c * R[i, 3] + s * R[i, 4]
        bvy = c * R[i, 4] - s * R[i, 3]
        w = R[i, 5]
        for k in range(n_wheels[i]):
            wheels[i, k] = M[i, k, 0] * bvx + M[i, k, 1] * bvy + M[i, k, 2] * w
        valid[i] = abs(R[i, 0]) <= half_length + 1.0 and abs(R[i, 1]) <= half_width + 1.0 and enabled[i]
        stuck[i] = _stuck(i, R[i, 3], R[i, 4], act, slow_since, step, stuck_steps)
    return wheels, valid, stuck


@numba.njit(cache=True)
def ball_apart(xpos, geoms, bound2, ball):
    """True when none of ``geoms`` (a robot's) can be in contact with geom ``ball``: every geom centre
    (``xpos``, the engine's geom_xpos of the last collision pass) is farther from the ball's than the
    geom's bound (``bound2``: squared; the two bounding spheres and the contact margin). The engine makes
    no contact between geoms whose bounding spheres, grown by the margin, are apart, so this answers
    without reading the contact list (a costly accessor) for most physics steps."""
    bx, by, bz = xpos[ball, 0], xpos[ball, 1], xpos[ball, 2]
    for k in range(geoms.shape[0]):
        g = geoms[k]
        dx, dy, dz = xpos[g, 0] - bx, xpos[g, 1] - by, xpos[g, 2] - bz
        if not dx * dx + dy * dy + dz * dz > bound2[k]:
            return False
    return True


@numba.njit(cache=True)
def model_poses(qpos, qvel, robot_q, robot_v, n, ball_q, ball_v):
    """Poses (n+1, 7: x y z qw qx qy qz) and twists (n+1, 6) of the robots (planar joints from robot_q/
    robot_v on) and the ball (free joint at ball_q/ball_v, its angular velocity turned to the world frame)."""
    pose = np.zeros((n + 1, 7))
    twist = np.zeros((n + 1, 6))
    _fill_model_poses(qpos, qvel, robot_q, robot_v, n, ball_q, ball_v, pose, twist)
    return pose, twist


@numba.njit(cache=True)
def model_poses32(qpos, qvel, robot_q, robot_v, n, ball_q, ball_v, pose, twist):
    """`model_poses` written into float32 zeros ``pose`` (7 (n+1),) and ``twist`` (6 (n+1),), flat as the
    ModelStates message carries them: each number computed in float64 as there, then rounded to float32
    (what ``astype(float32)`` of `model_poses`' arrays gives). Called every physics step: the arrays come
    in (allocating and returning arrays costs a compiled function more than its arithmetic here)."""
    _fill_model_poses(
        qpos, qvel, robot_q, robot_v, n, ball_q, ball_v, pose.reshape((n + 1, 7)), twist.reshape((n + 1, 6))
    )


@numba.njit(cache=True)
def _fill_model_poses(qpos, qvel, robot_q, robot_v, n, ball_q, ball_v, pose, twist):
    """The body of `model_poses`, into zeroed arrays of any float type."""
    for i in range(n):
        half = 0.5 * qpos[robot_q + 3 * i + 2]
        pose[i, 0] = qpos[robot_q + 3 * i]
        pose[i, 1] = qpos[robot_q + 3 * i + 1]
        pose[i, 3] = np.cos(half)
        pose[i, 6] = np.sin(half)
        twist[i, 0] = qvel[robot_v + 3 * i]
        twist[i, 1] = qvel[robot_v + 3 * i + 1]
        twist[i, 5] = qvel[robot_v + 3 * i + 2]
    for k in range(7):
        pose[n, k] = qpos[ball_q + k]
    for k in range(3):
        twist[n, k] = qvel[ball_v + k]
    # w_world = R(q) w_local
    twist[n, 3], twist[n, 4], twist[n, 5] = rotate(
        qpos[ball_q + 3],
        qpos[ball_q + 4],
        qpos[ball_q + 5],
        qpos[ball_q + 6],
        qvel[ball_v + 3],
        qvel[ball_v + 4],
        qvel[ball_v + 5],
    )


@numba.njit(cache=True)
def rotate(qw, qx, qy, qz, w0, w1, w2):
    """The vector (w0, w1, w2) turned by the unit quaternion q: v' = v + 2 qw (q x v) + 2 q x (q x v)."""
    cx = qy * w2 - qz * w1
    cy = qz * w0 - qx * w2
    cz = qx * w1 - qy * w0
    return (
        w0 + 2.0 * (qw * cx + qy * cz - qz * cy),
        w1 + 2.0 * (qw * cy + qz * cx - qx * cz),
        w2 + 2.0 * (qw * cz + qx * cy - qy * cx),
    )


@numba.njit(cache=True)
def sense_ground(
    qpos,
    qvel,
    robot_q,
    robot_v,
    ball_q,
    ball_v,
    act,
    M,
    n_wheels,
    enabled,
    slow_since,
    step,
    stuck_steps,
    half_length,
    half_width,
    sign,
    others,
    own,
    balls,
    valid,
    stuck,
    obs,
    wheels,
):
    """`robot_flags` and `perceive` (exact: no noise) in one call, for a world of ground robots alone, straight
    from the engine's ``qpos``/``qvel`` (robots' planar joints from robot_q/robot_v on, the ball's free joint at
    ball_q/ball_v) into float32 arrays laid out as the perception messages take them: own (n, 6) x y yaw vx vy
    w, balls (n, 8) x y z vx vy vz angle distance, obs (n * 6, n - 1) each observer's six rows x y vx vy angle
    distance, wheels (n, W) measured rim speeds (zeros beyond a robot's wheels); valid and stuck (n,) bool;
    updates slow_since. Every number is computed in float64 by the same operations as those two kernels and
    rounded once, as their arrays' ``astype(float32)`` is: the messages are the same bit for bit."""
    n = sign.shape[0]
    m = others.shape[1]
    W = M.shape[1]
    bx = qpos[ball_q]
    by = qpos[ball_q + 1]
    bz = qpos[ball_q + 2]
    bvx = qvel[ball_v]
    bvy = qvel[ball_v + 1]
    bvz = qvel[ball_v + 2]
    for i in range(n):
        x = qpos[robot_q + 3 * i]
        y = qpos[robot_q + 3 * i + 1]
        yaw = qpos[robot_q + 3 * i + 2]
        vx = qvel[robot_v + 3 * i]
        vy = qvel[robot_v + 3 * i + 1]
        w = qvel[robot_v + 3 * i + 2]
        # robot_flags
        c = np.cos(yaw)
        s_ = np.sin(yaw)
        fvx = c * vx + s_ * vy
        fvy = c * vy - s_ * vx
        for k in range(W):
            wheels[i, k] = (M[i, k, 0] * fvx + M[i, k, 1] * fvy + M[i, k, 2] * w) if k < n_wheels[i] else 0.0
        valid[i] = abs(x) <= half_length + 1.0 and abs(y) <= half_width + 1.0 and enabled[i]
        stuck[i] = _stuck(i, vx, vy, act, slow_since, step, stuck_steps)
        # perceive, without noise (adding a zero changes no number)
        s = sign[i]
        px = x + 0.0
        py = y + 0.0
        yw = yaw + 0.0
        own[i, 0] = s * px
        own[i, 1] = s * py
        own[i, 2] = _wrap(yw + (0.0 if s > 0 else np.pi))
        own[i, 3] = s * (vx + 0.0)
        own[i, 4] = s * (vy + 0.0)
        own[i, 5] = w
        ex = bx + 0.0
        ey = by + 0.0
        balls[i, 0] = s * ex
        balls[i, 1] = s * ey
        balls[i, 2] = bz
        balls[i, 3] = s * (bvx + 0.0)
        balls[i, 4] = s * (bvy + 0.0)
        balls[i, 5] = bvz
        balls[i, 6], balls[i, 7] = _polar(ex - px, ey - py, yw)
        for k in range(m):
            j = others[i, k]
            ox = qpos[robot_q + 3 * j] + 0.0
            oy = qpos[robot_q + 3 * j + 1] + 0.0
            obs[6 * i, k] = s * ox
            obs[6 * i + 1, k] = s * oy
            obs[6 * i + 2, k] = s * (qvel[robot_v + 3 * j] + 0.0)
            obs[6 * i + 3, k] = s * (qvel[robot_v + 3 * j + 1] + 0.0)
            obs[6 * i + 4, k], obs[6 * i + 5, k] = _polar(ox - px, oy - py, yw)


# --- the exact states' fingerprint ---------------------------------------------------------------------------
# A recording takes a fingerprint of the exact (float64) model states at every control tick, so that a
# re-simulation is checked below the float32 the states are recorded in. It needs to tell any difference, not
# to resist an adversary: per 64-bit word of the states a round like xxHash64's (the word's product xored in,
# not added), then xxHash64's final mix. Each step is a bijection of the running value, so a difference in one
# word always changes the result; two differences cancel with a chance of 1 in 2**64. SHA-256 took 0.8 us a
# tick with the processor's SHA instructions, its hash object and digest as Python objects besides; measured in
# a running match, the fingerprint cost 1.3-1.7 % of its time (now 0.6 us: one compiled call).
_P1 = np.uint64(0x9E3779B185EBCA87)
_P2 = np.uint64(0xC2B2AE3D27D4EB4F)
_P3 = np.uint64(0x165667B19E3779F9)
_L31, _R33 = np.uint64(31), np.uint64(33)  # a rotation left by 31 bits
_S33, _S29, _S32 = np.uint64(33), np.uint64(29), np.uint64(32)


@numba.njit(cache=True)
def mix64(words):
    """The fingerprint of ``words`` (uint64, C-ordered): see above; the same on every machine (integer
    arithmetic modulo 2**64)."""
    h = np.uint64(words.size) * _P3
    for w in words:
        h ^= w * _P2
        h = ((h << _L31) | (h >> _R33)) * _P1
    h ^= h >> _S33
    h *= _P2
    h ^= h >> _S29
    h *= _P3
    h ^= h >> _S32
    return h


@numba.njit(cache=True)
def model_fingerprint(qpos, qvel, robot_q, robot_v, n, ball_q, ball_v, state, words):
    """`mix64` of the exact poses then twists (`model_poses`' numbers), filled into the float64 block ``state``
    (13 (n+1) zeros, the positions `model_poses` leaves zero never written) whose words ``words`` are (its
    uint64 view): one compiled call a control tick."""
    m = n + 1
    _fill_model_poses(
        qpos, qvel, robot_q, robot_v, n, ball_q, ball_v, state[: 7 * m].reshape((m, 7)), state[7 * m :].reshape((m, 6))
    )
    return mix64(words)
