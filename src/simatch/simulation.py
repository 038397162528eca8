"""`Simulation`: one run of a scene, embedded in this process — the Python API of simatch.

It composes the three subsystems on one bus: the simulator (simulation subsystem), the judge and coaches
(scene subsystem) and each team's nodes (strategy subsystem), and ticks them in lockstep, so the same
scene and seed give the same run, bit for bit.

    import simatch
    sim = simatch.Simulation("msl_5v5", seed=1, overrides={"teams.magenta.strategy": "simple"})
    sim.run(seconds=2.0)
    sim.model_states()["ball"].x
"""

from __future__ import annotations

import contextlib
import json
import signal
import threading
import time as _time
import warnings
from collections.abc import Callable, Mapping
from typing import Any

from . import msgs
from .bus import Bus, InProcessBus, LockstepClock, Node, Phase, topics
from .config.loader import LoadedScene, check_models, load_scene
from .scene.coach import Coach
from .scene.judges import make_judge
from .sim.node import PhysicsNode, SimulatorNode
from .sim.simulator import CommandError, Simulator
from .strategy.node import RobotNode
from .strategy.team import build_team


def event_dict(ev) -> dict:
    """A GameEvent as the JSON object of ``simatch run --json``."""
    out: dict[str, Any] = {"t": round(float(ev.stamp), 6), "type": ev.type}
    if ev.team:
        out["team"] = ev.team
    if ev.robot:
        out["robot"] = int(ev.robot)
    if ev.x or ev.y:
        out["x"], out["y"] = round(float(ev.x), 4), round(float(ev.y), 4)
    if ev.value or ev.limit:
        out["value"], out["limit"] = float(ev.value), float(ev.limit)
    if ev.detail:
        out["detail"] = ev.detail
    return out


def _plain(value: Any) -> Any:
    """JSON for numpy scalars and arrays handed to the API (exact: float32 widens to float64 exactly)."""
    if hasattr(value, "tolist"):
        return value.tolist()
    return repr(value)  # never fails the caller; the simulator refuses such values anyway


class StateOverridden(UserWarning):
    """The judge moved a model whose state the caller had just set with `Simulation.set_model_state` (a referee
    places the ball for every restart and parks the robots it sends off): what the caller set did not last."""


#: [s] of simulated time after the caller sets a model's state within which the judge moving that model undoes
#: it (a referee puts a ball that left the spot of a prepared restart back at most once a second)
OVERRIDE_WINDOW = 1.0


class _JudgedWorld:
    """The simulator as the judge's `WorldControl`, telling the `Simulation` which models the judge moves, so that
    the API can say when the judge undoes a state the caller set. Everything else is the simulator's own."""

    def __init__(self, simulator: Simulator, moved: Callable[[str], None]):
        self._simulator = simulator
        self._moved = moved
        self.model_states = simulator.model_states
        self.apply_wrench = simulator.apply_wrench
        self.set_enabled = simulator.set_enabled
        self.set_frozen = simulator.set_frozen

    def set_model_state(self, name: str, **state: float) -> None:
        self._simulator.set_model_state(name, **state)
        self._moved(name)

    def __getattr__(self, name: str):
        return getattr(self._simulator, name)


class ManualDriver(Node):
    """Drives a robot taken over by the caller (`Simulation.take_control`): re-sends the last command every
    control period, as a joystick node would, so the watchdog sees a live robot."""

    phase = Phase.ROBOT

    def __init__(self, team: str, rid: int, period: float):
        self.team, self.rid, self.period = team, rid, period
        self.name = f"{team}/{rid}/manual"
        self.vel = (0.0, 0.0, 0.0, 0.0)
        self.dribble = False
        self.kick = 0.0
        self.lob = False

    def start(self, ctx) -> None:
        super().start(ctx)
        self.pub_vel = ctx.bus.publisher(topics.robot_topic(self.team, self.rid, topics.VEL_CMD), msgs.VelCmd)
        self.pub_action = ctx.bus.publisher(topics.robot_topic(self.team, self.rid, topics.ACTION_CMD), msgs.ActionCmd)

    def send_now(self, now: float) -> None:
        vx, vy, w, vz = self.vel
        self.pub_vel.put(msgs.VelCmd(stamp=now, tick=0, vx=vx, vy=vy, w=w, vz=vz))
        self.pub_action.put(
            msgs.new(
                msgs.ActionCmd,
                stamp=now,
                dribble=self.dribble,
                kick_speed=self.kick,
                kick_type=msgs.ActionCmd.KICK_LOB if self.lob else msgs.ActionCmd.KICK_GROUND,
            )
        )
        self.kick = 0.0

    def tick(self, now: float) -> None:
        self.send_now(now)


