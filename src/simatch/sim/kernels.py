"""The simulator's compiled kernels: the work of every physics step and control tick on the engine's arrays.

They are compiled (`simatch.compiled`) because each touches a few numbers per robot, many times a simulated
second, where NumPy's per-operation overhead would outweigh the arithmetic. The arithmetic is plain IEEE
double precision in a fixed order, so runs stay deterministic.

The engine's joints are given by address: ``qpos[robot_q + 3 i]`` .. ``+ 2`` are ground robot i's x, y, yaw
(``qvel[robot_v + 3 i]`` .. its vx, vy, w), ``qpos[ball_q]`` .. ``+ 6`` the ball's x y z qw qx qy qz and
``qvel[ball_v]`` .. ``+ 5`` its vx vy vz and spin (in its own frame).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba.core import types

from ..compiled import Array, Bool, Float, Int, Matrix, Vector, kernel

#: array kinds the kernels take besides float64 vectors and matrices
Indices = Array(np.int64, 1)
Ints32 = Array(np.int32, 1)
Flags = Array(np.bool_, 1)
Floats32 = Array(np.float32, 1)
Matrix32 = Array(np.float32, 2)
Words = Array(np.uint64, 1)


@kernel
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


#: the dribbler's mouth: how near [m] and how far off the heading (cosine) the ball may be, and how high its
#: centre at most [m], for it to be in a robot's mouth
MOUTH = dict(hold_dist=Float, hold_cos=Float, top=Float)


@kernel
def ball_from_robot(qpos, robot_q, ball_q, i):
    """Where the ball's centre is from ground robot i's: (forward, lateral) in the robot's frame, and the
    horizontal distance."""
    dx = qpos[ball_q] - qpos[robot_q + 3 * i]
    dy = qpos[ball_q + 1] - qpos[robot_q + 3 * i + 1]
    yaw = qpos[robot_q + 3 * i + 2]
    c = np.cos(yaw)
    s = np.sin(yaw)
    return c * dx + s * dy, -s * dx + c * dy, (dx * dx + dy * dy) ** 0.5


@kernel
def mouth_view(qpos, robot_q, ball_q, i, hold_dist, hold_cos, top):
    """The ball as ground robot i's mouth sees it: (inside, forward, lateral, distance) (`ball_from_robot`).
    The ball is inside the mouth within ``hold_dist``, within the bearing cone (forward at least ``hold_cos``
    times the distance) and on the ground (its centre no higher than ``top``)."""
    fwd, lat, dist = ball_from_robot(qpos, robot_q, ball_q, i)
    inside = dist <= hold_dist and fwd >= hold_cos * dist and qpos[ball_q + 2] <= top
    return inside, fwd, lat, dist


@kernel(qpos=Vector, robot_q=Int, ball_q=Int, i=Int, **MOUTH)
def in_mouth(qpos, robot_q, ball_q, i, hold_dist, hold_cos, top):
    """Whether the ball is in ground robot i's mouth (`mouth_view`)."""
    return mouth_view(qpos, robot_q, ball_q, i, hold_dist, hold_cos, top)[0]


@kernel(qpos=Vector, qvel=Vector, robot_q=Int, robot_v=Int, i=Int, mouth_x=Float)
def mouth_velocity(qpos, qvel, robot_q, robot_v, i, mouth_x):
    """The world velocity (vx, vy) of ground robot i's mouth point, ``mouth_x`` ahead of its centre: the
    robot's velocity plus w x r."""
    yaw = qpos[robot_q + 3 * i + 2]
    w = qvel[robot_v + 3 * i + 2]
    rx = np.cos(yaw) * mouth_x
    ry = np.sin(yaw) * mouth_x
    return qvel[robot_v + 3 * i] - w * ry, qvel[robot_v + 3 * i + 1] + w * rx


