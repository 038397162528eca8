"""Dribbler and kicker: the robot mechanisms that act on the ball.

Dribbler. When a robot's dribbler is on and the ball lies in its mouth (within the scene's distance and
bearing thresholds, on the ground, not arriving faster than the rollers can absorb), a connect constraint
ties the ball's centre to a point of the robot and draws that point into the mouth at the rollers' speed.
The constraint is physical: the engine computes the force it needs, and when that force exceeds the
dribbler's grip (a violent turn or acceleration, or an opponent wrestling for the ball) the ball is lost.
Nothing is teleported.

Rollers. While the ball is held, the dribbler's rollers keep it turning: every physics step they turn its
horizontal spin towards ``roller_spin`` times rolling with its motion over the floor, with at most
``roller_torque`` (a real active dribbler does so, and the MSL rules, RC-12.3.1, forbid forces against the
ball's natural rotation; the referee judges the ball's spin). Without them the floor alone turns the held
ball, lagging when the robot speeds up; ``roller_spin = 0`` models a dribbler that clamps the ball.

Kicker. A kick request fires at the first physics step the ball sits in the mouth: it releases the
dribbler and gives the ball the robot's own velocity at the mouth plus the kick speed along the heading
(ground kick, with rolling spin) or along the heading tilted up by the lob angle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from ..compiled import bind
from .kernels import catch_candidate, in_mouth, keep_ball, mouth_velocity, roll_held_ball

#: a bound on any robot's speed, used only to know when no catch can happen yet [m/s]
_ROBOT_TOP_SPEED = 12.0
#: how long a robot that lost the ball (grip exceeded) cannot take it back while it is still in its mouth [s]
RECATCH_WAIT = 0.5


@dataclass
class KickRequest:
    speed: float
    lob: bool
    until_step: int


class BallHandling:
    """Every ground robot's dribbler and kicker, and the ball they act on (see the module)."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, index, robot_models, scene, on_event):
        self.m, self.d, self.ix = model, data, index
        self.n = len(index.robots)
        self.on_event = on_event
        self.ball_r = scene.ball.radius
        self._dt = model.opt.timestep
        self._init_dribbler(scene.dribbler, model, index)
        self._init_kicker(scene.kicker)
        self.mouth = np.array([[rm.mouth_x(self.ball_r), 0.0, 0.0] for rm in robot_models])
        self._mouth_x = np.ascontiguousarray(self.mouth[:, 0])
        self._mouth_xs = self._mouth_x.tolist()
        self.holder = -1
        self.hold_since = 0
        # a robot that lost the ball cannot take it again until the ball has left its mouth (or for
        # RECATCH_WAIT seconds): the lost ball is on its way out, not to be caught back at once
        self.lost_by = -1
        self.lost_until = 0
        self.recatch_steps = round(RECATCH_WAIT / self._dt)
        # the engine's arrays the kernels read and write (their memory is fixed for the model's and the data's
        # life), and where the ground robots' joints (consecutive) and the ball's start
        self._qpos, self._qvel, self._eq_data = data.qpos, data.qvel, model.eq_data
        self._qpos_flat = memoryview(self._qpos)  # items are plain floats
        self._robot_q0 = int(index.robot_qpos[0, 0]) if len(index.robot_qpos) else 0
        self._robot_v0 = int(index.robot_qvel[0, 0]) if len(index.robot_qvel) else 0
        self._ball_q, self._ball_v = int(index.ball_qpos), int(index.ball_qvel)
        self._dribble_eq = [int(e) for e in index.dribble_eq]
        self._eq_rows_type = int(mujoco.mjtConstraint.mjCNSTR_EQUALITY.value)
        self._roll = bind(roll_held_ball)
        self._keep_kernel = bind(keep_ball)
        self._catch_kernel = bind(catch_candidate)
        self._in_mouth = bind(in_mouth)
        self._mouth_vel = bind(mouth_velocity)

    def _init_dribbler(self, dr, model: mujoco.MjModel, index) -> None:
        dt = model.opt.timestep
        self.hold_dist = dr.distance
        self.hold_cos = math.cos(math.radians(dr.angle))
        self.grip = dr.grip_force
        self.pull_step = dr.pull_speed * dt
        self.catch_speed = dr.catch_speed
        self.settle_steps = max(1, round(dr.settle_time / dt))
        inertia = float(model.body_inertia[index.ball_body, 0])  # a sphere: the same about every axis
        self.roller_spin = dr.roller_spin
        self.roller_dw = dr.roller_torque * dt / inertia  # spin change per step at most [rad/s]
        self.dribble_on = np.zeros(self.n, dtype=bool)
        self.dribbling = [False] * self.n  # the same as plain bools (read for every command and step)
        self._dribblers = 0  # how many are on
        self._catch_idle_until = 0  # no catch is possible before this step (see _catch)
        self._catch_top = self.ball_r + 0.05  # a ball whose centre is higher is in the air: no catch
        # the robots whose dribbler is on and that are usable, as `catch_candidate` takes them (int64), kept
        # while neither changes (`set_dribbler` forgets them; the usable flags are compared as bytes)
        self._cand: np.ndarray | None = None
        self._cand_usable = b""

    def _init_kicker(self, kk) -> None:
        self.kick_max = kk.max_speed
        self.lob_max = kk.max_lob_speed
        self.lob_angle = math.radians(kk.lob_angle)
        self.recharge_steps = round(kk.recharge / self._dt)
        self.kicks: dict[int, KickRequest] = {}
        self.ready_at = np.zeros(self.n, dtype=np.int64)
        self.kicked_by = -1  # robot whose kicker fired during the last step, -1 if none
        self.kicked_speed = 0.0
        self.kicked_lob = False

    # --- requests from commands -----------------------------------------------------------------------------
    def set_dribbler(self, i: int, on: bool) -> None:
        on = bool(on)
        self._dribblers += on - self.dribbling[i]
        self.dribbling[i] = on
        self.dribble_on[i] = on
        self._catch_idle_until = 0
        self._cand = None
        if not on and self.holder == i:
            self.release("dribbler_off")

    def request_kick(self, i: int, speed: float, lob: bool, until_step: int) -> None:
        if speed <= 0.0:
            self.kicks.pop(i, None)
            return
        self.kicks[i] = KickRequest(min(speed, self.lob_max if lob else self.kick_max), lob, until_step)

    # --- the mouth ----------------------------------------------------------------------------------------
    def in_mouth(self, i: int) -> bool:
        """Whether the ball is in robot i's mouth (`kernels.mouth_view`, as a catch judges it)."""
        return self._in_mouth(
            self._qpos, self._robot_q0, self._ball_q, i, self.hold_dist, self.hold_cos, self._catch_top
        )

    def _mouth_velocity(self, i: int) -> np.ndarray:
        """World velocity (vx, vy, 0) of robot i's mouth point (`kernels.mouth_velocity`)."""
        vx, vy = self._mouth_vel(self._qpos, self._qvel, self._robot_q0, self._robot_v0, i, self._mouth_xs[i])
        return np.array([vx, vy, 0.0])

    # --- per physics step ---------------------------------------------------------------------------------
    def before_step(self, step: int, enabled: np.ndarray) -> None:
        self.kicked_by = -1
        if self.kicks:
            self._kicks(step, enabled)
        if self.holder >= 0:
            self._keep(step, enabled)
            if self.holder >= 0 and self.roller_dw > 0.0:
                self._roll(
                    self._qpos, self._qvel, self._ball_q, self._ball_v, self.ball_r, self.roller_spin, self.roller_dw
                )
        elif step >= self._catch_idle_until and self._dribblers:
            self._catch(step, enabled)

    def _kicks(self, step: int, enabled: np.ndarray) -> None:
        for i in sorted(self.kicks):
            req = self.kicks[i]
            if step > req.until_step or not enabled[i]:
                del self.kicks[i]
                continue
            if step < self.ready_at[i] or self.kicked_by >= 0:
                continue
            if self.holder == i or (self.holder < 0 and self.in_mouth(i)):
                self._fire(i, req, step)
                del self.kicks[i]

    def _fire(self, i: int, req: KickRequest, step: int) -> None:
        if self.holder >= 0:
            self.release("kick")
        yaw = self.d.qpos[self.ix.robot_qpos[i, 2]]
        c, s = math.cos(yaw), math.sin(yaw)
        v = self._mouth_velocity(i)
        bv = self.ix.ball_qvel
        if req.lob:
            ch, sv = math.cos(self.lob_angle), math.sin(self.lob_angle)
            v += (req.speed * ch * c, req.speed * ch * s, req.speed * sv)
            self.d.qvel[bv : bv + 3] = v
            self.d.qvel[bv + 3 : bv + 6] = 0.0
        else:
            v += (req.speed * c, req.speed * s, 0.0)
            self.d.qvel[bv : bv + 3] = v
            # rolling without slipping: w = z x v / r, expressed in the ball's own frame (free-joint convention)
            w_world = np.array([-v[1], v[0], 0.0]) / self.ball_r
            quat = self.d.qpos[self.ix.ball_qpos + 3 : self.ix.ball_qpos + 7]
            inv = np.empty(4)
            mujoco.mju_negQuat(inv, quat)
            w_local = np.empty(3)
            mujoco.mju_rotVecQuat(w_local, w_world, inv)
            self.d.qvel[bv + 3 : bv + 6] = w_local
        self.ready_at[i] = step + self.recharge_steps
        self.kicked_by, self.kicked_speed, self.kicked_lob = i, req.speed, req.lob
        self.on_event("kick", i, value=req.speed, detail="lob" if req.lob else "ground")

    def _catch(self, step: int, enabled: np.ndarray) -> None:
        if self._qpos_flat[self._ball_q + 2] > self._catch_top:
            return
        usable = enabled.tobytes()
        cand = self._cand
        if cand is None or usable != self._cand_usable:  # only when a dribbler or a robot's state changed
            self._cand = cand = np.flatnonzero(self.dribble_on & enabled)
            self._cand_usable = usable
        if self.lost_by >= 0:
            if step < self.lost_until and self.in_mouth(self.lost_by):
                cand = cand[cand != self.lost_by]
            else:
                self.lost_by = -1
        if cand.size == 0:
            return
        ix = self.ix
        i, fwd, lat, nearest = self._catch_kernel(
            self._qpos,
            self._qvel,
            self._robot_q0,
            self._robot_v0,
            self._ball_q,
            self._ball_v,
            cand,
            self.hold_dist,
            self.hold_cos,
            self._catch_top,
            self._mouth_x,
            self.catch_speed,
        )
        if i >= 0:
            self._attach(i, fwd, lat, step)
        elif nearest > self.hold_dist:
            # nothing can come within reach before the gap closes at the fastest possible closing speed
            # (ball speed plus a robot's top speed): sleep until then (switching a dribbler on wakes it)
            bv = self._qvel[ix.ball_qvel : ix.ball_qvel + 2]
            closing = math.hypot(bv[0], bv[1]) + _ROBOT_TOP_SPEED
            self._catch_idle_until = step + max(0, int((nearest - self.hold_dist) / (closing * self._dt)))

    def _attach(self, i: int, fx: float, fy: float, step: int) -> None:
        eq = self.ix.dribble_eq[i]
        self.m.eq_data[eq, 0:3] = (fx, fy, self.ball_r)
        self.m.eq_data[eq, 3:6] = 0.0
        self.d.eq_active[eq] = 1
        self.holder = i
        self.hold_since = step
        self.on_event("dribble_start", i)

    def _keep(self, step: int, enabled: np.ndarray) -> None:
        i = self.holder
        if not (self.dribbling[i] and enabled[i]):
            self.release("dribbler_off")
            return
        d = self.d
        status, force = self._keep_kernel(
            self._eq_data,
            self._dribble_eq[i],
            self._qpos,
            self._robot_q0,
            self._ball_q,
            i,
            self._mouth_xs[i],
            self.pull_step,
            step - self.hold_since >= self.settle_steps,
            d.efc_type,
            d.efc_id,
            d.efc_force,
            d.nefc,
            self._eq_rows_type,
            self.grip,
        )
        if status == 1:
            self.release("grip_exceeded", value=force, limit=self.grip, step=step)
        elif status == 2:
            self.release("pulled_away", step=step)

    def release(self, why: str, value: float = 0.0, limit: float = 0.0, step: int | None = None) -> None:
        i = self.holder
        if i < 0:
            return
        self.d.eq_active[self.ix.dribble_eq[i]] = 0
        self.holder = -1
        if why in ("grip_exceeded", "pulled_away") and step is not None:
            self.lost_by = i
            self.lost_until = step + self.recatch_steps
        self.on_event("dribble_end", i, value=value, limit=limit, detail=why)
