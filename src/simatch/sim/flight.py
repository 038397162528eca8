"""The aerial robots' onboard flight controller, run inside every physics step for all of them at once.

A drone takes the same command as every robot (VelCmd: body-frame vx, vy and turn rate w, plus the
vertical speed vz) and its controller turns it into four rotor thrusts through the usual cascade:

1. **Hold point.** The commanded velocity (vx, vy turned by the drone's heading, and vz) moves a hold
   point; the velocity target is the command plus a pull back onto that point (``position_gain``), so a
   drone told to stand still holds where it is and one told to move follows the commanded path. The hold
   point stays within ``leash`` of the body (after a push or a collision the drone does not fly back
   across the arena). The commanded turn rate moves a heading set point the same way.
2. **Velocity loop** (PI, ``velocity_gain``, ``velocity_integral``, with the rotor drag fed forward): the
   wanted acceleration, its horizontal part capped by the tilt limit (``max_tilt``).
3. **Thrust and attitude.** The wanted force m (a + g z) gives the collective thrust (its part along the
   body's z axis) and the wanted direction of the body's z axis; with the heading set point it makes the
   wanted attitude. The attitude error (on SO(3), as in Lee, Leok and McClamroch 2010) sets the wanted body
   rates (``attitude_gain``), with the turn rate fed forward.
4. **Rate loop** (``rate_gain``): the torques that bring the body rates to the wanted ones (gyroscopic
   terms included).
5. **Mixer**: four rotor thrusts that give the collective thrust and the three torques; when a rotor
   would have to go past its limits, yaw is given up first, then the collective thrust, then the
   roll/pitch torques are scaled down, never the other way round (attitude keeps a drone flying).

The rotors' commanded thrusts are the actuators' controls; the engine applies each with its motor lag.
Everything is one compiled call per physics step (no Python per drone), the same IEEE arithmetic every
time, so runs stay deterministic.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ..compiled import Array, Float, Matrix, Vector, bind, kernel
from ..robots import exact
from .kernels import Indices, free_body_state, wrap_angle

#: one drone's parameters, a row of the fleet's table: mass [kg], principal inertia [kg m^2], a rotor's
#: largest thrust [N], rotor drag (horizontal, vertical) [N s/m], the gains of the cascade (position,
#: velocity, velocity integral, attitude, rate) and the tangent of the largest tilt, the hold point's leash [m]
PARAMS = np.dtype(
    [
        (name, np.float64)
        for name in ("mass ixx iyy izz fmax drag_xy drag_z k_pos k_vel k_int k_att k_rate tan_tilt leash".split())
    ]
)
#: the heading set point stays this close to the heading [rad]
YAW_LEASH = 0.5
#: the integral of the velocity loop gives at most this acceleration [m/s^2]
INTEGRAL_LIMIT = 3.0


@kernel(
    qpos=Vector,
    qvel=Vector,
    ctrl=Vector,
    qadr=Indices,
    vadr=Indices,
    rotor=Array(np.int64, 2),
    P=Array(PARAMS, 1),
    mix=Array(np.float64, 3),
    cmd=Matrix,
    armed=Array(np.bool_, 1),
    pref=Matrix,
    vref=Matrix,
    yref=Vector,
    vint=Matrix,
    dt=Float,
    g=Float,
)
def fly(qpos, qvel, ctrl, qadr, vadr, rotor, P, mix, cmd, armed, pref, vref, yref, vint, dt, g):
    """One physics step of every drone's controller: writes the four rotor thrust commands into ``ctrl``.

    qadr, vadr (A,) free-joint addresses; rotor (A, 4) actuator ids; P (A,) `PARAMS`; mix (A, 4, 4) the
    mixer's inverse (rotor thrusts from collective thrust and torques); cmd (A, 4) vx, vy (heading frame),
    w, vz; armed (A,) motors on; pref, vref (A, 3), yref (A,), vint (A, 3) the controller's state (updated)."""
    R = np.empty((3, 3))
    Rd = np.empty((3, 3))
    wrench = np.empty(4)
    f = np.empty(4)
    for k in range(qadr.shape[0]):
        qa = qadr[k]
        va = vadr[k]
        if not armed[k]:
            for j in range(4):
                ctrl[rotor[k, j]] = 0.0
            for j in range(3):
                pref[k, j] = qpos[qa + j]
                vref[k, j] = 0.0
                vint[k, j] = 0.0
            continue
        p = P[k]
        _body_rotation(qpos[qa + 3], qpos[qa + 4], qpos[qa + 5], qpos[qa + 6], R)
        yaw = math.atan2(R[1, 0], R[0, 0])
        afx, afy, afz, dx, dy, dz = _follow_reference(
            p, cmd[k], pref[k], vref[k], yref, k, qpos[qa], qpos[qa + 1], qpos[qa + 2], yaw, dt
        )
        ax, ay, az = _velocity_loop(
            p, R, qvel[va], qvel[va + 1], qvel[va + 2], vref[k], vint[k], afx, afy, afz, dx, dy, dz, dt
        )
        thrust = _attitude_wanted(p, R, ax, ay, az, yref[k], g, Rd)
        _rate_loop(p, R, Rd, cmd[k, 2], qvel[va + 3], qvel[va + 4], qvel[va + 5], thrust, wrench)
        _mix(mix[k], wrench, f, p.fmax)
        for j in range(4):
            ctrl[rotor[k, j]] = f[j]