@kernel(
    qpos=Vector,
    qvel=Vector,
    robot_q=Int,
    robot_v=Int,
    ball_q=Int,
    ball_v=Int,
    candidates=Indices,
    **MOUTH,
    mouth_x=Vector,
    catch_speed=Float,
)
def catch_candidate(
    qpos, qvel, robot_q, robot_v, ball_q, ball_v, candidates, hold_dist, hold_cos, top, mouth_x, catch_speed
):
    """The robot (index) that can take the ball now: among ``candidates`` (dribbler on, usable), those
    with the ball in their mouth (`mouth_view`) arriving no faster than ``catch_speed`` relative to the
    mouth (`mouth_velocity`); the nearest wins (ties: lowest index). Returns (robot, forward, lateral,
    nearest distance) with robot = -1 if none."""
    best = -1
    best_d = np.inf
    best_f = 0.0
    best_l = 0.0
    nearest = np.inf
    for i in candidates:
        inside, fwd, lat, dist = mouth_view(qpos, robot_q, ball_q, i, hold_dist, hold_cos, top)
        if dist < nearest:
            nearest = dist
        if not inside or dist >= best_d:
            continue
        mvx, mvy = mouth_velocity(qpos, qvel, robot_q, robot_v, i, mouth_x[i])
        rvx = qvel[ball_v] - mvx
        rvy = qvel[ball_v + 1] - mvy
        if (rvx * rvx + rvy * rvy) ** 0.5 > catch_speed:
            continue
        best = i
        best_d = dist
        best_f = fwd
        best_l = lat
    return best, best_f, best_l, nearest


@kernel(
    eq_data=Matrix,
    eq=Int,
    qpos=Vector,
    robot_q=Int,
    ball_q=Int,
    robot=Int,
    target_x=Float,
    pull_step=Float,
    check_grip=Bool,
    efc_type=Ints32,
    efc_id=Ints32,
    efc_force=Vector,
    nefc=Int,
    eq_type=Int,
    grip=Float,
)
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
    fx, fy, _ = ball_from_robot(qpos, robot_q, ball_q, robot)
    if ((fx - ax) ** 2 + (fy - ay) ** 2) ** 0.5 > 0.1:
        return 2, force
    return 0, force


@kernel(qpos=Vector, qvel=Vector, ball_q=Int, ball_v=Int, radius=Float, spin=Float, max_dw=Float)
def roll_held_ball(qpos, qvel, ball_q, ball_v, radius, spin, max_dw):
    """One physics step of the dribbler's rollers on a held ball: turn its horizontal spin towards ``spin``
    times rolling with its motion over the floor (w = z x v / r), by at most ``max_dw`` [rad/s] (the rollers'
    torque over a step, divided by the ball's moment of inertia). The free joint's angular velocity is in the
    ball's own frame: it is turned to the world frame, changed, and turned back (unit quaternion)."""
    qw = qpos[ball_q + 3]
    qx = qpos[ball_q + 4]
    qy = qpos[ball_q + 5]
    qz = qpos[ball_q + 6]
    wx, wy, wz = rotate(qw, qx, qy, qz, qvel[ball_v + 3], qvel[ball_v + 4], qvel[ball_v + 5])
    tx = -spin * qvel[ball_v + 1] / radius
    ty = spin * qvel[ball_v] / radius
    dx = tx - wx
    dy = ty - wy
    d = (dx * dx + dy * dy) ** 0.5
    if d > max_dw:
        dx *= max_dw / d
        dy *= max_dw / d
    # back to the ball's frame: turned by the inverse quaternion
    qvel[ball_v + 3], qvel[ball_v + 4], qvel[ball_v + 5] = rotate(qw, -qx, -qy, -qz, wx + dx, wy + dy, wz)


@kernel
def wrap_angle(a):
    """The angle ``a`` wrapped to [-pi, pi)."""
    return (a + np.pi) % (2.0 * np.pi) - np.pi


@kernel
def _polar(dx, dy, heading):
    """Bearing from ``heading`` (wrapped) and distance of the offset (dx, dy): how a robot sees a thing."""
    return wrap_angle(np.arctan2(dy, dx) - heading), np.hypot(dx, dy)


#: the noise added to what each robot perceives (float64): to its own pose (n, 5: x y yaw vx vy), to the
#: ball it sees (n, 4: x y vx vy) and to each other robot it sees (n, n-1, 4: x y vx vy)
Noise = namedtuple("Noise", "own ball obstacles")
NOISE = types.NamedTuple((Matrix, Matrix, Array(np.float64, 3)), Noise)

