"""The simulation subsystem's core: the MuJoCo world with its robots and ball, stepped at the physics rate.

It realises the robots' motions (omnidirectional drive with wheel limits, dribbler, kicker), gives exact
model and link states, and offers the Gazebo-like interface: set model/link state, apply a force/torque
for a duration. It knows nothing of soccer rules; the bus adapter (`simatch.sim.node`) connects it to
the other subsystems.

Everything that enters the world from outside goes through the methods marked `world_input` (commands,
the Gazebo-like calls, sending off, freezing): while `inputs` is on they are logged there, so that a run
can be re-simulated from its inputs alone (`simatch.sim.inputs`).

Bad input never reaches the physics: a command with a NaN, an infinity or an absurd value is refused and
reported as an event (rate-limited per robot, with a count), and the robot keeps its last good command.
"""

from __future__ import annotations

import hashlib
import math
import struct
from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import mujoco
import numpy as np

from .. import msgs
from ..compiled import entry
from ..config.schema import Scene
from ..robots.drive import OmniDrive, plan_drive
from .ballhandling import BallHandling
from .flight import AerialFleet, aerial_poses, frame_contacts, planar, rotor_links
from .inputs import InputLog, action_input, install, velocity_input, world_input
from .kernels import ball_apart, mix64, model_fingerprint, model_poses, model_poses32, robot_flags, sense_ground
from .perception import Perception, Snapshot
from .sight import Sight
from .timers import keep_timers_off
from .world import BALL_NAME, build_world

_f32s = msgs.f32s
_zeros, _f32 = np.zeros, np.float32
_f32x3 = struct.Struct("<3f")  # three float32 numbers: a velocity command rounded as `msgs.f32s` rounds it
_pack3, _unpack3 = _f32x3.pack, _f32x3.unpack
_put3 = struct.Struct("=3d").pack_into  # three float64 numbers (a drive command's row) into a buffer

#: Commands beyond these are refused as absurd (anything a robot could follow is far below them).
MAX_COMMAND_SPEED = 50.0  # m/s
MAX_COMMAND_TURN = 100.0  # rad/s
# the lower limits as constants (a negation in the check would make a float at every command)
_LEAST_SPEED, _LEAST_TURN = -MAX_COMMAND_SPEED, -MAX_COMMAND_TURN
MAX_KICK_REQUEST = 100.0  # m/s (requests above the kicker's limit but below this are clamped)
MAX_KICK_WINDOW = 60.0  # s: how long a kick request may wait for the ball
MAX_WRENCH = 1e5  # N, N m
MAX_BALL_SPIN = 2000.0  # rad/s (a ball rolling at 100 m/s turns at some 900)
MAX_HEIGHT = 50.0  # m: the highest a model may be placed
BOUNCE_MIN_SPEED = 0.3  # m/s: slower impacts are absorbed (the ball settles instead of chattering)
COLLISION_APART = 0.25  # s: a drone that touches a thing again after this long apart has hit it again


def _label(geom_name: str) -> str:
    """What a geom is, for an event: a robot's name for its parts, else the geom's own name."""
    for part in ("/hull", "/mouth"):
        if geom_name.endswith(part):
            return geom_name[: -len(part)]
    return geom_name or "something"


#: how the StateFingerprint of the exact states is taken (a recording says which in its metadata, `FINGERPRINTS`):
#: ``mix64`` (`simatch.sim.kernels.mix64` of the states' 64-bit words) since recording format 2, ``sha256`` (the
#: first 8 bytes of their SHA-256, little endian) before
FINGERPRINT = "mix64"


def fingerprint(pose: np.ndarray, twist: np.ndarray, kind: str = FINGERPRINT) -> int:
    """The StateFingerprint of the exact poses and twists (float64 arrays, as the simulator makes them): their
    numbers, poses then twists, in C order, taken as ``kind`` (`FINGERPRINT`, or ``sha256`` for a recording of
    format 1). Equal fingerprints mean the same states bit for bit (a chance difference is 1 in 1.8e19)."""
    pose, twist = np.ascontiguousarray(pose, np.float64), np.ascontiguousarray(twist, np.float64)
    if kind == "sha256":
        h = hashlib.sha256(pose)
        h.update(twist)
        return int.from_bytes(h.digest()[:8], "little")
    if kind != FINGERPRINT:
        raise ValueError(f"unknown fingerprint {kind!r} (known: {', '.join(FINGERPRINTS)})")
    return int(mix64(np.concatenate((pose.ravel(), twist.ravel())).view(np.uint64)))


FINGERPRINTS = (FINGERPRINT, "sha256")


class CommandError(ValueError):
    """A command or request the simulator refuses."""


@dataclass
class ModelStateView:
    """One model's state in the world frame."""

    name: str
    x: float
    y: float
    z: float
    yaw: float
    qw: float
    qx: float
    qy: float
    qz: float
    vx: float
    vy: float
    vz: float
    wx: float
    wy: float
    wz: float


def _yaw_of(qw: float, qx: float, qy: float, qz: float) -> float:
    return math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


def _finite(*values: float) -> bool:
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in values)


