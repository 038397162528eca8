"""Omnidirectional drive: from body-frame velocity commands to limited wheel speeds, for all robots at once.

For every robot, a command v = (vx, vy, w) becomes rim speeds U* = M v (paper Eq. 2-3, M = r A). Limits
act in the robot frame, on the wheels, and always scale all wheels of a robot together so the direction
of motion is kept:

* speed: if any |U*_i| exceeds the rim speed limit, U* is scaled down as a whole;
* acceleration: the wheels move from their current speeds U straight towards U*, by the same fraction of
  U* - U for every wheel each physics step, the largest fraction such that no wheel changes by more than
  a_up dt when it speeds up (or starts from rest, or will pass through zero within the planning window)
  and a_down dt when it slows down. All wheels reach U* together.

The drive plans once per control period (and when a command arrives): the per-step change is constant
within that window, so the physics engine integrates the ramp itself (integrator actuators whose set
point is clamped at the target, see `simatch.robots.body`). From rest, or whenever no wheel reverses, this
is exactly the per-step rule above; when a wheel passes through zero inside a window, the window keeps the
slower, speeding-up bound (never faster).

The body velocity set point is v = M+ U (M+ the pseudo-inverse). Robots with fewer wheels are padded
with zero rows, so one (N, W) array serves every model.
"""

from __future__ import annotations

import struct

import numpy as np

from ..compiled import Array, Float, Int, Matrix, Vector, kernel
from . import exact

_TINY = 1e-300
#: a robot's command row (vx, vy, w as float64), written into its memory in one call
TWIST = struct.Struct("=3d")
_Tensor = Array(np.float64, 3)
_Flags = Array(np.bool_, 1)


@kernel(
    M=_Tensor,
    P=_Tensor,
    cmd=Matrix,
    dirty=_Flags,
    due=_Flags,
    U_target=Matrix,
    up=Vector,
    down=Vector,
    max_speed=Vector,
    act=Matrix,
    window=Int,
    actrange=_Tensor,
    ctrl=Matrix,
    biasprm=_Tensor,
    kv=Matrix,
    ramping=_Flags,
    dt=Float,
)
def plan_drive(
    M, P, cmd, dirty, due, U_target, up, down, max_speed, act, window, actrange, ctrl, biasprm, kv, ramping, dt
):
    """Plan the wheel ramps of the robots marked in ``due`` for the next ``window`` physics steps.

    M (N, W, 3) rim-speed matrices, P (N, 3, W) their pseudo-inverses, cmd (N, 3) body-frame commands,
    dirty (N,) commands not yet turned into U_target (N, W) rim-speed targets; up/down (N,) per-step
    bounds of speeding up / slowing down; act (N, 3) the servos' current set points.
    Writes, for each due robot: actrange (N, 3, 2) the set point's bounds (it stops at the target),
    ctrl (N, 3) its rate of change [per s], the servos' constant bias force biasprm[:, :, 0] (N, 3, P: the
    model's bias parameters) the exact-arc correction, ramping (N,)."""
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
        biasprm[i, 0, 0] = -kv[i, 0] * theta * vm[1]
        biasprm[i, 1, 0] = kv[i, 1] * theta * vm[0]
        biasprm[i, 2, 0] = 0.0


class OmniDrive:
    """Wheel-speed targets and limits of N robots (one row per robot)."""

    def __init__(self, rim_matrices: list[np.ndarray], max_speed, max_accel, max_decel, dt: float):
        n = len(rim_matrices)
        self.n = n
        self.n_wheels = np.array([m.shape[0] for m in rim_matrices], dtype=int)
        self.max_wheels = int(max(self.n_wheels)) if n else 0
        W = self.max_wheels
        self.M = np.zeros((n, W, 3))
        self.Mpinv = np.zeros((n, 3, W))
        for i, m in enumerate(rim_matrices):
            self.M[i, : m.shape[0]] = m
            self.Mpinv[i, :, : m.shape[0]] = exact.pseudo_inverse(m)
        self.max_speed = np.broadcast_to(np.asarray(max_speed, dtype=float), (n,)).copy()
        self.up = np.ascontiguousarray(np.broadcast_to(np.asarray(max_accel, dtype=float), (n,)) * dt)
        self.down = np.ascontiguousarray(np.broadcast_to(np.asarray(max_decel, dtype=float), (n,)) * dt)
        self.dt = dt
        self.cmd = np.zeros((n, 3))  # latest body-frame command per robot
        self.U_target = np.zeros((n, W))  # speed-limited target rim speeds
        self.dirty = np.zeros(n, dtype=bool)  # a command arrived since the last plan
        self.ramping = np.zeros(n, dtype=bool)  # the last plan did not reach the target
        self.any_dirty = False
        #: each robot's row of ``cmd`` and the ``dirty`` flags as memoryviews (the same memory, fixed for the
        #: drive's life), written by plain Python calls: a command is taken at every control tick of every robot
        self.command_rows = [memoryview(row) for row in self.cmd]
        self.dirty_flags = memoryview(self.dirty)
        self.ramping_flags = memoryview(self.ramping)

    # --- commands -----------------------------------------------------------------------------------------
    def command(self, i: int, vx: float, vy: float, w: float) -> None:
        """Robot i's body-frame velocity command (assumed finite; the caller validates)."""
        TWIST.pack_into(self.command_rows[i], 0, vx, vy, w)
        self.dirty_flags[i] = True
        self.any_dirty = True

    def stop(self, i: int) -> None:
        self.command(i, 0.0, 0.0, 0.0)

    def target_speeds(self, V: np.ndarray, rows=slice(None)) -> np.ndarray:
        """Speed-limited rim speeds (rows, W) of body velocities V (rows, 3)."""
        u = np.einsum("nwk,nk->nw", self.M[rows], V)
        peak = np.abs(u).max(axis=1)
        scale = np.minimum(1.0, self.max_speed[rows] / np.maximum(peak, _TINY))
        return u * scale[:, None]

    # --- planning -------------------------------------------------------------------------------------------
    def plan(
        self,
        due: np.ndarray,
        act: np.ndarray,
        window: int,
        actrange: np.ndarray,
        ctrl: np.ndarray,
        bias: np.ndarray,
        kv: np.ndarray,
    ) -> None:
        """Plan the next ``window`` steps of the robots marked in ``due`` whose servo set points are ``act``
        (N, 3); writes the set points' bounds, rates and bias forces (N, 3) (see `plan_drive`)."""
        plan_drive(
            self.M,
            self.Mpinv,
            self.cmd,
            self.dirty,
            due,
            self.U_target,
            self.up,
            self.down,
            self.max_speed,
            act,
            window,
            actrange,
            ctrl,
            bias.reshape(len(bias), 3, 1),
            kv,
            self.ramping,
            self.dt,
        )
        self.any_dirty = bool(self.dirty.any())