#: what the robots' flags are computed from: the base servos' set points (n, 3), the rim-speed matrices
#: (n, W, 3), each robot's number of wheels, whether it is enabled, since when it is slow (-1: it is not;
#: updated), how many steps slow make it stuck, and the field's half length and width [m]
FlagInputs = namedtuple("FlagInputs", "setpoint rim n_wheels enabled slow_since stuck_steps half_length half_width")
FLAG_INPUTS = types.NamedTuple((Matrix, Array(np.float64, 3), Indices, Flags, Indices, Int, Float, Float), FlagInputs)

#: where the engine keeps the ground robots' planar joints and the ball's free joint (see the module)
Joints = namedtuple("Joints", "robot_q robot_v ball_q ball_v")
JOINTS = types.NamedUniTuple(Int, 4, Joints)


#: who perceives (each robot's team frame, the other robots it sees, the noise) and what they perceive: the
#: parameters `perceive` and `sense_ground` share
_OBSERVERS = dict(sign=Vector, others=Array(np.int64, 2), noise=NOISE)
_PERCEIVED = dict(own=Matrix32, balls=Matrix32, obs=Matrix32)


@kernel(R=Matrix, ball=Vector, **_OBSERVERS, **_PERCEIVED)
def perceive(R, ball, sign, others, noise, own, balls, obs):
    """Every robot's perception (the OmniVisionInfo's numbers), in its team frame, with ``noise``.

    R (n, 6) the robots' x y yaw vx vy w and ball (6,) its x y z vx vy vz, world frame; sign (n,) +1 or -1:
    each robot's team frame (-1: the world turned by pi); others (n, n-1) the other robots of each observer.
    Writes, each number computed in float64 and rounded once to the arrays' float32: own (n, 6) x y yaw vx vy
    w; balls (n, 8) x y z vx vy vz bearing distance; obs (6 n, n-1) each observer's six rows x y vx vy
    bearing distance of the robots it sees. Bearings are from the observer's heading (its kicker axis)."""
    n = R.shape[0]
    m = others.shape[1]
    for i in range(n):
        s = sign[i]
        px = R[i, 0] + noise.own[i, 0]
        py = R[i, 1] + noise.own[i, 1]
        yaw = R[i, 2] + noise.own[i, 2]
        own[i, 0] = s * px
        own[i, 1] = s * py
        own[i, 2] = wrap_angle(yaw + (0.0 if s > 0 else np.pi))
        own[i, 3] = s * (R[i, 3] + noise.own[i, 3])
        own[i, 4] = s * (R[i, 4] + noise.own[i, 4])
        own[i, 5] = R[i, 5]
        bx = ball[0] + noise.ball[i, 0]
        by = ball[1] + noise.ball[i, 1]
        balls[i, 0] = s * bx
        balls[i, 1] = s * by
        balls[i, 2] = ball[2]
        balls[i, 3] = s * (ball[3] + noise.ball[i, 2])
        balls[i, 4] = s * (ball[4] + noise.ball[i, 3])
        balls[i, 5] = ball[5]
        balls[i, 6], balls[i, 7] = _polar(bx - px, by - py, yaw)
        for k in range(m):
            j = others[i, k]
            ox = R[j, 0] + noise.obstacles[i, k, 0]
            oy = R[j, 1] + noise.obstacles[i, k, 1]
            obs[6 * i, k] = s * ox
            obs[6 * i + 1, k] = s * oy
            obs[6 * i + 2, k] = s * (R[j, 3] + noise.obstacles[i, k, 2])
            obs[6 * i + 3, k] = s * (R[j, 4] + noise.obstacles[i, k, 3])
            obs[6 * i + 4, k], obs[6 * i + 5, k] = _polar(ox - px, oy - py, yaw)


@kernel
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