def _describe_bad_velocity(vx, vy, w, vz=0.0) -> str:
    up = f" vz={vz!r}" if vz != 0.0 else ""
    if not _finite(vx, vy, w, vz):
        return f"velocity command with a non-finite or non-numeric value: vx={vx!r} vy={vy!r} w={w!r}{up}"
    up = f" vz={vz:g}" if vz != 0.0 else ""
    return (
        f"absurd velocity command vx={vx:g} vy={vy:g} w={w:g}{up} (limits {MAX_COMMAND_SPEED:g} m/s, "
        f"{MAX_COMMAND_TURN:g} rad/s)"
    )


class Simulator:
    def __init__(self, scene: Scene, seed: int = 0, on_event: Callable | None = None):
        self.scene = scene
        self.seed = seed
        self.m, self.d, self.ix, self.field = build_world(scene)
        keep_timers_off()  # MuJoCo's profiling clock, read some twenty times a step and never by us
        self._qpos, self._qvel = self.d.qpos, self.d.qvel  # views of the engine's arrays (fixed memory)
        # the same memory as memoryviews, whose items are plain floats (a physics step reads a few)
        self._qpos_flat, self._qvel_flat = memoryview(self._qpos), memoryview(self._qvel)
        self.dt = float(self.m.opt.timestep)
        self.step_index = 0
        robots = self.ix.robots
        self.n = len(robots)
        #: robots 0 .. ng-1 are ground robots (planar bases, wheels), ng .. n-1 aerial ones (`aerial`)
        self.ng = self.n - (len(self.ix.aerial.robots) if self.ix.aerial is not None else 0)
        self.robot_names = [r.name for r in robots]
        self.robot_index = {r.name: i for i, r in enumerate(robots)}
        self.robot_models = [r.model for r in robots]
        self.team_of = [r.team for r in robots]
        self.model_names = self.robot_names + [BALL_NAME]
        self.signs = np.array([scene.team_sign(r.team) for r in robots], dtype=float)
        self.radii = np.array([rm.radius for rm in self.robot_models])
        self.ball_radius = scene.ball.radius
        ground = self.robot_models[: self.ng]
        p = [rm.params for rm in ground]
        self.control_steps = max(1, round(scene.control.period / self.dt))
        self.drive = OmniDrive(
            [rm.rim_matrix() for rm in ground],
            [q.max_wheel_speed for q in p],
            [q.max_acceleration for q in p],
            [q.max_deceleration for q in p],
            self.dt,
        )
        # the drive's command array as bytes and its dirty flags, as memoryviews (fixed memory), for
        # `command_velocity`
        self._drive_cmd = memoryview(self.drive.cmd.view(np.uint8).reshape(-1))
        self._drive_dirty = memoryview(self.drive.dirty)
        self._drive_ramping = memoryview(self.drive.ramping)
        self._plan = None  # `plan_drive` for the simulator's arguments (made at the first plan)
        self._on_event = on_event
        # the log of the world's inputs: on from the start, so that what a judge or a script does before the
        # first step is in it; the bus adapter turns it off while nobody listens
        self._inputs: InputLog | None = None
        self.inputs = InputLog()
        self.events: list = []  # GameEvent messages not yet taken by the bus adapter
        self.mechanics: Counter = Counter()  # kicks, catches, ball losses by reason
        self.ball = BallHandling(self.m, self.d, self.ix, self.robot_models, scene, self._mechanism_event)
        self.enabled = np.ones(self.n, dtype=bool)
        self.frozen = np.zeros(self.n, dtype=bool)
        self.usable = np.ones(self.n, dtype=bool)  # enabled and not frozen
        self.last_command_step = np.zeros(self.n, dtype=np.int64)
        # the same memory as a memoryview: a command (400 a second) writes its step through it, a fraction of
        # what NumPy's item assignment costs
        self._last_command = memoryview(self.last_command_step)
        self.watchdog_tripped = np.zeros(self.n, dtype=bool)
        self.commanded = np.zeros(self.n, dtype=bool)  # has ever received a command
        # per robot: commanded, not stopped by the watchdog, and usable (a command needs no other check then);
        # plain bools, read for every command
        self._live = [False] * self.n
        self.refused = np.zeros(self.n, dtype=np.int64)
        self._refused_reported_step = np.full(self.n, -(10**9), dtype=np.int64)
        self._refused_since_report = np.zeros(self.n, dtype=np.int64)
        self.stuck = np.zeros(self.n, dtype=bool)
        self._slow_since = np.full(self.n, -1, dtype=np.int64)
        self._stuck_steps = round(0.5 / self.dt)
        # robots within 1 m of the lines count as on the field ("valid" in their perception)
        self._valid_box = np.array([self.field.half_length + 1.0, self.field.half_width + 1.0])
        self._wrenches: list[tuple[int, np.ndarray, int]] = []  # (body, 6-vector, until step)
        self._wheel_r = np.array([rm.params.wheel_radius for rm in ground])[:, None]
        self.touching: list[int] = []  # robots touching the ball after the last step
        self._ctrl_ids = self.ix.robot_ctrl
        self._act_ids = self.ix.robot_act
        self._kv = np.ascontiguousarray(self.m.actuator_gainprm[self._ctrl_ids, 0])  # (N, 3)
        self._inv_dt = 1.0 / self.dt
        self._command_limits = np.array([MAX_COMMAND_SPEED, MAX_COMMAND_SPEED, MAX_COMMAND_TURN])
        # the servos are the model's first 3N actuators, in robot order: views instead of fancy indexing
        ng = self.ng
        assert np.array_equal(self._ctrl_ids.ravel(), np.arange(3 * ng))
        assert np.array_equal(self._act_ids.ravel(), np.arange(3 * ng))
        self._act3 = self.d.act[: 3 * ng].reshape(ng, 3)
        self._ctrl3 = self.d.ctrl[: 3 * ng].reshape(ng, 3)
        self._actrange3 = self.m.actuator_actrange[: 3 * ng].reshape(ng, 3, 2)
        self._bias3 = self.m.actuator_biasprm[: 3 * ng, 0].reshape(ng, 3)
        assert np.shares_memory(self._bias3, self.m.actuator_biasprm) or ng == 0
        self.track_wheels = False
        self.wheel_travel = np.zeros((ng, self.drive.max_wheels))  # rim distance rolled [m]
        self._rq = self.ix.robot_qpos
        self._rv = self.ix.robot_qvel
        # robots' joints are consecutive (x, y, yaw per robot): views instead of fancy indexing
        q0, v0 = (int(self._rq[0, 0]), int(self._rv[0, 0])) if ng else (0, 0)
        assert np.array_equal(self._rq.ravel(), np.arange(q0, q0 + 3 * ng))
        assert np.array_equal(self._rv.ravel(), np.arange(v0, v0 + 3 * ng))
        self._qpos3 = self.d.qpos[q0 : q0 + 3 * ng].reshape(ng, 3)
        self._q0, self._v0 = q0, v0
        self._qvel3 = self.d.qvel[v0 : v0 + 3 * ng].reshape(ng, 3)
        #: the aerial robots' controllers (None in a world without them)
        self.aerial = (
            AerialFleet(self.d, self.ix.aerial, self.robot_models[ng:], self.dt, scene.physics.gravity)
            if self.ix.aerial is not None
            else None
        )
        if self.aerial is not None:
            # a drone's frame meeting anything is an event (once per meeting): what each geom is, by name
            self._frame_of = np.full(self.m.ngeom, -1, dtype=np.int64)
            self._frame_of[self.ix.aerial.geom] = np.arange(len(self.ix.aerial.geom))
            self._geom_label = [_label(self.m.geom(g).name) for g in range(self.m.ngeom)]
            self._frame_touching: dict = {}  # (drone, geom) -> last step they touched
            self._frame_v = (self.ix.aerial.qvel[:, None] + np.arange(3)).ravel()
            self._frame_vel = self.d.qvel[self._frame_v]
            d = self.d  # what drones touch at the start (a landed drone stands on the floor) is no collision
            for pair in frame_contacts(d.contact.geom, d.ncon, self._frame_of) if d.ncon else ():
                self._frame_touching[pair] = 0
        self._bq = self.ix.ball_qpos
        self._bv = self.ix.ball_qvel
        self._bz = self._bq + 2
        self._bvz = self._bv + 2
        self.restitution = scene.ball.restitution
        self._geom_robot = np.full(self.m.ngeom, -1, dtype=np.int64)
        for g, i in self.ix.robot_of_geom.items():
            self._geom_robot[g] = i
        self._geom_robot_list = self._geom_robot.tolist()
        self._init_touch_bounds()
        # the per-step kernels, called without numba's dispatcher (`simatch.compiled.entry`: their arguments are the
        # engine's arrays taken once, plain numbers and float32 arrays made for the call)
        self._pose32_size, self._twist32_size = 7 * (self.n + 1), 6 * (self.n + 1)  # the robots and the ball
        q, v = self._qpos, self._qvel
        self._poses32 = entry(
            model_poses32, q, v, self._q0, self._v0, self.n, self._bq, self._bv, np.zeros(0, _f32), np.zeros(0, _f32)
        )
        # the exact states whose fingerprint a recording takes every control tick: poses then twists, float64,
        # in one block that `model_fingerprint` fills in place (the numbers `model_poses` returns, the positions it
        # leaves zero never written) and hashes as the two arrays one after the other, by its 64-bit words
        m = self.n + 1  # the robots and the ball
        self._state64 = np.zeros(13 * m)
        self._words64 = self._state64.view(np.uint64)
        self._state_fingerprint = entry(
            model_fingerprint, q, v, self._q0, self._v0, self.n, self._bq, self._bv, self._state64, self._words64
        )
        #: how `state_fingerprint` takes it (`FINGERPRINTS`: a re-simulation of an older recording sets its kind)
        self.fingerprint_kind = FINGERPRINT
        self._ball_apart = entry(
            ball_apart, self._geom_xpos, self._touch_geoms, self._touch_bound2, int(self.ix.ball_geom)
        )
        self.perception = Perception(
            robots,
            self.signs,
            self.radii,
            np.concatenate((self.drive.n_wheels, np.zeros(self.n - ng, dtype=int))),
            scene.perception,
            self.dt,
            np.random.default_rng([seed & 0xFFFFFFFF, 0x5E45E]),
            sight=Sight.of(self.robot_models, self.field, scene.perception),
        )
        self._plan_drive(np.ones(ng, dtype=bool), self.control_steps)
        # what the robots' flags are computed from (`kernels.robot_flags`), around the step index
        F = self.field
        self._flags_in = (self._act3, self.drive.M, self.drive.n_wheels, self.enabled, self._slow_since)
        self._flags_of = (self._stuck_steps, F.half_length, F.half_width)
        #: `observations` by one compiled call (exact perception of ground robots alone)
        p = self.perception
        self._sense_fast = self.aerial is None and p.exact and p.sight is None and p.delay_steps == 0 and self.n > 0
        self._sense = None  # `sense_ground` for these arguments (made at the first observation)

    # --- inputs -------------------------------------------------------------------------------------------
    @property
    def inputs(self) -> InputLog | None:
        """The log of the world's inputs (`simatch.sim.inputs`), or None while they are not logged."""
        return self._inputs

    @inputs.setter
    def inputs(self, log: InputLog | None) -> None:
        if log is not self._inputs:
            self._inputs = log
            install(self, log)  # the marked methods log while on, and are the plain ones while off

    # --- time --------------------------------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self.step_index * self.dt

    # --- events ---------------------------------------------------------------------------------------------
    def event(
        self,
        kind: str,
        robot: int = -1,
        value: float = 0.0,
        limit: float = 0.0,
        detail: str = "",
        x: float | None = None,
        y: float | None = None,
    ) -> None:
        team, rid = ("", 0)
        if robot >= 0:
            team, rid = self.team_of[robot], self.ix.robots[robot].rid
            if x is None:
                x, y = (float(v) for v in self.robot_xy(robot))
        ev = msgs.GameEvent(
            stamp=self.time,
            type=kind,
            team=team,
            robot=rid,
            x=float(x or 0.0),
            y=float(y or 0.0),
            value=float(value),
            limit=float(limit),
            detail=detail,
        )
        self.events.append(ev)
        if self._on_event is not None:
            self._on_event(ev)

    def _mechanism_event(self, kind: str, robot: int, value: float = 0.0, limit: float = 0.0, detail: str = "") -> None:
        """Kicks, catches and losses of the ball are counted, not logged: the ball contacts carry them."""
        self.mechanics[kind if not detail or kind == "kick" else f"{kind}:{detail}"] += 1

    def take_events(self) -> list:
        out, self.events = self.events, []
        return out

    # --- commands ------------------------------------------------------------------------------------------
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
        if type(i) is not int or not 0 <= i < self.n:  # (`_check_index`, inline: 400 calls a second)
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
            return self._refuse(i, _describe_bad_velocity(vx, vy, w, vz))
        self._last_command[i] = self.step_index
        if not self._live[i]:
            if not self.commanded[i] or self.watchdog_tripped[i]:
                self._fresh(i)
            if not self.usable[i]:
                return True
        if i < self.ng:
            try:  # at VelCmd's precision, however the command came (`msgs.f32s`, inline: the numbers are in range)
                vx, vy, w = _unpack3(_pack3(vx, vy, w))
            except (TypeError, struct.error):  # numbers of other kinds: rounded one by one
                vx, vy, w = _f32s(vx, vy, w)
            # `OmniDrive.command`, inline (400 calls a second: a Python frame is a third of the call's cost), the
            # three numbers written into robot i's row in one call
            _put3(self._drive_cmd, 24 * i, vx, vy, w)
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
                self._refuse(int(i), _describe_bad_velocity(*V[i]))
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
        if type(i) is not int or not 0 <= i < self.n:  # (`_check_index`, inline: 400 calls a second)
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
        on = usable if dribble else False  # (`bool(dribble) and usable` without the call: 400 a second)
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
        # (the builtin `min` over the memoryview, without keywords (slow to parse): the same int, without NumPy's
        # reduction; no robots, nothing to check)
        if not self.n or min(self._last_command) > self.step_index + next_check - limit:
            return  # every robot commanded recently (the usual case): nothing to check one by one
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

    # --- stepping --------------------------------------------------------------------------------------------
    def advance(self) -> None:
        """One physics step as a run makes it after its nodes: at a control tick, the watchdog first (robots
        whose commands stopped coming are stopped within ``control.command_timeout``)."""
        self._step(True)

    def step(self, n: int = 1) -> None:
        step = self._step
        for _ in range(n):
            step()

    def _step(self, watch: bool = False) -> None:
        """One physics step; with ``watch``, at a control tick the watchdog first (`advance`)."""
        d = self.d
        drive = self.drive
        k = self.step_index
        cs = self.control_steps
        into = k % cs
        if watch and into == 0:
            self.watchdog(self.scene.control.command_timeout, cs)
        if drive.any_dirty or (into == 0 and any(self._drive_ramping)):
            self._plan_drive(drive.dirty | drive.ramping if into == 0 else drive.dirty.copy(), cs - into)
        if self.track_wheels:
            self.wheel_travel += np.einsum("nwk,nk->nw", drive.M, self._act3) * self.dt
        self.ball.before_step(k, self.usable)
        if self._wrenches:
            self._apply_wrenches()
        if self.aerial is not None:
            self.aerial.step(d.ctrl)
            self._frame_vel = d.qvel[self._frame_v]  # before the step: what a drone hits something with
        qpos = self._qpos_flat  # (plain floats: a NumPy scalar costs more to make and compare, every step)
        vz = self._qvel_flat[self._bvz]
        z = qpos[self._bz]
        mujoco.mj_step(self.m, d)
        if vz < -BOUNCE_MIN_SPEED and qpos[self._bz] < self.ball_radius and self.restitution > 0:
            self._bounce(z, vz)
        if self.aerial is not None:
            self._frame_contacts()
        self.step_index += 1

    def _frame_contacts(self) -> None:
        """A ``collision`` event (value: the drone's speed as it came) for each drone frame that meets
        something it has not touched for a quarter of a second: a wall, the floor, an obstacle, the ceiling,
        a robot, the ball, another drone (a drone that bumps along a wall makes one event, not one a step)."""
        d = self.d
        if not d.ncon:
            return
        step, apart = self.step_index, round(COLLISION_APART / self.dt)
        touching = self._frame_touching
        for k, g in sorted(set(frame_contacts(d.contact.geom, d.ncon, self._frame_of))):
            last = touching.get((k, g))
            touching[(k, g)] = step
            if last is None or step - last > apart:
                i = self.ng + k
                detail = f"{self.robot_names[i]} hit {self._geom_label[g]}"
                speed = math.sqrt(float(self._frame_vel[3 * k : 3 * k + 3] @ self._frame_vel[3 * k : 3 * k + 3]))
                self.event("collision", i, value=round(speed, 4), detail=detail)

    def _bounce(self, z0: float, vz0: float) -> None:
        """The falling ball (height ``z0``, vertical speed ``vz0`` at the start of the step) met the floor
        during the step: its vertical motion is replaced by the exact one, impact included, rebounding at
        restitution times the impact speed. (The floor contact itself is critically damped and would
        swallow the bounce; it is not active yet during the step the ball arrives.)"""
        d, g, dt, r = self.d, self.scene.physics.gravity, self.dt, self.ball_radius
        # time of impact: z0 + vz0 t - g t^2 / 2 = r
        h = max(z0 - r, 0.0)
        disc = vz0 * vz0 + 2.0 * g * h
        t_hit = min(dt, (vz0 + math.sqrt(disc)) / g) if g > 0 else min(dt, h / -vz0)
        v_up = -self.restitution * (vz0 - g * t_hit)
        tau = dt - t_hit
        d.qpos[self._bz] = r + v_up * tau - 0.5 * g * tau * tau
        d.qvel[self._bvz] = v_up - g * tau

    def _plan_drive(self, due: np.ndarray, window: int) -> None:
        """Plan the wheel ramps of the robots marked in ``due`` for the next ``window`` steps and hand them to
        their base servos: the set point (the servo's activation) moves at the planned rate (ctrl) and
        stops at the target (actrange), integrated by the engine. The bias corrects for the engine moving
        a body during a step along its heading at the start of the step (it turns the set point by half
        the step's rotation), so the base follows the commanded twist along the exact arc."""
        drive = self.drive
        args = (
            drive.M,
            drive.Mpinv,
            drive.cmd,
            drive.dirty,
            due,
            drive.U_target,
            drive.up,
            drive.down,
            drive.max_speed,
            self._act3,
            window,
            self._actrange3,
            self._ctrl3,
            self._bias3,
            self._kv,
            drive.ramping,
            drive.dt,
        )
        plan = self._plan
        if plan is None:  # (`OmniDrive.plan` without numba's dispatcher: the same kinds of arguments at every call)
            plan = self._plan = entry(plan_drive, *args)
        plan(*args)
        drive.any_dirty = any(self._drive_dirty)  # (`bool(drive.dirty.any())` without NumPy's reduction)

    def _reset_drive(self, i: int, body_velocity: np.ndarray | None) -> None:
        """Robot i's wheels turn at once at the speeds of ``body_velocity`` (teleports, freezing)."""
        V = np.zeros(3) if body_velocity is None else body_velocity
        self.drive.cmd[i] = V
        self.drive.U_target[i] = self.drive.target_speeds(V[None, :], np.array([i]))[0]
        V = np.einsum("kw,w->k", self.drive.Mpinv[i], self.drive.U_target[i])
        self._act3[i] = V
        self.drive.dirty[i] = False
        due = np.zeros(self.n, dtype=bool)
        due[i] = True
        self._plan_drive(due, self.control_steps - self.step_index % self.control_steps)

    def commanded_velocity(self) -> np.ndarray:
        """(N, 3): each robot's body-velocity set point now (after the wheel limits)."""
        return self._act3.copy()

    def wheel_speeds(self) -> np.ndarray:
        """(N, W): each robot's commanded rim speeds now."""
        return np.einsum("nwk,nk->nw", self.drive.M, self._act3)

    def _apply_wrenches(self) -> None:
        xf = self.d.xfrc_applied
        xf[:] = 0.0
        keep = []
        for body, wrench, until in self._wrenches:
            if self.step_index < until:
                xf[body] += wrench
                keep.append((body, wrench, until))
        self._wrenches = keep

    def _init_touch_bounds(self) -> None:
        """The robots' geoms and, for each, how far its centre must be from the ball's for the engine to
        make no contact between them (see `kernels.ball_apart`): both bounding spheres, the largest margin
        a contact may have (geoms', explicit pairs', the global override), and a centimetre to spare. A geom
        without a bounding sphere (a plane) never counts as apart."""
        m = self.m
        geoms = np.flatnonzero(self._geom_robot >= 0)
        margin = max(float(m.geom_margin.max(initial=0.0)), float(m.pair_margin.max(initial=0.0)))
        if m.opt.enableflags & mujoco.mjtEnableBit.mjENBL_OVERRIDE:
            margin = max(margin, float(m.opt.o_margin))
        rball = float(m.geom_rbound[self.ix.ball_geom])
        rb = m.geom_rbound[geoms]
        bound = np.where((rb > 0) & (rball > 0), rb + rball + margin + 0.01, np.inf)
        self._touch_geoms, self._touch_bound2 = geoms.astype(np.int64), bound * bound
        self._geom_xpos = self.d.geom_xpos  # a view of the engine's array (the same memory at every step)
        self._ball_geom = int(self.ix.ball_geom)

    def ball_touches(self) -> list[int]:
        """Robots whose mouth touches the ball right now (from the engine's contacts).

        Called every physics step while anybody listens to ``ball_contacts``: most steps no robot is near
        enough to the ball for a contact (a compiled test of the bounding spheres, about a microsecond), and
        the contact list, whose accessor costs some ten microseconds, is not read; otherwise a scan of plain
        ints (the contacts are few) costs a few microseconds where NumPy calls on such small arrays cost tens."""
        bg = self._ball_geom
        # (a held ball is in its holder's mouth: never apart, the test is left out; the test first, before the
        # contacts' count, whose accessor costs more)
        if self.ball.holder < 0 and self._ball_apart(self._geom_xpos, self._touch_geoms, self._touch_bound2, bg):
            return []
        d = self.d
        n = d.ncon
        if n == 0:
            return []
        flat = d.contact.geom.ravel().tolist()  # (the engine's ncon contacts: its rows are those alone)
        if bg not in flat:
            return []
        robot_of = self._geom_robot_list
        robots = set()
        for k in range(0, 2 * n, 2):
            a, b = flat[k], flat[k + 1]
            r = robot_of[b] if a == bg else robot_of[a] if b == bg else -1
            if r >= 0:
                robots.add(r)
        return sorted(robots)

    # --- states --------------------------------------------------------------------------------------------
    def robot_positions(self) -> np.ndarray:
        """(N, 3) x, y, yaw of every robot (world frame): a view for ground robots alone (valid until the next
        step, do not modify), a new array where aerial robots fly."""
        if self.aerial is None:
            return self._qpos3
        return self.robot_array()[:, :3]

    def robot_xy(self, i: int) -> np.ndarray:
        """Robot i's x, y (world frame)."""
        if i < self.ng:
            return self.d.qpos[self._rq[i, :2]]
        a = self.ix.aerial.qpos[i - self.ng]
        return self.d.qpos[a : a + 2].copy()

    def aerial_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """Poses (A, 7) and world twists (A, 6) of the aerial robots (empty without them)."""
        if self.aerial is None:
            return np.zeros((0, 7)), np.zeros((0, 6))
        ix = self.ix.aerial
        return aerial_poses(self.d.qpos, self.d.qvel, ix.qpos, ix.qvel)

    def robot_heights(self, aerial: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """(N, 2): z and vz of every robot's origin, world frame (0 for ground robots)."""
        out = np.zeros((self.n, 2))
        if self.aerial is not None:
            pose, twist = aerial or self.aerial_arrays()
            out[self.ng :, 0] = pose[:, 2]
            out[self.ng :, 1] = twist[:, 2]
        return out

    def ball_position(self) -> np.ndarray:
        """(3,) view of the ball's x, y, z (world frame); valid until the next step, do not modify."""
        return self.d.qpos[self._bq : self._bq + 3]

    def robot_array(self, aerial: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """(N, 6): x y yaw vx vy w of every robot, world frame (an aerial robot's heading and turn rate about
        the vertical; ``aerial``: its `aerial_arrays`, if at hand)."""
        out = np.empty((self.n, 6))
        ng = self.ng
        out[:ng, :3] = self._qpos3
        out[:ng, 3:] = self._qvel3
        if self.aerial is not None:
            out[ng:] = planar(*(aerial or self.aerial_arrays()))
        return out

    def ball_array(self) -> np.ndarray:
        """(6,): x y z vx vy vz of the ball, world frame."""
        q, v = self.d.qpos, self.d.qvel
        b, bv = self._bq, self._bv
        return np.array((q[b], q[b + 1], q[b + 2], v[bv], v[bv + 1], v[bv + 2]))

    def model_state_arrays(self) -> tuple[list[str], np.ndarray, np.ndarray]:
        """Names, poses (M, 7: x y z qw qx qy qz) and twists (M, 6: v, w), world frame; ball last."""
        pose, twist = model_poses(self.d.qpos, self.d.qvel, self._q0, self._v0, self.ng, self._bq, self._bv)
        if self.aerial is not None:
            ap, at = self.aerial_arrays()
            ng = self.ng
            pose = np.concatenate((pose[:ng], ap, pose[ng:]))
            twist = np.concatenate((twist[:ng], at, twist[ng:]))
        return self.model_names, pose, twist

    def model_state_arrays32(self) -> tuple[np.ndarray, np.ndarray]:
        """`model_state_arrays`' poses and twists rounded to float32 and flat (M*7,), (M*6,), as the
        ModelStates message carries them: one compiled call, for every physics step's message (in a world with
        drones, whose poses come from the airframes, the float64 arrays rounded)."""
        if self.aerial is not None:
            _, pose, twist = self.model_state_arrays()
            return pose.astype(np.float32).ravel(), twist.astype(np.float32).ravel()
        pose, twist = _zeros(self._pose32_size, _f32), _zeros(self._twist32_size, _f32)
        self._poses32(self._qpos, self._qvel, self._q0, self._v0, self.n, self._bq, self._bv, pose, twist)
        return pose, twist

    def state_fingerprint(self) -> int:
        """`fingerprint` of `model_state_arrays`' poses and twists, without making them (a recording takes it at
        every control tick)."""
        if self.aerial is not None or self.fingerprint_kind != FINGERPRINT:
            _, pose, twist = self.model_state_arrays()
            return fingerprint(pose, twist, self.fingerprint_kind)
        return self._state_fingerprint(
            self._qpos, self._qvel, self._q0, self._v0, self.n, self._bq, self._bv, self._state64, self._words64
        )

    def model_states(self) -> dict[str, ModelStateView]:
        names, pose, twist = self.model_state_arrays()
        out = {}
        for name, p, t in zip(names, pose.tolist(), twist.tolist()):  # plain floats: a judge reads them often
            out[name] = ModelStateView(name, *p[:3], _yaw_of(*p[3:]), *p[3:], *t)
        return out

    def robot_body_velocity(self, R: np.ndarray | None = None) -> np.ndarray:
        """(N, 3): each robot's velocity in its own body frame (vx forward, vy left, w); for an aerial robot
        its horizontal velocity in its heading frame."""
        if R is None:
            R = self.robot_array()
        c, s = np.cos(R[:, 2]), np.sin(R[:, 2])
        out = np.empty((len(R), 3))
        out[:, 0] = c * R[:, 3] + s * R[:, 4]
        out[:, 1] = c * R[:, 4] - s * R[:, 3]
        out[:, 2] = R[:, 5]
        return out

    def measured_wheel_speeds(self, R: np.ndarray | None = None) -> np.ndarray:
        """(Ng, W): rim speeds that follow from each ground robot's actual motion (what wheel encoders
        measure)."""
        if R is None:
            R = self.robot_array()
        return np.einsum("nwk,nk->nw", self.drive.M, self.robot_body_velocity(R[: self.ng]))

    def link_state_arrays(self) -> tuple[list[str], np.ndarray, np.ndarray]:
        """Every link: each robot's base and wheels (an aerial robot's base and rotors), and the ball. Same
        layout as model states.

        A wheel's pose is its hub centre, with its axle along the line from the robot centre; its
        angular velocity adds the wheel's spin (from its rim speed) to the robot's turn. A rotor's pose is
        its hub, turned with the body; its velocity is the body's at that point."""
        self.track_wheels = True
        names, pose, twist = self.model_state_arrays()
        travel = self.wheel_travel
        U = self.wheel_speeds()
        out_names, out_pose, out_twist = [], [], []
        for i, rname in enumerate(self.robot_names):
            rm = self.robot_models[i]
            out_names.append(f"{rname}/base")
            out_pose.append(pose[i])
            out_twist.append(twist[i])
            if i >= self.ng:
                for k, (p, v) in enumerate(rotor_links(rm, pose[i], twist[i])):
                    out_names.append(f"{rname}/rotor_{k + 1}")
                    out_pose.append(p)
                    out_twist.append(v)
                continue
            x, y, _, qw, _, _, qz = pose[i]
            yaw = 2.0 * math.atan2(qz, qw)
            r = rm.params.wheel_radius
            for k, wheel in enumerate(rm.wheels):
                a = yaw + wheel.alpha
                cx, cy = x + wheel.distance * math.cos(a), y + wheel.distance * math.sin(a)
                spin = travel[i, k] / r
                # orientation: yaw to the wheel's radial direction, then spin about that (local x) axis
                qa = (math.cos(a / 2), 0.0, 0.0, math.sin(a / 2))
                qs = (math.cos(spin / 2), math.sin(spin / 2), 0.0, 0.0)
                quat = np.empty(4)
                mujoco.mju_mulQuat(quat, np.array(qa), np.array(qs))
                wz = twist[i, 5]
                spin_rate = U[i, k] / r
                vx = twist[i, 0] - wz * (cy - y)
                vy = twist[i, 1] + wz * (cx - x)
                out_names.append(f"{rname}/wheel_{k + 1}")
                out_pose.append(np.array((cx, cy, r, *quat)))
                out_twist.append(np.array((vx, vy, 0.0, spin_rate * math.cos(a), spin_rate * math.sin(a), wz)))
        out_names.append(BALL_NAME)
        out_pose.append(pose[self.n])
        out_twist.append(twist[self.n])
        return out_names, np.array(out_pose), np.array(out_twist)

    def observations(self, stamp: float, tick: int, only: list[int] | None = None) -> list:
        """Every robot's OmniVisionInfo now (``only``: those robots', None in the others' places), as
        `Perception.observe` makes them from a `snapshot` (which updates the robots' 'stuck' flags) delayed by
        the perception's latency. For exact perception of ground robots (no noise, dropout, sight rules or
        latency: the shipped matches) one compiled call reads the engine's arrays into the messages' numbers
        instead (`kernels.sense_ground`): the same messages, without the snapshot's arrays."""
        p = self.perception
        if only is not None or not self._sense_fast:
            return p.observe(p.delayed(self.snapshot()), stamp, tick, only)
        n, m = self.n, self.n - 1
        obs = np.empty((6 * n, m), dtype=np.float32)
        wheels = np.empty((n, self.drive.max_wheels), dtype=np.float32)
        args = (
            self._qpos,
            self._qvel,
            self._q0,
            self._v0,
            self._bq,
            self._bv,
            *self._flags_in,
            self.step_index,
            *self._flags_of,
            p.sign,
            p.others,
            p.own32,
            p.balls32,
            p.valid,
            p.stuck,
            obs,
            wheels,
        )
        sense = self._sense
        if sense is None:  # (the arguments' kinds are the same at every call: see `simatch.compiled.entry`)
            sense = self._sense = entry(sense_ground, *args)
        sense(*args)
        self.stuck = p.stuck
        return p.observe_exact(obs, wheels, self.ball.holder, stamp, tick)

    def snapshot(self) -> Snapshot:
        """The current world for perception (also updates each robot's 'stuck' flag)."""
        flying = self.aerial_arrays() if self.aerial is not None else None
        R = self.robot_array(flying)
        F = self.field
        ng = self.ng
        wheels, valid, stuck = robot_flags(
            R[:ng] if self.aerial is not None else R, *self._flags_in, self.step_index, *self._flags_of
        )
        heights = None
        if self.aerial is not None:  # aerial robots: valid over the field while enabled; never stuck
            na = self.n - ng
            wheels = np.concatenate((wheels, np.zeros((na, wheels.shape[1]))))
            air = R[ng:]
            over = (np.abs(air[:, 0]) <= F.half_length + 1.0) & (np.abs(air[:, 1]) <= F.half_width + 1.0)
            valid = np.concatenate((valid, over & self.enabled[ng:]))
            stuck = np.concatenate((stuck, np.zeros(na, dtype=bool)))
            heights = self.robot_heights(flying)
        self.stuck = stuck
        return Snapshot(
            step=self.step_index,
            robots=R,
            ball=self.ball_array(),
            holder=self.ball.holder,
            wheels=wheels,
            valid=valid,
            stuck=stuck.copy(),
            heights=heights,
        )

    def _update_stuck(self, R: np.ndarray) -> None:
        """Stuck: commanded to move (> 0.2 m/s) but moving at less than half of it for 0.5 s or more."""
        V = self._act3
        cmd2 = V[:, 0] ** 2 + V[:, 1] ** 2
        slow = (cmd2 > 0.04) & (R[:, 3] ** 2 + R[:, 4] ** 2 < 0.25 * cmd2)
        since = self._slow_since
        since[~slow] = -1
        since[slow & (since < 0)] = self.step_index
        self.stuck = slow & (self.step_index - since >= self._stuck_steps)

    def digest(self) -> str:
        """Hex SHA-256 of every model's state: equal digests mean the same run, bit for bit."""
        names, pose, twist = self.model_state_arrays()
        h = hashlib.sha256()
        h.update("\n".join(names).encode())
        h.update(np.ascontiguousarray(pose).tobytes())
        h.update(np.ascontiguousarray(twist).tobytes())
        return h.hexdigest()

    # --- the Gazebo-like interface ------------------------------------------------------------------------------
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
            if not _finite(v) or abs(v) > 1e4:
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
        self._set_free(BALL_NAME, self._bq, self._bv, s, self.ball_radius)

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
            norm = np.linalg.norm(quat)
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
        qa, va = self._rq[i], self._rv[i]
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
            q[qa[2]] = _yaw_of(s.get("qw", 1.0), s.get("qx", 0.0), s.get("qy", 0.0), s.get("qz", 0.0))
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
        b = self._bq
        bx, by = q[b], q[b + 1]
        R = q[self._rq]
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
        if not _finite(*f, *t, duration) or duration < 0 or any(abs(x) > MAX_WRENCH for x in f + t):
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
            self.d.qvel[self._rv[i]] = 0.0

    def _freeze(self, i: int, on: bool) -> None:
        if i >= self.ng:
            return self._freeze_drone(i - self.ng, on)
        eq = self.ix.freeze_eq[i]
        if on:
            x, y, yaw = self.d.qpos[self._rq[i]]
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