@kernel
def _body_rotation(qw, qx, qy, qz, R):
    """R (3, 3): the rotation body -> world of the unit quaternion (qw, qx, qy, qz)."""
    R[0, 0] = 1.0 - 2.0 * (qy * qy + qz * qz)
    R[0, 1] = 2.0 * (qx * qy - qw * qz)
    R[0, 2] = 2.0 * (qx * qz + qw * qy)
    R[1, 0] = 2.0 * (qx * qy + qw * qz)
    R[1, 1] = 1.0 - 2.0 * (qx * qx + qz * qz)
    R[1, 2] = 2.0 * (qy * qz - qw * qx)
    R[2, 0] = 2.0 * (qx * qz - qw * qy)
    R[2, 1] = 2.0 * (qy * qz + qw * qx)
    R[2, 2] = 1.0 - 2.0 * (qx * qx + qy * qy)


@kernel
def _follow_reference(p, cmd, pref, vref, yref, k, px, py, pz, yaw, dt):
    """1. The reference velocity ``vref`` moves towards the command (turned by the heading) at the velocity
    loop's own pace and moves the hold point ``pref`` (kept within the leash of the body at px, py, pz); the
    commanded turn rate moves the heading set point ``yref[k]`` (kept within `YAW_LEASH` of ``yaw``).
    Returns the reference's acceleration (fed forward) and the pull back onto the hold point."""
    c, s = math.cos(yaw), math.sin(yaw)
    kv = p.k_vel
    blend = min(1.0, kv * dt)
    tx = c * cmd[0] - s * cmd[1] - vref[0]
    ty = s * cmd[0] + c * cmd[1] - vref[1]
    tz = cmd[3] - vref[2]
    vref[0] += blend * tx
    vref[1] += blend * ty
    vref[2] += blend * tz
    pref[0] += vref[0] * dt
    pref[1] += vref[1] * dt
    pref[2] += vref[2] * dt
    dx, dy, dz = pref[0] - px, pref[1] - py, pref[2] - pz
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    if d > p.leash:
        sc = p.leash / d
        dx, dy, dz = dx * sc, dy * sc, dz * sc
        pref[0], pref[1], pref[2] = px + dx, py + dy, pz + dz
    yref[k] += cmd[2] * dt
    ey = wrap_angle(yref[k] - yaw)
    if ey > YAW_LEASH:
        ey = YAW_LEASH
    elif ey < -YAW_LEASH:
        ey = -YAW_LEASH
    yref[k] = yaw + ey
    return kv * tx, kv * ty, kv * tz, dx, dy, dz