@kernel(R=Matrix, flags=FLAG_INPUTS, step=Int, wheels=Matrix, valid=Flags, stuck=Flags)
def robot_flags(R, flags, step, wheels, valid, stuck):
    """Per robot, from its state R (n, 6: x y yaw vx vy w; the ground robots first, as many as ``flags.rim``
    has rows, then the aerial ones): the rim speeds its actual motion means (what wheel encoders measure;
    zero beyond its wheels, and for an aerial robot) into ``wheels`` (n, W, of any float type), whether it is
    over the field within 1 m and enabled (``valid``), and whether it is stuck (a ground robot commanded
    > 0.2 m/s but moving at less than half of it for ``flags.stuck_steps``; updates ``flags.slow_since``;
    an aerial robot never is)."""
    rim = flags.rim
    ground = rim.shape[0]
    for i in range(R.shape[0]):
        valid[i] = (
            abs(R[i, 0]) <= flags.half_length + 1.0 and abs(R[i, 1]) <= flags.half_width + 1.0 and flags.enabled[i]
        )
        if i >= ground:
            wheels[i, :] = 0.0
            stuck[i] = False
            continue
        c = np.cos(R[i, 2])
        s = np.sin(R[i, 2])
        bvx = c * R[i, 3] + s * R[i, 4]
        bvy = c * R[i, 4] - s * R[i, 3]
        w = R[i, 5]
        for k in range(rim.shape[1]):
            on = k < flags.n_wheels[i]
            wheels[i, k] = (rim[i, k, 0] * bvx + rim[i, k, 1] * bvy + rim[i, k, 2] * w) if on else 0.0
        stuck[i] = _stuck(i, R[i, 3], R[i, 4], flags.setpoint, flags.slow_since, step, flags.stuck_steps)


@kernel(xpos=Matrix, geoms=Indices, bound2=Vector, ball=Int)
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


@kernel
def fill_model_states(qpos, qvel, robot_q, robot_v, n, ball_q, ball_v, pose, twist):
    """The world-frame states of n ground robots and the ball into zeroed ``pose`` (n+1, 7: x y z qw qx qy qz)
    and ``twist`` (n+1, 6: v, w) of any float type: each number computed in float64, then stored (a float32
    array rounds it once, as ``astype(float32)`` of the float64 numbers would). A robot stands on the floor,
    turned by its yaw; the ball's spin is turned from its own frame to the world's."""
    for i in range(n):
        half = 0.5 * qpos[robot_q + 3 * i + 2]
        pose[i, 0] = qpos[robot_q + 3 * i]
        pose[i, 1] = qpos[robot_q + 3 * i + 1]
        pose[i, 3] = np.cos(half)
        pose[i, 6] = np.sin(half)
        twist[i, 0] = qvel[robot_v + 3 * i]
        twist[i, 1] = qvel[robot_v + 3 * i + 1]
        twist[i, 5] = qvel[robot_v + 3 * i + 2]
    free_body_state(qpos, qvel, ball_q, ball_v, pose[n], twist[n])


@kernel
def free_body_state(qpos, qvel, qa, va, pose, twist):
    """The world-frame state of a body on a free joint (at ``qpos[qa]``, ``qvel[va]``) into ``pose`` (7: x y z
    qw qx qy qz) and ``twist`` (6: v, w): its angular velocity turned from its own frame to the world's."""
    for k in range(7):
        pose[k] = qpos[qa + k]
    for k in range(3):
        twist[k] = qvel[va + k]
    twist[3], twist[4], twist[5] = rotate(
        qpos[qa + 3], qpos[qa + 4], qpos[qa + 5], qpos[qa + 6], qvel[va + 3], qvel[va + 4], qvel[va + 5]
    )


#: the engine's state and where n ground robots' and the ball's joints are in it: the first parameters of
#: the kernels of the models' states
_MODEL_STATES = dict(qpos=Vector, qvel=Vector, robot_q=Int, robot_v=Int, n=Int, ball_q=Int, ball_v=Int)


@kernel(**_MODEL_STATES, pose=Floats32, twist=Floats32)
def model_states32(qpos, qvel, robot_q, robot_v, n, ball_q, ball_v, pose, twist):
    """`fill_model_states` into float32 zeros ``pose`` (7 (n+1),) and ``twist`` (6 (n+1),), flat as the
    ModelStates message carries them."""
    fill_model_states(
        qpos, qvel, robot_q, robot_v, n, ball_q, ball_v, pose.reshape((n + 1, 7)), twist.reshape((n + 1, 6))
    )


