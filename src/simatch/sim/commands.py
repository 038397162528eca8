"""Command intake and the watchdog: how the robots' commands enter the simulator.

Bad input never reaches the physics: a command with a NaN, an infinity or an absurd value is refused and
reported as a ``bad_command`` event (at most one a second per robot, with the count since the last), and the
robot keeps its last good command. A robot whose commands stop coming (its node died or hangs) is stopped by
the watchdog within the scene's ``control.command_timeout``, its dribbler off, and resumes at its next command.

`CommandIntake` is a part of `simatch.sim.simulator.Simulator` (its methods are the simulator's, so that the
input log (`simatch.sim.inputs`) finds and logs them); it keeps the per-robot state below.
"""

from __future__ import annotations

import math
import struct

import numpy as np

from .. import msgs
from ..robots.drive import TWIST
from .inputs import action_input, velocity_input, world_input

#: Commands beyond these are refused as absurd (anything a robot could follow is far below them).
MAX_COMMAND_SPEED = 50.0  # m/s
MAX_COMMAND_TURN = 100.0  # rad/s
# the lower limits as constants, compared without arithmetic
_LEAST_SPEED, _LEAST_TURN = -MAX_COMMAND_SPEED, -MAX_COMMAND_TURN
MAX_KICK_REQUEST = 100.0  # m/s (requests above the kicker's limit but below this are clamped)
MAX_KICK_WINDOW = 60.0  # s: how long a kick request may wait for the ball

#: a velocity command's three numbers as float32 (VelCmd's precision): packed and unpacked, they are rounded
#: as `msgs.f32s` rounds them
_F32_TWIST = struct.Struct("<3f")
_pack_f32, _unpack_f32 = _F32_TWIST.pack, _F32_TWIST.unpack
_write_twist = TWIST.pack_into
_f32s = msgs.f32s


class CommandError(ValueError):
    """A command or request the simulator refuses."""


def finite(*values: float) -> bool:
    """Every value a real number (not a bool), finite."""
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in values)


def describe_bad_velocity(vx, vy, w, vz=0.0) -> str:
    up = f" vz={vz!r}" if vz != 0.0 else ""
    if not finite(vx, vy, w, vz):
        return f"velocity command with a non-finite or non-numeric value: vx={vx!r} vy={vy!r} w={w!r}{up}"
    up = f" vz={vz:g}" if vz != 0.0 else ""
    return (
        f"absurd velocity command vx={vx:g} vy={vy:g} w={w:g}{up} (limits {MAX_COMMAND_SPEED:g} m/s, "
        f"{MAX_COMMAND_TURN:g} rad/s)"
    )


