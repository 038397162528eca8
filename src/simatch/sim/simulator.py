"""The simulation subsystem's core: the MuJoCo world with its robots and ball, stepped at the physics rate.

It realises the robots' motions (omnidirectional drive with wheel limits, dribbler, kicker; aerial robots'
flight), gives exact model and link states, and offers the Gazebo-like interface: set model/link state,
apply a force/torque for a duration. It knows nothing of soccer rules; the bus adapter (`simatch.sim.node`)
connects it to the other subsystems.

`Simulator` is made of parts, each in a module of its own:

* `simatch.sim.engine`: named views of the engine's arrays the kernels read and write (`EngineViews`);
* `simatch.sim.commands`: command intake and the watchdog (`CommandIntake`);
* `simatch.sim.services`: the Gazebo-like world services (`WorldServices`);
* `simatch.sim.readout`: the states, the fingerprint and the digest (`StateReadout`);
* `simatch.sim.sensing`: the robots' perception and the ball's contacts (`Sensing`);
* `simatch.sim.components`: each step's per-component fingerprints, while somebody records them (`prints`);
* `simatch.sim.ballhandling`, `simatch.sim.flight`, `simatch.robots.drive`: the mechanisms.

This module builds the world, steps it, plans the wheels and reports events.

Everything that enters the world from outside goes through the methods marked `world_input` (commands,
the Gazebo-like calls, sending off, freezing): while `inputs` is on they are logged there, so that a run
can be re-simulated from its inputs alone (`simatch.sim.inputs`).
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable

import mujoco
import numpy as np

from .. import msgs
from ..compiled import bind
from ..config.schema import Scene
from ..robots.drive import OmniDrive, plan_drive
from .ballhandling import BallHandling
from .commands import MAX_COMMAND_SPEED, MAX_COMMAND_TURN, MAX_KICK_REQUEST, CommandError, CommandIntake
from .components import ComponentPrints
from .engine import EngineViews
from .flight import AerialFleet, frame_contacts
from .inputs import InputLog, install
from .readout import FINGERPRINT, FINGERPRINTS, ModelStateView, StateReadout, fingerprint
from .sensing import Sensing
from .services import WorldServices
from .timers import keep_timers_off
from .world import BALL_NAME, build_world

__all__ = [
    "FINGERPRINT",
    "FINGERPRINTS",
    "MAX_COMMAND_SPEED",
    "MAX_COMMAND_TURN",
    "MAX_KICK_REQUEST",
    "CommandError",
    "ModelStateView",
    "Simulator",
    "fingerprint",
]

BOUNCE_MIN_SPEED = 0.3  # m/s: slower impacts are absorbed (the ball settles instead of chattering)
COLLISION_APART = 0.25  # s: a drone that touches a thing again after this long apart has hit it again


def _label(geom_name: str) -> str:
    """What a geom is, for an event: a robot's name for its parts, else the geom's own name."""
    for part in ("/hull", "/mouth"):
        if geom_name.endswith(part):
            return geom_name[: -len(part)]
    return geom_name or "something"


class Simulator(CommandIntake, WorldServices, StateReadout, Sensing):
    """The world of ``scene`` (its randomness from ``seed``), stepped by `advance`; ``on_event`` is called with
    every GameEvent as it happens (they are also kept in ``events`` until taken)."""

    def __init__(self, scene: Scene, seed: int = 0, on_event: Callable | None = None):
        self.scene = scene
        self.seed = seed
        self.m, self.d, self.ix, self.field = build_world(scene)
        keep_timers_off()  # MuJoCo's profiling timers: simatch never reads them
        self.dt = float(self.m.opt.timestep)
        self.step_index = 0
        self._init_robots()
        self.engine = EngineViews(self.m, self.d, self.ix, self.ng)
        self._on_event = on_event
        # the log of the world's inputs: on from the start, so that what a judge or a script does before the
        # first step is in it; the bus adapter turns it off while nobody listens
        self._inputs: InputLog | None = None
        self.inputs = InputLog()
        self.events: list = []  # GameEvent messages not yet taken by the bus adapter
        self.mechanics: Counter = Counter()  # kicks, catches, ball losses by reason
        self.ball = BallHandling(self.m, self.d, self.ix, self.robot_models, scene, self._mechanism_event)
        self.ball_radius = scene.ball.radius
        self.restitution = scene.ball.restitution
        self._init_drive()
        self._init_commands()
        self._wrenches: list[tuple[int, np.ndarray, int]] = []  # (body, 6-vector, until step)
        self.touching: list[int] = []  # robots touching the ball after the last step
        #: the aerial robots' controllers (None in a world without them)
        self.aerial = None
        if self.ix.aerial is not None:
            self._init_aerial()
        self._init_readout()
        #: the per-component fingerprints of each step, while somebody listens (`simatch.sim.components`)
        self.prints: ComponentPrints | None = None
        self._init_sensing(seed)
        self._plan_drive(np.ones(self.ng, dtype=bool), self.control_steps)

    def _init_robots(self) -> None:
        """The robots' names, teams, models and frames, in the world's order: ground robots first."""
        scene, robots = self.scene, self.ix.robots
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
        self.control_steps = max(1, round(scene.control.period / self.dt))

    def _init_drive(self) -> None:
        """The ground robots' omnidirectional drives, planned by `plan_drive` onto their base servos."""
        ground = self.robot_models[: self.ng]
        p = [rm.params for rm in ground]
        self.drive = OmniDrive(
            [rm.rim_matrix() for rm in ground],
            [q.max_wheel_speed for q in p],
            [q.max_acceleration for q in p],
            [q.max_deceleration for q in p],
            self.dt,
        )
        self._drive_dirty = self.drive.dirty_flags
        self._drive_ramping = self.drive.ramping_flags
        self._plan = bind(plan_drive)
        self.track_wheels = False
        self.wheel_travel = np.zeros((self.ng, self.drive.max_wheels))  # rim distance rolled [m]

    def _init_aerial(self) -> None:
        """The aerial robots' controllers, and what a drone's frame meeting anything is, for its event."""
        ng, ix = self.ng, self.ix.aerial
        self.aerial = AerialFleet(self.d, ix, self.robot_models[ng:], self.dt, self.scene.physics.gravity)
        self._frame_of = np.full(self.m.ngeom, -1, dtype=np.int64)
        self._frame_of[ix.geom] = np.arange(len(ix.geom))
        self._geom_label = [_label(self.m.geom(g).name) for g in range(self.m.ngeom)]
        self._frame_touching: dict = {}  # (drone, geom) -> last step they touched
        self._frame_v = (ix.qvel[:, None] + np.arange(3)).ravel()
        self._frame_vel = self.d.qvel[self._frame_v]
        d = self.d  # what drones touch at the start (a landed drone stands on the floor) is no collision
        for pair in frame_contacts(d.contact.geom, d.ncon, self._frame_of) if d.ncon else ():
            self._frame_touching[pair] = 0

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
        fp = self.prints  # each component's fingerprint, while recorded (`simatch.sim.components`)
        if fp is not None:
            fp.inputs()
        if drive.any_dirty or (into == 0 and any(self._drive_ramping)):
            self._plan_drive(drive.dirty | drive.ramping if into == 0 else drive.dirty.copy(), cs - into)
        if self.track_wheels:
            self.wheel_travel += np.einsum("nwk,nk->nw", drive.M, self.engine.setpoint) * self.dt
        self.ball.before_step(k, self.usable)
        wrenched = self._wrenches  # (the list of this step: applying them makes a new one)
        if wrenched:
            self._apply_wrenches()
        if self.aerial is not None:
            self.aerial.step(d.ctrl)
            self._frame_vel = d.qvel[self._frame_v]  # before the step: what a drone hits something with
        if fp is not None:
            fp.before_physics(bool(wrenched))
        e = self.engine  # the ball's height and vertical speed, before and after the step: a bounce?
        qpos = e.qpos_flat
        vz = e.qvel_flat[e.ball_vz]
        z = qpos[e.ball_z]
        mujoco.mj_step(self.m, d)
        if fp is not None:
            fp.physics()
        if vz < -BOUNCE_MIN_SPEED and qpos[e.ball_z] < self.ball_radius and self.restitution > 0:
            self._bounce(z, vz)
            if fp is not None:
                fp.bounce()
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
                vx, vy, vz = self._frame_vel[3 * k : 3 * k + 3].tolist()
                speed = math.sqrt(vx * vx + vy * vy + vz * vz)
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
        d.qpos[self.engine.ball_z] = r + v_up * tau - 0.5 * g * tau * tau
        d.qvel[self.engine.ball_vz] = v_up - g * tau

    def _plan_drive(self, due: np.ndarray, window: int) -> None:
        """Plan the wheel ramps of the robots marked in ``due`` for the next ``window`` steps and hand them to
        their base servos: the set point (the servo's activation) moves at the planned rate (ctrl) and
        stops at the target (actrange), integrated by the engine. The bias corrects for the engine moving
        a body during a step along its heading at the start of the step (it turns the set point by half
        the step's rotation), so the base follows the commanded twist along the exact arc."""
        drive, e = self.drive, self.engine
        self._plan(
            drive.M,
            drive.Mpinv,
            drive.cmd,
            drive.dirty,
            due,
            drive.U_target,
            drive.up,
            drive.down,
            drive.max_speed,
            e.setpoint,
            window,
            e.setpoint_range,
            e.rate,
            e.biasprm,
            e.gain,
            drive.ramping,
            drive.dt,
        )
        drive.any_dirty = any(self._drive_dirty)  # (the builtin over the memoryview: a plain bool)

    def _reset_drive(self, i: int, body_velocity: np.ndarray | None) -> None:
        """Robot i's wheels turn at once at the speeds of ``body_velocity`` (teleports, freezing)."""
        V = np.zeros(3) if body_velocity is None else body_velocity
        self.drive.cmd[i] = V
        self.drive.U_target[i] = self.drive.target_speeds(V[None, :], np.array([i]))[0]
        V = np.einsum("kw,w->k", self.drive.Mpinv[i], self.drive.U_target[i])
        self.engine.setpoint[i] = V
        self.drive.dirty[i] = False
        due = np.zeros(self.n, dtype=bool)
        due[i] = True
        self._plan_drive(due, self.control_steps - self.step_index % self.control_steps)

    def commanded_velocity(self) -> np.ndarray:
        """(N, 3): each robot's body-velocity set point now (after the wheel limits)."""
        return self.engine.setpoint.copy()

    def wheel_speeds(self) -> np.ndarray:
        """(N, W): each robot's commanded rim speeds now."""
        return np.einsum("nwk,nk->nw", self.drive.M, self.engine.setpoint)