@kernel
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


@kernel(
    qpos=Vector,
    qvel=Vector,
    joints=JOINTS,
    flags=FLAG_INPUTS,
    step=Int,
    **_OBSERVERS,
    R=Matrix,
    ball=Vector,
    **_PERCEIVED,
    wheels=Matrix32,
    valid=Flags,
    stuck=Flags,
)
def sense_ground(qpos, qvel, joints, flags, step, sign, others, noise, R, ball, own, balls, obs, wheels, valid, stuck):
    """`robot_flags` and `perceive` of a world of ground robots alone, straight from the engine's ``qpos`` and
    ``qvel``: the robots' and the ball's states are read into ``R`` (n, 6) and ``ball`` (6,) first."""
    for i in range(R.shape[0]):
        for k in range(3):
            R[i, k] = qpos[joints.robot_q + 3 * i + k]
            R[i, 3 + k] = qvel[joints.robot_v + 3 * i + k]
    for k in range(3):
        ball[k] = qpos[joints.ball_q + k]
        ball[3 + k] = qvel[joints.ball_v + k]
    robot_flags(R, flags, step, wheels, valid, stuck)
    perceive(R, ball, sign, others, noise, own, balls, obs)


# --- the exact states' fingerprint ---------------------------------------------------------------------------
# A recording takes a fingerprint of the exact (float64) model states at every control tick, so that a
# re-simulation is checked below the float32 the states are recorded in. It needs to tell any difference, not
# to resist an adversary: per 64-bit word of the states a round like xxHash64's (the word's product xored in,
# not added), then xxHash64's final mix. Each step is a bijection of the running value, so a difference in one
# word always changes the result; two differences cancel with a chance of 1 in 2**64. It is cheap enough to take
# at every control tick, where a cryptographic hash would be a visible part of a match's time.
_P1 = np.uint64(0x9E3779B185EBCA87)
_P2 = np.uint64(0xC2B2AE3D27D4EB4F)
_P3 = np.uint64(0x165667B19E3779F9)
_L31, _R33 = np.uint64(31), np.uint64(33)  # a rotation left by 31 bits
_S33, _S29, _S32 = np.uint64(33), np.uint64(29), np.uint64(32)


@kernel
def mix_begin(n):
    """The running value of a fingerprint of ``n`` words, before the first (`mix64` in parts: a fingerprint of
    words that are not one array, e.g. a strided column, with the same value as `mix64` of them gathered)."""
    return np.uint64(n) * _P3


@kernel
def mix_word(h, w):
    """The running value ``h`` after one more word ``w``."""
    h ^= w * _P2
    return ((h << _L31) | (h >> _R33)) * _P1


@kernel
def mix_end(h):
    """The fingerprint from the running value after the last word."""
    h ^= h >> _S33
    h *= _P2
    h ^= h >> _S29
    h *= _P3
    h ^= h >> _S32
    return h


@kernel
def mix64(words):
    """The fingerprint of ``words`` (uint64, C-ordered: an array, or a tuple of words taken as one): see above;
    the same on every machine (integer arithmetic modulo 2**64)."""
    h = mix_begin(len(words))
    for w in words:
        h = mix_word(h, w)
    return mix_end(h)


@kernel(**_MODEL_STATES, state=Vector, words=Words)
def model_fingerprint(qpos, qvel, robot_q, robot_v, n, ball_q, ball_v, state, words):
    """`mix64` of the exact poses then twists (`fill_model_states`' numbers), filled into the float64 block
    ``state`` (13 (n+1) zeros, the positions `fill_model_states` leaves zero never written) whose words
    ``words`` are (its uint64 view)."""
    m = n + 1
    fill_model_states(
        qpos, qvel, robot_q, robot_v, n, ball_q, ball_v, state[: 7 * m].reshape((m, 7)), state[7 * m :].reshape((m, 6))
    )
    return mix64(words)
