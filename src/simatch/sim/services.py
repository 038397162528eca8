"""The Gazebo-like world services: what a judge, a script or a bridge does to the world from outside.

Set a model's or a link's state (place, turn, set moving; the ball pushed out of a robot it was placed in),
apply a force and torque for a while, enable or disable a robot (sent off), freeze it where it stands (a
captured target), turn a team's frame, cut a drone's rotor. Each is checked first: a placement outside the
world or faster than anything in it moves, or a wrench that would make it so, is refused with a
`CommandError` (the physics never sees it).

`WorldServices` is a part of `simatch.sim.simulator.Simulator`: its methods marked `world_input` are the
simulator's, so that the input log (`simatch.sim.inputs`) finds and logs them.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import mujoco
import numpy as np

from .commands import MAX_COMMAND_SPEED, MAX_COMMAND_TURN, MAX_KICK_REQUEST, CommandError, finite
from .flight import yaw_of
from .inputs import world_input
from .world import BALL_NAME

MAX_WRENCH = 1e5  # N, N m
MAX_BALL_SPIN = 2000.0  # rad/s (a ball rolling at 100 m/s turns at some 900)
MAX_HEIGHT = 50.0  # m: the highest a model may be placed


class WorldServices:
    """The simulator's Gazebo-like methods (see the module)."""

    @world_input
    def set_model_state(self, name: str, **state: float) -> None:
        """Place a model and/or set its velocity, world frame. Keys: x y z yaw qw qx qy qz vx vy vz wx wy wz;
        keys not given keep their current value. Ground robots are planar: a ground robot asked to leave the
        floor or to tilt is put back upright on the floor (and an event says so). An aerial robot takes any
        pose (``yaw`` alone: level at that heading) and holds where it was put."""
        allowed = {"x", "y", "z", "yaw", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz"}
        unknown = set(state) - allowed
        if unknown:
            raise CommandError(
                f"set_model_state: unknown key(s) {', '.join(sorted(unknown))}; allowed: {', '.join(sorted(allowed))}"
            )
        for k, v in state.items():
            if not finite(v) or abs(v) > 1e4:
                raise CommandError(f"set_model_state({name!r}): {k}={v!r} is not a finite value of sensible size")
        self._check_placement(name, state)
        if name == BALL_NAME:
            self._set_ball(state)
        else:
            i = self.index_of(name)
            if i < self.ng:
                self._set_robot(i, state)
            else:
                self._set_drone(i, state)
        mujoco.mj_forward(self.m, self.d)
        self._push_ball_out_of_robots()

    def _check_placement(self, name: str, s: dict) -> None:
        """A model is placed inside the world (within the boards, below `MAX_HEIGHT`) and set moving no faster
        than anything in it can: a robot at most at `MAX_COMMAND_SPEED` and `MAX_COMMAND_TURN`, the ball at
        `MAX_KICK_REQUEST` and `MAX_BALL_SPIN` (faster, a body would pass through the boards in one step)."""
        f = self.field
        ball = name == BALL_NAME
        bounds = {"x": f.half_length + f.margin, "y": f.half_width + f.margin, "z": MAX_HEIGHT}
        speed = MAX_KICK_REQUEST if ball else MAX_COMMAND_SPEED
        turn = MAX_BALL_SPIN if ball else MAX_COMMAND_TURN
        bounds.update({"vx": speed, "vy": speed, "vz": speed, "wx": turn, "wy": turn, "wz": turn})
        for k, limit in bounds.items():
            if k in s and abs(s[k]) > limit:
                what = "outside the world" if k in "xyz" else "faster than anything in the world moves"
                raise CommandError(f"set_model_state({name!r}): {k}={s[k]!r} is {what} (|{k}| <= {limit:g})")

    def _set_ball(self, s: dict) -> None:
        if self.ball.holder >= 0 and any(k in s for k in ("x", "y", "z")):
            self.ball.release("ball_placed")
        self._set_free(BALL_NAME, self.engine.ball_q, self.engine.ball_v, s, self.ball_radius)

    def _set_free(self, name: str, b: int, bv: int, s: dict, floor: float) -> None:
        """Set a free body's state (its free joint at qpos ``b``, qvel ``bv``), its centre kept ``floor`` or
        more above the ground; angular velocities are given in the world frame."""
        q, v = self.d.qpos, self.d.qvel
        for k, off in (("x", 0), ("y", 1), ("z", 2)):
            if k in s:
                q[b + off] = s[k]
        q[b + 2] = max(q[b + 2], floor)
        if any(k in s for k in ("qw", "qx", "qy", "qz")):
            quat = np.array(
                [s.get("qw", q[b + 3]), s.get("qx", q[b + 4]), s.get("qy", q[b + 5]), s.get("qz", q[b + 6])]
            )
            norm = math.sqrt(sum(float(c) * float(c) for c in quat))  # not np.linalg.norm: BLAS by CPU
            if norm < 1e-9:
                raise CommandError(f"set_model_state({name!r}): the quaternion has zero length")
            q[b + 3 : b + 7] = quat / norm
        elif "yaw" in s:  # level, heading yaw
            q[b + 3 : b + 7] = (math.cos(s["yaw"] / 2), 0.0, 0.0, math.sin(s["yaw"] / 2))
        for k, off in (("vx", 0), ("vy", 1), ("vz", 2)):
            if k in s:
                v[bv + off] = s[k]
        if any(k in s for k in ("wx", "wy", "wz")):
            w_world = np.empty(3)
            mujoco.mju_rotVecQuat(w_world, v[bv + 3 : bv + 6], q[b + 3 : b + 7])
            for k, off in (("wx", 0), ("wy", 1), ("wz", 2)):
                if k in s:
                    w_world[off] = s[k]
            inv = np.empty(4)
            mujoco.mju_negQuat(inv, q[b + 3 : b + 7])
            w_local = np.empty(3)
            mujoco.mju_rotVecQuat(w_local, w_world, inv)
            v[bv + 3 : bv + 6] = w_local

    def _set_drone(self, i: int, s: dict) -> None:
        """An aerial robot placed anywhere in 3D, at any attitude; its controller holds where it was put."""
        k = i - self.ng
        ix = self.ix.aerial
        self._set_free(self.robot_names[i], int(ix.qpos[k]), int(ix.qvel[k]), s, self.robot_models[i].height / 2)
        self.aerial.hold(k)
        if self.frozen[i]:
            self._freeze(i, True)

    def _set_robot(self, i: int, s: dict) -> None:
        q, v = self.d.qpos, self.d.qvel
        qa, va = self.ix.robot_qpos[i], self.ix.robot_qvel[i]
        lifted = (
            abs(s.get("z", 0.0)) > 1e-9
            or abs(s.get("qx", 0.0)) > 1e-9
            or abs(s.get("qy", 0.0)) > 1e-9
            or abs(s.get("vz", 0.0)) > 1e-9
            or abs(s.get("wx", 0.0)) > 1e-9
            or abs(s.get("wy", 0.0)) > 1e-9
        )
        if "x" in s:
            q[qa[0]] = s["x"]
        if "y" in s:
            q[qa[1]] = s["y"]
        if "yaw" in s:
            q[qa[2]] = s["yaw"]
        elif "qw" in s or "qz" in s:
            q[qa[2]] = yaw_of(s.get("qw", 1.0), s.get("qx", 0.0), s.get("qy", 0.0), s.get("qz", 0.0))
        for k, dof in (("vx", va[0]), ("vy", va[1]), ("wz", va[2])):
            if k in s:
                v[dof] = s[k]
        if self.ball.holder == i:
            self.ball.release("robot_placed")
        # the wheels now turn at the speeds of the new body velocity (no ramp through a teleport)
        yaw = q[qa[2]]
        c, sn = math.cos(yaw), math.sin(yaw)
        body = np.array((c * v[va[0]] + sn * v[va[1]], -sn * v[va[0]] + c * v[va[1]], v[va[2]]))
        self._reset_drive(i, body)
        if self.frozen[i]:
            self._freeze(i, True)
        if lifted:
            self.event("robot_upright", i, detail="robots are planar: put back upright on the floor")

    def _push_ball_out_of_robots(self) -> None:
        """A ball placed inside a robot is moved out in front of the overlap (never left inside)."""
        q = self.d.qpos
        b = self.engine.ball_q
        bx, by = q[b], q[b + 1]
        R = q[self.ix.robot_qpos]
        for i in range(self.ng):
            rm = self.robot_models[i]
            cx_off, cr = rm.ball_collider(self.ball_radius)
            yaw = R[i, 2]
            c, s = math.cos(yaw), math.sin(yaw)
            cx, cy = R[i, 0] + c * cx_off, R[i, 1] + s * cx_off
            dx, dy = bx - cx, by - cy
            dist = math.hypot(dx, dy)
            need = cr + self.ball_radius + 1e-3
            if dist < need and q[b + 2] < rm.params.height + self.ball_radius:
                if dist < 1e-9:
                    dx, dy, dist = c, s, 1.0
                bx, by = cx + dx / dist * need, cy + dy / dist * need
                q[b], q[b + 1] = bx, by
                self.event("ball_moved_out", i, detail="the ball was placed inside a robot; moved out to its surface")
        mujoco.mj_forward(self.m, self.d)

    @world_input
    def set_link_state(self, name: str, **state: float) -> None:
        """Links: ``<robot>/base`` is the robot itself and ``ball`` the ball; wheels and rotors follow their
        base."""
        if name == BALL_NAME:
            return self.set_model_state(name, **state)
        robot, _, link = name.rpartition("/")
        if link == "base":
            return self.set_model_state(robot, **state)
        if link.startswith(("wheel_", "rotor_")) and robot in self.robot_index:
            raise CommandError(
                f"set_link_state({name!r}): a {link.partition('_')[0]} follows its robot's base; "
                f"set the state of {robot!r} (or {robot}/base) instead"
            )
        raise CommandError(f"no link named {name!r} (links: <robot>/base, <robot>/wheel_<k>, <robot>/rotor_<k>, ball)")

    @world_input
    def apply_wrench(
        self, name: str, force: Iterable[float] = (0, 0, 0), torque: Iterable[float] = (0, 0, 0), duration: float = 0.0
    ) -> None:
        """Apply a world-frame force [N] and torque [N m] at a model's centre for ``duration`` seconds
        (at least one physics step). On a ground robot only the planar part acts (x, y force, z torque); on
        an aerial robot all of it."""
        f, t = list(force), list(torque)
        if len(f) != 3 or len(t) != 3:
            raise CommandError("apply_wrench: force and torque must have 3 components each")
        if not finite(*f, *t, duration) or duration < 0 or any(abs(x) > MAX_WRENCH for x in f + t):
            raise CommandError(
                f"apply_wrench({name!r}): force {f}, torque {t}, duration {duration!r} must be "
                f"finite, |value| <= {MAX_WRENCH:g}, duration >= 0"
            )
        ball = name == BALL_NAME
        i = -1 if ball else self.index_of(name)
        body = self.ix.ball_body if ball else int(self.ix.robot_body[i])
        free = ball or i >= self.ng  # the ball and aerial robots take the whole wrench, ground robots its plane
        steps = max(1, round(duration / self.dt))
        # what it can do: a robot moved (or turned) faster than any command, the ball faster than any kick,
        # would pass through the boards in one step
        seconds = steps * self.dt
        mass = float(self.m.body_subtreemass[body])
        inertia = float(min(self.m.body_inertia[body])) or 1e-9
        dv = math.hypot(*(f if free else f[:2])) * seconds / mass
        dw = (math.hypot(*t) if free else abs(t[2])) * seconds / inertia
        if dv > (MAX_KICK_REQUEST if ball else MAX_COMMAND_SPEED) or dw > (MAX_BALL_SPIN if ball else MAX_COMMAND_TURN):
            raise CommandError(
                f"apply_wrench({name!r}): force {f}, torque {t} for {seconds:g} s would change its speed by "
                f"{dv:.3g} m/s and its turn by {dw:.3g} rad/s: more than anything in the world moves"
            )
        self._wrenches.append((body, np.array(f + t, dtype=float), self.step_index + steps))

    @world_input
    def set_enabled(self, name: str, enabled: bool) -> None:
        """A disabled robot ignores its commands and stands still (e.g. sent off)."""
        i = self.index_of(name)
        self.enabled[i] = enabled
        self.usable[i] = self.enabled[i] and not self.frozen[i]
        self._relive(i)
        if not enabled:
            self._stop_robot(i)
            if self.ball.holder == i:
                self.ball.release("robot_disabled")

    @world_input
    def set_team_sign(self, team: str, sign: int) -> None:
        """``team``'s frame from now on: the world frame (``sign`` +1, the team attacks +x) or the world turned
        by pi (-1). Its robots' perception is given in it from the next observation on (a referee turns the
        frames when the teams change ends; commands are in the body frame and need nothing)."""
        if sign not in (1, -1):
            raise CommandError(f"set_team_sign({team!r}): sign must be +1 or -1, not {sign!r}")
        members = [i for i, t in enumerate(self.team_of) if t == team]
        if not members:
            raise CommandError(
                f"set_team_sign: no team named {team!r} (teams: {', '.join(dict.fromkeys(self.team_of))})"
            )
        self.signs[members] = float(sign)
        self.perception.set_signs(self.signs)

    @world_input
    def set_frozen(self, name: str, frozen: bool) -> None:
        """A frozen robot is welded to the floor where it stands (an aerial robot to the air where it flies):
        nothing moves it (e.g. a captured target)."""
        i = self.index_of(name)
        self.frozen[i] = frozen
        self.usable[i] = self.enabled[i] and not self.frozen[i]
        self._relive(i)
        self._freeze(i, frozen)
        if frozen:
            self._stop_robot(i)
            if i >= self.ng:
                va = self.ix.aerial.qvel[i - self.ng]
                self.d.qvel[va : va + 6] = 0.0
                return
            self._reset_drive(i, None)
            self.d.qvel[self.ix.robot_qvel[i]] = 0.0

    def _freeze(self, i: int, on: bool) -> None:
        if i >= self.ng:
            return self._freeze_drone(i - self.ng, on)
        eq = self.ix.freeze_eq[i]
        if on:
            x, y, yaw = self.d.qpos[self.ix.robot_qpos[i]]
            # weld body1 = robot to body2 = world: anchor at the robot origin, world pose of the robot
            # expressed as body2's pose in body1's frame (relpos/relquat of the inverse transform)
            c, s = math.cos(yaw), math.sin(yaw)
            self.m.eq_data[eq, 0:3] = 0.0
            self.m.eq_data[eq, 3:6] = (-(c * x + s * y), -(-s * x + c * y), 0.0)
            self.m.eq_data[eq, 6:10] = (math.cos(-yaw / 2), 0.0, 0.0, math.sin(-yaw / 2))
            self.m.eq_data[eq, 10] = 1.0
        self.d.eq_active[eq] = 1 if on else 0

    def _freeze_drone(self, k: int, on: bool) -> None:
        """A frozen drone is welded where it flies, its motors off (a weld holds it against its weight, not
        against its own controller); thawed, it holds that point again."""
        ix = self.ix.aerial
        eq = ix.freeze_eq[k]
        self.aerial.arm(k, not on)
        if on:
            a = ix.qpos[k]
            # the weld point is the drone's centre: in the world where it is now (anchor, body2 = world) and
            # at the body's origin (relpos); the relative turn is the inverse of its attitude. (An anchor at
            # the world's origin, metres away, couples turning and moving: a light body then drifts off.)
            inv = np.empty(4)
            mujoco.mju_negQuat(inv, self.d.qpos[a + 3 : a + 7])
            self.m.eq_data[eq, 0:3] = self.d.qpos[a : a + 3]
            self.m.eq_data[eq, 3:6] = 0.0
            self.m.eq_data[eq, 6:10] = inv
            self.m.eq_data[eq, 10] = 1.0
        self.d.eq_active[eq] = 1 if on else 0

    # --- aerial robots ------------------------------------------------------------------------------------------
    @world_input
    def set_rotor(self, name: str, rotor: int, working: bool = True) -> None:
        """Cut (``working=False``) or restore one rotor of an aerial robot (rotors 1-4, see
        `simatch.robots.quadrotor`): a cut rotor gives no thrust and no torque whatever its controller asks,
        which the controller does not know."""
        i = self.index_of(name)
        if i < self.ng:
            raise CommandError(f"set_rotor: {name} is a ground robot; only aerial robots have rotors")
        if not (isinstance(rotor, int) and 1 <= rotor <= 4):
            raise CommandError(f"set_rotor({name!r}): rotor {rotor!r} is not one of 1, 2, 3, 4")
        a = self.ix.aerial.rotor[i - self.ng, rotor - 1]
        self.m.actuator_gainprm[a, 0] = 1.0 if working else 0.0
        self.event("rotor_working" if working else "rotor_cut", i, value=float(rotor), detail=f"rotor {rotor}")

    def _apply_wrenches(self) -> None:
        xf = self.d.xfrc_applied
        xf[:] = 0.0
        keep = []
        for body, wrench, until in self._wrenches:
            if self.step_index < until:
                xf[body] += wrench
                keep.append((body, wrench, until))
        self._wrenches = keep