@kernel
def _velocity_loop(p, R, vx, vy, vz, vref, vint, afx, afy, afz, dx, dy, dz, dt):
    """2. The velocity loop (PI, the pull onto the hold point added to the reference, the integral ``vint``
    updated and bounded) with the reference's acceleration (afx, afy, afz) and the rotor drag (drag =
    R D R^T v) fed forward: the wanted acceleration."""
    kv, kp, ki = p.k_vel, p.k_pos, p.k_int
    evx = vref[0] + kp * dx - vx
    evy = vref[1] + kp * dy - vy
    evz = vref[2] + kp * dz - vz
    if ki > 0.0:
        lim = INTEGRAL_LIMIT / ki
        vint[0] = min(max(vint[0] + evx * dt, -lim), lim)
        vint[1] = min(max(vint[1] + evy * dt, -lim), lim)
        vint[2] = min(max(vint[2] + evz * dt, -lim), lim)
    bx = (R[0, 0] * vx + R[1, 0] * vy + R[2, 0] * vz) * p.drag_xy
    by = (R[0, 1] * vx + R[1, 1] * vy + R[2, 1] * vz) * p.drag_xy
    bz = (R[0, 2] * vx + R[1, 2] * vy + R[2, 2] * vz) * p.drag_z
    m = p.mass
    ax = afx + kv * evx + ki * vint[0] + (R[0, 0] * bx + R[0, 1] * by + R[0, 2] * bz) / m
    ay = afy + kv * evy + ki * vint[1] + (R[1, 0] * bx + R[1, 1] * by + R[1, 2] * bz) / m
    az = afz + kv * evz + ki * vint[2] + (R[2, 0] * bx + R[2, 1] * by + R[2, 2] * bz) / m
    return ax, ay, az


@kernel
def _attitude_wanted(p, R, ax, ay, az, heading, g, Rd):
    """3. The wanted force m (a + g z), its tilt limited, gives the collective thrust (its part along the
    body's z axis, returned) and the wanted attitude ``Rd`` (its z axis along the force, its heading at the
    set point)."""
    m = p.mass
    fz = m * (g + az)
    if fz < 0.2 * m * g:
        fz = 0.2 * m * g
    fx, fy = m * ax, m * ay
    fxy = math.sqrt(fx * fx + fy * fy)
    cap = fz * p.tan_tilt
    if fxy > cap:
        fx *= cap / fxy
        fy *= cap / fxy
    fn = math.sqrt(fx * fx + fy * fy + fz * fz)
    b3x, b3y, b3z = fx / fn, fy / fn, fz / fn
    thrust = fx * R[0, 2] + fy * R[1, 2] + fz * R[2, 2]
    if thrust < 0.0:
        thrust = 0.0
    cy, sy = math.cos(heading), math.sin(heading)
    # b2 = b3 x b1c (b1c = heading set point), normalised; b1 = b2 x b3
    b2x, b2y, b2z = -b3z * sy, b3z * cy, b3x * sy - b3y * cy
    nb = math.sqrt(b2x * b2x + b2y * b2y + b2z * b2z)
    b2x, b2y, b2z = b2x / nb, b2y / nb, b2z / nb
    Rd[0, 0], Rd[1, 0], Rd[2, 0] = b2y * b3z - b2z * b3y, b2z * b3x - b2x * b3z, b2x * b3y - b2y * b3x
    Rd[0, 1], Rd[1, 1], Rd[2, 1] = b2x, b2y, b2z
    Rd[0, 2], Rd[1, 2], Rd[2, 2] = b3x, b3y, b3z
    return thrust


@kernel
def _rate_loop(p, R, Rd, w, ox, oy, oz, thrust, wrench):
    """4. The attitude error e_R = vee(Rd^T R - R^T Rd) / 2 (on SO(3)) sets the wanted body rates, the turn
    rate ``w`` fed forward (world z in the body frame); the rate loop's torques bring the body rates
    (ox, oy, oz) to them, gyroscopic terms included. Writes ``wrench``: thrust and the three torques."""
    e = np.zeros(3)
    for a, (i, j) in enumerate(((2, 1), (0, 2), (1, 0))):
        mij = 0.0
        mji = 0.0
        for r in range(3):
            mij += Rd[r, i] * R[r, j]
            mji += Rd[r, j] * R[r, i]
        e[a] = 0.5 * (mij - mji)
    katt, kr = p.k_att, p.k_rate
    wdx = -katt * e[0] + w * R[2, 0]
    wdy = -katt * e[1] + w * R[2, 1]
    wdz = -katt * e[2] + w * R[2, 2]
    ixx, iyy, izz = p.ixx, p.iyy, p.izz
    wrench[0] = thrust
    wrench[1] = ixx * kr * (wdx - ox) + (izz - iyy) * oy * oz
    wrench[2] = iyy * kr * (wdy - oy) + (ixx - izz) * oz * ox
    wrench[3] = izz * kr * (wdz - oz) + (iyy - ixx) * ox * oy