class CommandIntake:
    """The simulator's command methods and the per-robot state they keep (see the module)."""

    def _init_commands(self) -> None:
        n = self.n
        self.enabled = np.ones(n, dtype=bool)
        self.frozen = np.zeros(n, dtype=bool)
        self.usable = np.ones(n, dtype=bool)  # enabled and not frozen
        self.last_command_step = np.zeros(n, dtype=np.int64)
        #: the same memory as a memoryview: a command writes its step with a plain item assignment
        self._last_command = memoryview(self.last_command_step)
        self.watchdog_tripped = np.zeros(n, dtype=bool)
        self.commanded = np.zeros(n, dtype=bool)  # has ever received a command
        #: per robot: commanded, not stopped by the watchdog, and usable (a command needs no other check then)
        self._live = [False] * n
        self.refused = np.zeros(n, dtype=np.int64)
        self._refused_reported_step = np.full(n, -(10**9), dtype=np.int64)
        self._refused_since_report = np.zeros(n, dtype=np.int64)
        self._command_limits = np.array([MAX_COMMAND_SPEED, MAX_COMMAND_SPEED, MAX_COMMAND_TURN])
        self._command_rows = self.drive.command_rows

    def index_of(self, name: str) -> int:
        try:
            return self.robot_index[name]
        except KeyError:
            raise CommandError(f"no robot named {name!r}; robots are {', '.join(self.robot_names)}") from None

    def _refuse(self, i: int, why: str) -> bool:
        self.refused[i] += 1
        self._refused_since_report[i] += 1
        # report the first refusal, then at most one event a second with the count since the last one
        if self.step_index - self._refused_reported_step[i] >= round(1.0 / self.dt):
            self.event("bad_command", i, value=float(self._refused_since_report[i]), detail=why)
            self._refused_reported_step[i] = self.step_index
            self._refused_since_report[i] = 0
        return False

    @velocity_input
    def command_velocity(self, i: int, vx: float, vy: float, w: float, vz: float = 0.0) -> bool:
        """Robot i's body-frame velocity command (``vz``, the upward speed, moves aerial robots only). False
        (and an event) if refused."""
        if type(i) is not int or not 0 <= i < self.n:
            self._check_index(i)
        try:
            ok = (
                _LEAST_SPEED <= vx <= MAX_COMMAND_SPEED
                and _LEAST_SPEED <= vy <= MAX_COMMAND_SPEED
                and _LEAST_TURN <= w <= MAX_COMMAND_TURN
                and _LEAST_SPEED <= vz <= MAX_COMMAND_SPEED
            )  # False for NaN, inf and absurd values
        except TypeError:
            ok = False
        if not ok:
            return self._refuse(i, describe_bad_velocity(vx, vy, w, vz))
        self._last_command[i] = self.step_index
        if not self._live[i]:
            if not self.commanded[i] or self.watchdog_tripped[i]:
                self._fresh(i)
            if not self.usable[i]:
                return True
        if i < self.ng:
            try:  # at VelCmd's precision, however the command came
                vx, vy, w = _unpack_f32(_pack_f32(vx, vy, w))
            except (TypeError, struct.error):  # numbers of other kinds: rounded one by one
                vx, vy, w = _f32s(vx, vy, w)
            # `OmniDrive.command`, written here: this runs for every robot at every control tick
            _write_twist(self._command_rows[i], 0, vx, vy, w)
            self._drive_dirty[i] = True
            self.drive.any_dirty = True
        else:
            self.aerial.command(i - self.ng, *_f32s(vx, vy, w, vz))
        return True

    @world_input
    def command_all(self, V: np.ndarray, dribble: np.ndarray | None = None) -> None:
        """Every robot's body-frame velocity command at once, V of shape (N, 3) or (N, 4) with the upward
        speed (for scripted drivers), and optionally every dribbler; rows with a bad value are refused one by
        one, like `command_velocity`."""
        V = np.asarray(V, dtype=float)
        if self.aerial is not None:  # the aerial robots' rows one by one, then the ground robots' as a block
            for i in range(self.ng, self.n):
                self.command_velocity(i, *V[i, :3], V[i, 3] if V.shape[1] > 3 else 0.0)
            self._command_ground(V[: self.ng, :3], None if dribble is None else dribble[: self.ng])
        else:
            self._command_ground(V, dribble)

    def _command_ground(self, V: np.ndarray, dribble: np.ndarray | None) -> None:
        ng = self.ng
        usable, commanded, tripped = self.usable[:ng], self.commanded[:ng], self.watchdog_tripped[:ng]
        ok = np.isfinite(V).all(axis=1)
        ok &= (np.abs(V) <= self._command_limits).all(axis=1)
        drive = self.drive
        if ok.all() and usable.all():
            drive.cmd[:] = V
            drive.dirty[:] = True
            self.last_command_step[:ng] = self.step_index
        else:
            for i in np.flatnonzero(~ok):
                self._refuse(int(i), describe_bad_velocity(*V[i]))
            take = ok & usable
            drive.cmd[take] = V[take]
            drive.dirty |= take
            self.last_command_step[:ng][ok] = self.step_index
        drive.any_dirty = True
        if not commanded.all() or tripped.any():
            for i in np.flatnonzero(ok & (~commanded | tripped)):
                self._fresh(int(i))
        if dribble is not None:
            want = np.asarray(dribble, dtype=bool) & usable
            changed = want != self.ball.dribble_on[:ng]
            if changed.any():
                for i in np.flatnonzero(changed):
                    self.ball.set_dribbler(int(i), bool(want[i]))

    @action_input
    def command_action(
        self, i: int, dribble: bool, kick_speed: float = 0.0, lob: bool = False, window: float | None = None
    ) -> bool:
        """Robot i's dribbler state and kick request (fires at the first step the ball is in the mouth,
        within ``window`` seconds, by default one control period). An aerial robot has neither: its
        ball-handling requests are taken (it is alive) and do nothing."""
        if type(i) is not int or not 0 <= i < self.n:
            self._check_index(i)
        try:
            ok = 0.0 <= kick_speed <= MAX_KICK_REQUEST
        except TypeError:
            ok = False
        if not ok:
            return self._refuse(i, f"kick speed {kick_speed!r} is not a number in [0, {MAX_KICK_REQUEST:g}] m/s")
        if window is not None:
            try:
                ok = 0.0 <= window <= MAX_KICK_WINDOW
            except TypeError:
                ok = False
            if not ok:
                return self._refuse(i, f"kick window {window!r} is not a number of seconds in [0, {MAX_KICK_WINDOW:g}]")
        self._last_command[i] = self.step_index
        if self._live[i]:
            usable = True
        else:
            if not self.commanded[i] or self.watchdog_tripped[i]:
                self._fresh(i)
            usable = bool(self.usable[i])
        if i >= self.ng:
            return True
        on = usable if dribble else False
        if on is not self.ball.dribbling[i]:
            self.ball.set_dribbler(i, on)
        if kick_speed > 0.0 and usable:
            window = self.scene.control.period if window is None else window
            self.ball.request_kick(
                i, msgs.f32(kick_speed), bool(lob), self.step_index + max(1, round(window / self.dt))
            )
        return True

    def _fresh(self, i: int) -> None:
        if self.watchdog_tripped[i]:
            self.watchdog_tripped[i] = False
            self.event("watchdog_resume", i, detail="commands arrive again")
        self.last_command_step[i] = self.step_index
        self.commanded[i] = True
        self._relive(i)

    def _relive(self, i: int) -> None:
        self._live[i] = bool(self.commanded[i] and not self.watchdog_tripped[i] and self.usable[i])

    @world_input
    def stop_robot(self, i: int) -> None:
        self._check_index(i)
        self._stop_robot(i)

    def _check_index(self, i: int) -> None:
        """Robot indices are 0..n-1 (ground robots, then aerial ones): any other is the caller's mistake, an
        IndexError here rather than another robot commanded (a negative index) or a drone's part missing."""
        if not 0 <= i < self.n:
            raise IndexError(f"robot index {i!r} out of range: the world has robots 0..{self.n - 1}")

    def _stop_robot(self, i: int) -> None:
        if i >= self.ng:  # a drone told to stop hovers where it is
            self.aerial.stop(i - self.ng)
            return
        self.drive.stop(i)
        self.ball.set_dribbler(i, False)
        self.ball.kicks.pop(i, None)

    def watchdog(self, timeout: float, next_check: int = 1) -> None:
        """Stop every robot whose last command would be older than ``timeout`` before the next check,
        ``next_check`` steps from now (its node died or hangs): it is stopped within ``timeout``."""
        limit = round(timeout / self.dt)
        # the oldest command first, by the builtin `min` over the memoryview: the usual answer is that every
        # robot was commanded recently, and there is nothing to check one by one
        if not self.n or min(self._last_command) > self.step_index + next_check - limit:
            return
        stale = (
            (self.step_index - self.last_command_step + next_check > limit) & ~self.watchdog_tripped & self.commanded
        )
        for i in np.flatnonzero(stale):
            self.watchdog_tripped[i] = True
            self._live[i] = False
            self._stop_robot(int(i))
            self.event(
                "watchdog_stop",
                int(i),
                value=(self.step_index - self.last_command_step[i]) * self.dt,
                limit=timeout,
                detail="no fresh command: robot stopped, dribbler off",
            )
