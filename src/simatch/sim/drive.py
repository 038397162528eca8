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
point is clamped at the target, see `Simulator`) and Python is not involved at every physics step.
From rest, or whenever no wheel reverses, this is exactly the per-step rule `ramp_step`; when a wheel
passes through zero inside a window, the window keeps the slower, speeding-up bound (never faster).

The body velocity set point is v = M+ U (M+ the pseudo-inverse). Robots with fewer wheels are padded
with zero rows, so one (N, W) array serves every model.
"""

from __future__ import annotations

import numpy as np

from .kernels import plan_drive

_TINY = 1e-300


def ramp_step(U: np.ndarray, U_target: np.ndarray, up: float, down: float) -> np.ndarray:
    """The per-step rule: rim speeds after one physics step (``up``/``down``: per-step bounds)."""
    dU = U_target - U
    adU = np.abs(dU)
    if adU.max() == 0.0:
        return U_target.copy()
    bound = np.where(U * dU >= 0.0, up, down)
    frac = min(1.0, float(np.min(bound / np.maximum(adU, _TINY))))
    return U + frac * dU


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
            self.Mpinv[i, :, : m.shape[0]] = np.linalg.pinv(m)
        self.max_speed = np.broadcast_to(np.asarray(max_speed, dtype=float), (n,)).copy()
        self.up = np.ascontiguousarray(np.broadcast_to(np.asarray(max_accel, dtype=float), (n,)) * dt)
        self.down = np.ascontiguousarray(np.broadcast_to(np.asarray(max_decel, dtype=float), (n,)) * dt)
        self.dt = dt
        self.cmd = np.zeros((n, 3))          # latest body-frame command per robot
        self.U_target = np.zeros((n, W))     # speed-limited target rim speeds
        self.dirty = np.zeros(n, dtype=bool)     # a command arrived since the last plan
        self.ramping = np.zeros(n, dtype=bool)   # the last plan did not reach the target
        self.any_dirty = False

    # --- commands -----------------------------------------------------------------------------------------
    def command(self, i: int, vx: float, vy: float, w: float) -> None:
        """Robot i's body-frame velocity command (assumed finite; the caller validates)."""
        self.cmd[i, 0] = vx
        self.cmd[i, 1] = vy
        self.cmd[i, 2] = w
        self.dirty[i] = True
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
    def plan(self, due: np.ndarray, act: np.ndarray, window: int, actrange: np.ndarray, ctrl: np.ndarray,
             bias: np.ndarray, kv: np.ndarray) -> None:
        """Plan the next ``window`` steps of the robots marked in ``due`` whose servo set points are ``act``
        (N, 3); writes the set points' bounds, rates and bias (see `kernels.plan_drive`)."""
        plan_drive(self.M, self.Mpinv, self.cmd, self.dirty, due, self.U_target, self.up, self.down,
                   self.max_speed, act, window, actrange, ctrl, bias, kv, self.ramping, self.dt)
        self.any_dirty = bool(self.dirty.any())