@kernel
def _span(d, yaw, s):
    lo = np.inf
    hi = -np.inf
    for j in range(4):
        v = d[j] + s * yaw[j]
        lo = min(lo, v)
        hi = max(hi, v)
    return hi - lo


@kernel
def _mix(M, wrench, f, fmax):
    """Rotor thrusts f (4,) within [0, fmax] for wrench (thrust, tx, ty, tz) through the inverse mixer M:
    exact when it fits; else the roll/pitch torques kept whole (scaled down only if they alone do not
    fit), as much of the yaw torque as fits beside them, and the collective thrust nearest to the wanted
    one that keeps every rotor within its limits."""
    for j in range(4):
        f[j] = M[j, 0] * wrench[0] + M[j, 1] * wrench[1] + M[j, 2] * wrench[2] + M[j, 3] * wrench[3]
    if f.min() >= 0.0 and f.max() <= fmax:
        return
    d = np.empty(4)
    yaw = np.empty(4)
    for j in range(4):
        d[j] = M[j, 1] * wrench[1] + M[j, 2] * wrench[2]
        yaw[j] = M[j, 3] * wrench[3]
    span = _span(d, yaw, 0.0)
    if span > fmax:
        for j in range(4):
            d[j] *= fmax / span
    elif _span(d, yaw, 1.0) > fmax:
        lo, hi = 0.0, 1.0  # the largest share of the yaw torque that fits (bisection)
        for _ in range(16):
            mid = 0.5 * (lo + hi)
            if _span(d, yaw, mid) > fmax:
                hi = mid
            else:
                lo = mid
        for j in range(4):
            d[j] += lo * yaw[j]
    else:
        for j in range(4):
            d[j] += yaw[j]
    c = M[0, 0] * wrench[0]  # the collective share of each rotor (equal for a symmetric frame)
    c = min(max(c, -d.min()), fmax - d.max())
    for j in range(4):
        f[j] = min(max(c + d[j], 0.0), fmax)


def mixer_inverse(positions, spin, torque_ratio: float) -> np.ndarray:
    """(4, 4) rotor thrusts from (thrust, torque x, torque y, torque z): the inverse of the map from rotor
    thrusts at ``positions`` (body x, y) with drag torque ``-spin * torque_ratio`` per newton."""
    A = np.array(
        [
            [1.0] * 4,
            [y for _, y in positions],
            [-x for x, _ in positions],
            [-s * torque_ratio for s in spin],
        ]
    )
    return exact.inverse(A)


def yaw_of(qw: float, qx: float, qy: float, qz: float) -> float:
    """The heading of the attitude (qw, qx, qy, qz): its turn about the vertical."""
    return math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