class Simulation:
    """One run of a scene. ``scene`` is a shipped scene name, a path to a TOML file, or a LoadedScene."""

    def __init__(
        self,
        scene: str | LoadedScene = "msl_5v5",
        seed: int = 0,
        overrides: Mapping[str, Any] | None = None,
        bus: Bus | None = None,
        run_name: str = "embedded",
        teams: str = "embedded",
    ):
        self.scene = scene if isinstance(scene, LoadedScene) else load_scene(scene, overrides)
        spec = self.scene.spec
        self.seed = int(seed)
        self.bus = bus or InProcessBus(run_name)
        self.clock = LockstepClock(self.bus, spec.physics.timestep, self.seed)
        self._events: list = []
        self._wall = 0.0
        self._closed = False
        self._sub_events = self.bus.subscribe(topics.EVENTS, msgs.GameEvent, self._on_event)
        self._pub_operator = self.bus.publisher(topics.OPERATOR, msgs.OperatorCommand)
        self._stepping = False  # inside a physics step (nodes at work) rather than between steps
        self._running = False  # inside `run`
        self._stop: BaseException | None = None  # raised by `run` at its next step boundary (`stop_soon`)
        check_models(self.scene)
        self.simulator = Simulator(spec, self.seed)
        self._sensor = self.clock.add(SimulatorNode(self.simulator))
        self._set_by_caller: dict[str, float] = {}  # model -> simulated time the caller last set its state
        self._undone: list[tuple[str, float, float]] = []  # (model, set at, moved by the judge at), not yet said
        self.judge = self.clock.add(make_judge(self.scene, _JudgedWorld(self.simulator, self._judge_moved)))
        #: per-team coaches, where no referee gives the commands (``sim.coaches["cyan"].start_play()``)
        self.coaches: dict[str, Coach] = {}
        if not self.judge.gives_commands:
            for team in spec.teams:
                self.coaches[team] = self.clock.add(Coach(team, spec.control.period))
        self.robot_nodes: dict[str, RobotNode] = {}
        self.team_nodes: dict[str, list[Node]] = {}
        if teams == "embedded":
            for team in spec.teams:
                nodes = build_team(self.scene, team, self.seed)
                self.team_nodes[team] = nodes
                for node in nodes:
                    self.clock.add(node)
                    if isinstance(node, RobotNode):
                        self.robot_nodes[node.name] = node
        self._physics = self.clock.add(PhysicsNode(self.simulator, self._sensor))
        self._manual: dict[str, ManualDriver] = {}
        #: pace `run` at this many simulated seconds per wall second (None: as fast as possible); may be
        #: changed while running (e.g. a live viewer asks for real time while it is open)
        self.pace: float | None = None

    # --- events ------------------------------------------------------------------------------------------
    def _on_event(self, ev) -> None:
        self._events.append(ev)
        if ev.type == "coach_command" and ev.team in self.coaches:
            # a run has coaches only where no judge gives commands: their commands come from outside
            coach = self.coaches[ev.team]
            self._operator("coach", ev.team, cmd=int(ev.value), max_vel=coach.max_vel, max_w=coach.max_w, **coach.extra)

    # --- operator commands ------------------------------------------------------------------------------------
    def _operator(self, call: str, target: str, **args: Any) -> None:
        """Publish an intervention from outside the run's nodes on the ``operator`` topic (when anybody, e.g.
        a recorder, listens), so that the run can be re-simulated from its recording."""
        if self._pub_operator.active:
            self._pub_operator.put(
                msgs.OperatorCommand(
                    stamp=self.time,
                    step=self.simulator.step_index,
                    during_step=self._stepping,
                    call=call,
                    target=target,
                    args=json.dumps(args, default=_plain),
                )
            )

    @property
    def events(self) -> list[dict]:
        """Every event so far, as in ``simatch run --json``."""
        return [event_dict(ev) for ev in self._events]

    # --- time ----------------------------------------------------------------------------------------------
    @property
    def dt(self) -> float:
        return self.simulator.dt

    @property
    def time(self) -> float:
        """Simulated seconds since the start."""
        return self.simulator.time

    @property
    def done(self) -> bool:
        """The judge has ended the run (e.g. the match is over)."""
        return self.judge.done

    @property
    def duration(self) -> float | None:
        return self.judge.duration

    def step(self, n: int = 1, hold_before: Phase | None = None) -> None:
        """Advance by ``n`` physics steps; every node and the judge run in lockstep. With ``hold_before``,
        then also tick the next step's nodes of the phases before that one and hold the step there (the next
        call finishes it, as its first step): a learning environment holds each control tick before
        `Phase.ROBOT`, where the perception and the game command are out and the decisions are still to come."""
        t0 = _time.perf_counter()
        step = self.clock.step
        self._stepping = True
        try:
            for _ in range(n):
                step()
            if hold_before is not None:
                self.clock.step_until(hold_before)
        finally:
            self._stepping = self.clock.holding
        self._wall += _time.perf_counter() - t0
        self._say_undone()

    def run(
        self,
        seconds: float | None = None,
        until_done: bool = True,
        progress: Callable[[float], None] | None = None,
        realtime: bool = False,
    ) -> None:
        """Advance by ``seconds`` of simulated time (default: the run's duration), stopping early when the
        judge ends the run. ``progress(sim_time)`` is called about ten times a simulated second;
        ``realtime`` paces the run at wall-clock speed (as does ``pace``, which may change during the run)."""
        if seconds is None:
            seconds = self.duration
            if seconds is None:
                raise ValueError("this scene has no duration: give seconds=...")
            seconds = max(0.0, seconds - self.time)
        steps = int(round(seconds / self.dt))
        chunk = max(1, int(round(0.1 / self.dt)))
        t0 = _time.perf_counter()
        anchor: tuple[float, float, float] | None = None  # (wall, sim, pace) when pacing began
        done = 0
        self._running = True
        try:
            while done < steps and not (until_done and self.judge.done):
                self._raise_stop()
                done += self._run_chunk(min(chunk, steps - done), until_done, progress)
                pace = 1.0 if realtime else self.pace
                if pace:
                    now = _time.perf_counter()
                    if anchor is None or anchor[2] != pace:
                        anchor = (now, self.time, pace)
                    ahead = (self.time - anchor[1]) / pace - (now - anchor[0])
                    if ahead > 0:
                        _time.sleep(ahead)
                else:
                    anchor = None
            self._raise_stop()
        finally:
            self._running, self._stop = False, None
            self._wall += _time.perf_counter() - t0
        self._say_undone()

    def _run_chunk(self, n: int, until_done: bool, progress) -> int:
        step = self.clock.step
        self._stepping = True
        try:
            for _ in range(n):
                step()
                if until_done and self.judge.done:
                    break
        finally:
            self._stepping = False
        if progress is not None:
            progress(self.time)
        return n

    def stop_soon(self, exc: BaseException) -> bool:
        """Make the `run` in progress raise ``exc`` at its next step boundary (within a tenth of a simulated
        second), for signal handlers: an exception raised by a handler at an arbitrary point can land inside a
        node's step or a compiled kernel's dispatch and leave a half-done step or a garbled error. Returns False
        when no run is in progress (or a stop is already pending): then the caller should raise it at once."""
        if not self._running or self._stop is not None:
            return False
        self._stop = exc
        return True

    @contextlib.contextmanager
    def stopping_on(self, signum: int, exc_type: type[BaseException]):
        """While the block runs, signal ``signum`` makes the run raise ``exc_type`` at its next step boundary
        (`stop_soon`) rather than wherever the signal lands; a second one raises at once. Only in the main
        thread (the only one that receives signals); elsewhere a no-op."""
        if threading.current_thread() is not threading.main_thread():
            yield
            return

        def handler(signo, frame):
            if not self.stop_soon(exc_type()):
                raise exc_type()

        previous = signal.signal(signum, handler)
        try:
            yield
        finally:
            signal.signal(signum, previous)

    def _raise_stop(self) -> None:
        exc, self._stop = self._stop, None
        if exc is not None:
            raise exc

    # --- the simulation interface ---------------------------------------------------------------------------
    def model_states(self):
        """Every model's state (name -> ModelStateView: pose with yaw, twist), world frame."""
        return self.simulator.model_states()

    def link_states(self):
        names, pose, twist = self.simulator.link_state_arrays()
        return {n: (pose[i], twist[i]) for i, n in enumerate(names)}

    def set_model_state(self, name: str, **state: float) -> None:
        """Place a model and/or set its velocity (keys: x y z yaw qw qx qy qz vx vy vz wx wy wz), world frame, at
        once. Where a judge moves models itself (a referee places the ball for every restart), a state it undoes
        within a second is reported by a `StateOverridden` warning when `run` or `step` returns."""
        self.simulator.set_model_state(name, **state)
        self._operator("set_model_state", name, **state)
        self._sensor.flush_events()
        self._set_by_caller[name] = self.time

    def _judge_moved(self, name: str) -> None:
        at = self._set_by_caller.pop(name, None)
        if at is not None and self.time - at <= OVERRIDE_WINDOW + 1e-9:
            self._undone.append((name, at, self.time))

    def _say_undone(self) -> None:
        """A `StateOverridden` warning for each state the caller set that the judge has undone (raised here, at
        the caller's `run` or `step`, so that it points at the caller's code)."""
        undone, self._undone = self._undone, []
        for name, at, t in undone:
            why = next(
                (
                    e.detail
                    for e in self._events
                    if abs(float(e.stamp) - t) < 1e-9 and e.detail and e.type not in ("command", "stage")
                ),
                "",
            )
            tip = (
                "set the ball while it is in play, run the scene without a referee (judge.kind = 'none'), or "
                "ask the referee to place it: sim.judge.place_ball(x, y)"
                if name == "ball"
                else "a referee parks the robots it sends off and keeps them there until they come back"
            )
            warnings.warn(
                StateOverridden(
                    f"the judge ({self.scene.spec.judge.kind}) moved {name!r} at t = {t:.3f} s, "
                    f"{t - at:.3f} s after set_model_state({name!r}) set it" + (f" ({why})" if why else "") + f": {tip}"
                ),
                stacklevel=3,
            )

    def set_link_state(self, name: str, **state: float) -> None:
        self.simulator.set_link_state(name, **state)
        self._operator("set_link_state", name, **state)
        self._sensor.flush_events()

    def apply_wrench(self, name: str, force=(0.0, 0.0, 0.0), torque=(0.0, 0.0, 0.0), duration: float = 0.0) -> None:
        self.simulator.apply_wrench(name, force, torque, duration)
        self._operator("apply_wrench", name, force=list(force), torque=list(torque), duration=duration)

    def set_rotor(self, name: str, rotor: int, working: bool = True) -> None:
        """Cut (``working=False``) or restore rotor ``rotor`` (1-4) of an aerial robot: a cut rotor gives no
        thrust, and the drone's controller does not know it."""
        self.simulator.set_rotor(name, rotor, working)
        self._operator("set_rotor", name, rotor=rotor, working=bool(working))
        self._sensor.flush_events()

    def set_perception_phase(self, name: str, phase: int) -> None:
        """Take robot ``name``'s perception (OmniVisionInfo) at physics step ``phase`` of each control period
        instead of the first: a real-time server spreads its robot processes over the period this way."""
        self._sensor.set_vision_phase(self.simulator.index_of(name), phase)

    # --- driving robots by hand -------------------------------------------------------------------------------
    def take_control(self, name: str) -> None:
        """Detach ``name`` from its strategy: from now on the caller drives it (send_vel, send_action)."""
        if name in self._manual:
            return
        team, rid = topics.split_robot_name(name)
        self.simulator.index_of(name)  # raises for an unknown robot
        node = self.robot_nodes.get(name)
        if node is not None:
            node.detached = True
        driver = ManualDriver(team, rid, self.scene.spec.control.period)
        self.clock.add(driver)
        self._manual[name] = driver
        self._operator("take_control", name)

    def release_control(self, name: str) -> None:
        driver = self._manual.pop(name, None)
        if driver is not None:
            self.clock.remove(driver)
        node = self.robot_nodes.get(name)
        if node is not None:
            node.detached = False
        if driver is not None:
            self._operator("release_control", name)

    def _driver(self, name: str) -> ManualDriver:
        try:
            return self._manual[name]
        except KeyError:
            raise CommandError(f"{name} is not under manual control: call take_control({name!r}) first") from None

    def send_vel(self, name: str, vx: float, vy: float, w: float, vz: float = 0.0) -> None:
        """Body-frame velocity command for a robot under manual control (applies at once); ``vz``, the
        upward speed, moves aerial robots."""
        d = self._driver(name)
        d.vel = (vx, vy, w, vz)
        args = {"vx": vx, "vy": vy, "w": w} if vz == 0.0 else {"vx": vx, "vy": vy, "w": w, "vz": vz}
        self._operator("send_vel", name, **args)
        d.send_now(self.time)

    def send_action(self, name: str, dribble: bool = False, kick: float = 0.0, lob: bool = False) -> None:
        """Dribbler on/off and a kick (speed in m/s, ground or lob) for a robot under manual control."""
        d = self._driver(name)
        d.dribble, d.kick, d.lob = bool(dribble), float(kick), bool(lob)
        self._operator("send_action", name, dribble=d.dribble, kick=d.kick, lob=d.lob)
        d.send_now(self.time)

    # --- results -------------------------------------------------------------------------------------------
    @property
    def game(self) -> dict | None:
        """Per-team command, score, stage and clock, where a referee judges a game."""
        return self.judge.game()

    def state_digest(self) -> str:
        return self.simulator.digest()

    def result(self) -> dict:
        """The object ``simatch run --json`` prints."""
        wall = self._wall
        return {
            "scene": self.scene.name,
            "seed": self.seed,
            "sim_seconds": round(self.time, 6),
            "wall_seconds": round(wall, 6),
            "rtf": round(self.time / wall, 3) if wall > 0 else None,
            "state_digest": self.state_digest(),
            "result": self.judge.result(),
            "events": self.events,
        }

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self.clock.close()
        self._sub_events.close()
        self.bus.close()

    def __enter__(self) -> Simulation:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