class AerialFleet:
    """Every aerial robot's command, controller state and parameters (one row each), stepped by the
    simulator before each physics step. Commands are capped by the drone's limits where they arrive."""

    def __init__(self, data, index, models, dt: float, gravity: float):
        self.d = data
        self.ix = index
        n = len(models)
        self.n = n
        self.dt = dt
        self.gravity = gravity
        self.P = np.zeros(n, dtype=PARAMS)
        self.mix = np.zeros((n, 4, 4))
        self.limits = np.zeros((n, 4))  # max horizontal speed, max turn rate, max climb, max descent
        for k, model in enumerate(models):
            p = model.params
            self.P[k] = (
                p.mass,
                p.ixx,
                p.iyy,
                p.izz,
                model.max_rotor_thrust,
                p.drag_xy,
                p.drag_z,
                p.position_gain,
                p.velocity_gain,
                p.velocity_integral,
                p.attitude_gain,
                p.rate_gain,
                math.tan(math.radians(p.max_tilt)),
                p.leash,
            )
            self.mix[k] = mixer_inverse(model.rotor_positions(), model.rotor_spin, p.torque_ratio)
            self.limits[k] = (p.max_speed, p.max_yaw_rate, p.max_climb, p.max_descent)
        self.cmd = np.zeros((n, 4))
        self.armed = np.array([m.params.start_altitude > 0.0 for m in models], dtype=bool)
        self.pref = np.zeros((n, 3))
        self.vref = np.zeros((n, 3))
        self.yref = np.zeros(n)
        self.vint = np.zeros((n, 3))
        self._fly = bind(fly)
        for k in range(n):
            self.hold(k)

    def command(self, k: int, vx: float, vy: float, w: float, vz: float) -> None:
        """Drone k's command (finite; the caller validates), capped by its limits. A landed drone (motors
        off) takes off when told to climb."""
        vmax, wmax, up, down = self.limits[k]
        speed = math.hypot(vx, vy)
        if speed > vmax:
            vx, vy = vx * vmax / speed, vy * vmax / speed
        c = self.cmd[k]
        c[0], c[1] = vx, vy
        c[2] = min(max(w, -wmax), wmax)
        c[3] = min(max(vz, -down), up)
        if vz > 0.0 and not self.armed[k]:
            self.armed[k] = True
            self.hold(k)

    def stop(self, k: int) -> None:
        self.cmd[k] = 0.0

    def arm(self, k: int, on: bool) -> None:
        """Motors of drone k on (it holds where it is) or off (no thrust at all)."""
        self.armed[k] = on
        if on:
            self.hold(k)

    def hold(self, k: int) -> None:
        """Hold where drone k is now (after a teleport): the hold point, heading and integral start afresh."""
        q = self.d.qpos
        a = self.ix.qpos[k]
        self.pref[k] = q[a : a + 3]
        self.vref[k] = self.d.qvel[self.ix.qvel[k] : self.ix.qvel[k] + 3]
        self.yref[k] = yaw_of(*q[a + 3 : a + 7])
        self.vint[k] = 0.0

    def step(self, ctrl) -> None:
        """Every drone's rotor commands for the next physics step, into the engine's ``ctrl``."""
        d, ix = self.d, self.ix
        self._fly(
            d.qpos,
            d.qvel,
            ctrl,
            ix.qpos,
            ix.qvel,
            ix.rotor,
            self.P,
            self.mix,
            self.cmd,
            self.armed,
            self.pref,
            self.vref,
            self.yref,
            self.vint,
            self.dt,
            self.gravity,
        )


@kernel
def aerial_poses(qpos, qvel, qadr, vadr):
    """Poses (A, 7: x y z qw qx qy qz) and world-frame twists (A, 6: v, w) of the free-flying bodies (their
    angular velocity turned from the body frame to the world frame)."""
    n = qadr.shape[0]
    pose = np.empty((n, 7))
    twist = np.empty((n, 6))
    for k in range(n):
        free_body_state(qpos, qvel, qadr[k], vadr[k], pose[k], twist[k])
    return pose, twist


def planar(pose: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """(A, 6) x y yaw vx vy w (world frame, w about z) of free bodies, as every robot's planar state."""
    out = np.empty((len(pose), 6))
    out[:, 0:2] = pose[:, 0:2]
    out[:, 2] = [yaw_of(*q) for q in pose[:, 3:7].tolist()]  # the C library's atan2, not NumPy's (by CPU)
    out[:, 3:5] = twist[:, 0:2]
    out[:, 5] = twist[:, 5]
    return out


def rotor_links(model, pose: np.ndarray, twist: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """(pose, twist) of each rotor hub of an aerial robot whose body has ``pose`` and world ``twist``."""
    quat = np.ascontiguousarray(pose[3:7])
    w = twist[3:6]
    out = []
    for rx, ry in model.rotor_positions():
        r = np.empty(3)
        mujoco.mju_rotVecQuat(r, np.array((rx, ry, 0.0)), quat)  # not `@`: BLAS's kernels depend on the CPU
        out.append((np.concatenate((pose[:3] + r, pose[3:7])), np.concatenate((twist[:3] + np.cross(w, r), w))))
    return out


@kernel
def frame_contacts(pairs, n, owner):
    """(drone, other geom) of every contact among the first ``n`` geom ``pairs`` that involves a drone's frame
    (``owner``: geom id -> drone index, -1 for any other geom); both ways for two drones."""
    out = []
    for c in range(n):
        a, b = pairs[c, 0], pairs[c, 1]
        ka, kb = owner[a], owner[b]
        if ka >= 0:
            out.append((ka, b))
        if kb >= 0:
            out.append((kb, a))
    return out
