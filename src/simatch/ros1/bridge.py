"""The bridge: simatch's bus on one side, a ROS 1 master on the other, speaking the original's interface.

`RosBridge` is one bus `Node` (ROBOT phase, every physics step). It joins a run where a team's robot nodes
would: embedded (`simatch run ... --ros1`, `simatch.ros1.embedded`) or in a team process of a distributed
run (`simatch ros1 --connect ...`, `simatch.ros1.client`). It adapts the existing nodes' messages and
simulates nothing: perception, game commands and the world come from the simulator and the referee, and
what ROS sends goes to the simulator as any team's commands (checked and counted there).

At every control tick, for every robot it serves, it publishes on ROS (in this order) ``/clock`` (so
simulated time on ROS advances a control period at a time: every node subscribes to it, and a clock at
the physics rate would be most of what the bridge sends), each
team's ``receive_from_coach`` (CoachInfo, every tick, stamped with the tick's simulated time), the relayed
``nubotcontrol/strategy`` (simulation_strategy), ``redcard/chatter`` when a robot is sent off or back,
then per robot ``ballisholding/BallIsHolding`` and ``omnivision/OmniVisionInfo`` (stamped likewise).

**Lockstep.** The bridge then waits, as a team process does, for each driven robot's answer to that tick:
a ``velcmd``, and an ``actioncmd`` / ``strategy`` too for a robot whose nodes sent one in each of the last
`LEARN` ticks (a node that answers every tick is waited for on every topic it answers on; one that
publishes on a timer of its own is not waited for beyond its velcmd). Everything received up to then
goes to the simulator, robots in scene order, each robot's messages in the order they came. A robot that
does not answer within ``answer_timeout`` is *late*: not waited for until it answers again (its robot is
then stopped by the simulator's watchdog if nothing comes). So a ROS team whose nodes answer every control
tick from that tick's messages plays deterministically: the same scene and seed give the same match.

A robot whose ``velcmd`` stops (its low-level controller died) gets none of its ``actioncmd`` through
either once `VEL_SILENT` (half a second) has passed: the simulator's watchdog then stops it, as any robot
whose process died.

**Real time.** Nothing is waited for; what ROS sends goes on at the next physics step (embedded) or at
once (a team process).
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from .. import msgs
from ..bus import Node, NodeContext, Phase, topics
from ..config.schema import Scene
from . import convert
from .names import Names, Robot

log = logging.getLogger(__name__)

#: ticks in a row a robot must answer on a topic before the bridge waits for that topic in lockstep
LEARN = 3
#: the original strategy relay dropped team-mates' StrategyInfo older than this [s]
RELAY_STALE = 0.10
VEL, ACTION, STRATEGY = "velcmd", "actioncmd", "strategy"
#: no velcmd of a robot for this long [s, simulated]: its actioncmds are held back too (see `RosBridge`)
VEL_SILENT = 0.5


@dataclass
class Options:
    """What a bridge serves and how."""

    teams: Sequence[str]  # teams whose robots ROS drives (their commands are taken)
    watch: Sequence[str] = ()  # further teams whose perception and game commands are published
    world: bool = False  # /gazebo/model_states out, /gazebo/set_model_state in (the organiser's)
    lockstep: bool = True
    answer_timeout: float = 1.0  # [s] lockstep: longest wait for a robot's answer to one tick
    clock: bool = True  # publish /clock (one bridge per ROS master should)
    sim_time: bool = True  # set /use_sim_time on the master (as the original's launch did)
    strategy_relay: bool = True  # relay <r>/nubotcontrol/strategy unless the team runs its own relay
    node_name: str = "simatch_bridge"


@dataclass
class Link:
    """One driven robot: what ROS sent it since the last hand-over, and whether it is waited for."""

    robot: Robot
    pending: list = field(default_factory=list)  # (kind, simatch message) in arrival order
    answered: set = field(default_factory=set)  # kinds received in the open window
    streak: dict = field(default_factory=lambda: {VEL: 0, ACTION: 0, STRATEGY: 0})
    late: bool = False
    answers: int = 0  # windows answered (velcmd)
    last_vel: float = -1e9  # simulated time of its newest velcmd

    def expected(self) -> set:
        return {VEL} | {k for k in (ACTION, STRATEGY) if self.streak[k] >= LEARN}

    def complete(self) -> bool:
        return self.expected() <= self.answered


@dataclass
class Stats:
    forwarded: dict = field(default_factory=lambda: {VEL: 0, ACTION: 0, STRATEGY: 0})
    late: int = 0  # times a robot missed its answer deadline (lockstep)
    refused: int = 0  # requests the bridge could not turn into simatch ones (e.g. an unknown model)
    dropped: int = 0  # actioncmds of robots whose velcmd stopped (so that the simulator's watchdog stops them)
    unknown_robots: set = field(default_factory=set)  # ROS topics naming robots this bridge does not serve
    waited: list = field(default_factory=list)  # lockstep: seconds waited for the answers, per tick

    def as_dict(self) -> dict:
        out = {f"forwarded_{k}": v for k, v in self.forwarded.items()}
        out.update(
            late=self.late, refused=self.refused, dropped=self.dropped, unknown_robots=sorted(self.unknown_robots)
        )
        return out


class RosBridge(Node):
    phase = Phase.ROBOT
    name = "ros1_bridge"

    def __init__(
        self,
        spec: Scene,
        options: Options,
        *,
        set_model_state: Callable[[Any], None] | None = None,
        phase_step: int = 0,
        say: Callable[[str], None] = lambda text: log.warning("%s", text),
    ):
        """``set_model_state(msg)`` applies a simatch ModelState request (embedded: the Simulation's; None:
        publish it on the bus for the server); ``phase_step``: the physics step of the control period at which
        this process's ticks open."""
        self.spec = spec
        self.opt = options
        self.names = Names(spec)
        self.period = spec.physics.timestep
        self.control_steps = round(spec.control.period / spec.physics.timestep)
        self.phase_step = phase_step
        #: a robot whose velcmd stopped this long ago [s] gets none of its actioncmds through either: its
        #: low-level controller died, and the simulator's watchdog must stop it (an actioncmd alone would
        #: keep it commanded, driving on at its last velocity); a controller that is only slow keeps it
        self.command_timeout = max(VEL_SILENT, spec.control.command_timeout)
        self.set_model_state_fn = set_model_state
        self.say = say
        driven = set(options.teams)
        self.links = {r.name: Link(r) for r in self.names.robots if r.team in driven}
        self.shown = [r for r in self.names.robots if r.team in driven or r.team in set(options.watch)]
        self.shown_teams = [t for t in self.names.teams if t in driven or t in set(options.watch)]
        self.stats = Stats()
        self.cond = threading.Condition()
        self.window_open = False
        self.tick_index = 0
        self.stamp = 0.0  # simulated time of the newest tick
        #: real time in a team process: hand what ROS sends over at once (called in rospy's threads)
        self.forward_now: Callable[[], None] | None = None
        self.requests: list = []  # set_model_state requests (simatch ModelState) not yet applied
        self.vision: dict[str, Any] = {}  # robot -> newest OmniVisionInfo (simatch)
        self.coach: dict[str, Any] = {}  # team -> newest CoachInfo (simatch)
        self.sent_off: set[str] = set()
        self.relayed: dict[str, dict[int, tuple[float, Any]]] = {t: {} for t in options.teams}
        self.own_relay: dict[str, bool] = {t: options.strategy_relay for t in options.teams}
        self.seq = 0
        self._last_clock = -1.0
        self._model_states: Any = None
        self.ros: Any = None  # the rospy side, made by `connect_ros`

    # --- ROS ------------------------------------------------------------------------------------------------
    def connect_ros(self) -> None:
        """Register with the ROS master: publishers, subscriptions, parameters."""
        from .rosside import RosSide

        self.ros = RosSide(self)

    def wait_for_ros(self, timeout: float) -> list[str]:
        """Wait until every driven robot has a node listening to its perception and one sending it velcmd;
        returns the robots still without (after ``timeout`` seconds)."""
        return self.ros.wait_for_nodes(timeout)

    # --- the bus ----------------------------------------------------------------------------------------------
    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        bus = ctx.bus
        self.subs = []
        for r in self.shown:
            self.subs.append(
                bus.subscribe(
                    topics.robot_topic(r.team, r.rid, topics.OMNI_VISION), msgs.OmniVisionInfo, self._vision_cb(r)
                )
            )
        for team in self.shown_teams:
            self.subs.append(
                bus.subscribe(topics.team_topic(team, topics.RECEIVE_FROM_COACH), msgs.CoachInfo, self._coach_cb(team))
            )
        self.subs.append(bus.subscribe(topics.GAME_STATE, msgs.GameState, self._on_game))
        if self.opt.world:
            self.subs.append(bus.subscribe(topics.MODEL_STATES, msgs.ModelStates, self._on_models))
            self.pub_set_model = bus.publisher(topics.SET_MODEL_STATE, msgs.ModelState)
        self.pubs = {}
        for name, link in self.links.items():
            r = link.robot
            self.pubs[name] = {
                VEL: bus.publisher(topics.robot_topic(r.team, r.rid, topics.VEL_CMD), msgs.VelCmd),
                ACTION: bus.publisher(topics.robot_topic(r.team, r.rid, topics.ACTION_CMD), msgs.ActionCmd),
                STRATEGY: bus.publisher(topics.robot_topic(r.team, r.rid, topics.STRATEGY_INFO), msgs.StrategyInfo),
            }

    def _vision_cb(self, robot: Robot):
        def on_vision(msg) -> None:
            self.vision[robot.name] = msg

        return on_vision

    def _coach_cb(self, team: str):
        def on_coach(msg) -> None:
            self.coach[team] = msg

        return on_coach

    def _on_game(self, msg) -> None:
        now_off = {str(n) for n in msg.sent_off}
        if now_off != self.sent_off and self.ros is not None:
            for name in sorted(now_off ^ self.sent_off):
                robot = self.names.by_name.get(name)
                if robot is not None and robot.team in self.shown_teams:
                    self.ros.sending_off(robot, self.names.teams.index(robot.team), name in now_off)
        self.sent_off = now_off

    def _on_models(self, msg) -> None:
        if self.ros is not None:
            self.ros.model_states(msg)

    # --- ticks -------------------------------------------------------------------------------------------------
    def tick(self, now: float) -> None:
        ros = self.ros
        if ros is None:
            return
        step = self.ctx.step()
        if step % self.control_steps == self.phase_step % self.control_steps:
            if self.opt.clock and now != self._last_clock:
                ros.clock(now)
                self._last_clock = now
            self.exchange(now, step // self.control_steps)
        else:
            self.hand_over()

    def exchange(self, now: float, tick: int) -> None:
        """One control tick: everything out to ROS, then (lockstep) the robots' answers back."""
        ros = self.ros
        with self.cond:
            self.stamp, self.tick_index = now, tick
            for link in self.links.values():
                link.answered.clear()
            self.window_open = True
        self.seq += 1
        for team in self.shown_teams:
            coach = self.coach.get(team)
            if coach is not None:
                ros.coach(team, coach, self.seq, now)
        for team in self.opt.teams:
            if self.own_relay.get(team):
                ros.relay(team, convert.fresh_strategies(self.relayed[team], now, RELAY_STALE, self._goalkeepers(team)))
        for r in self.shown:
            vision = self.vision.get(r.name)
            if vision is not None:
                ros.perception(r, vision, self.seq)
        if self.opt.lockstep and self.links:
            self._await_answers()
        with self.cond:
            self.window_open = False
            for link in self.links.values():
                for kind in (VEL, ACTION, STRATEGY):
                    link.streak[kind] = link.streak[kind] + 1 if kind in link.answered else 0
        self.hand_over()

    def _goalkeepers(self, team: str) -> tuple[int, ...]:
        gk = self.spec.teams[team].goalkeeper
        return () if gk is None else (gk,)

    def _await_answers(self) -> None:
        t0 = time.monotonic()
        deadline = t0 + self.opt.answer_timeout
        with self.cond:
            while True:
                waiting = [link for link in self.links.values() if not link.late and not link.complete()]
                if not waiting:
                    break
                left = deadline - time.monotonic()
                if left <= 0:
                    for link in waiting:
                        link.late = True
                        self.stats.late += 1
                        missing = ", ".join(sorted(link.expected() - link.answered))
                        self.say(
                            f"{link.robot.ros} ({link.robot.name}) did not answer tick {self.tick_index} within "
                            f"{self.opt.answer_timeout:g} s ({missing}): not waited for until it answers again"
                        )
                    break
                self.cond.wait(left)
        self.stats.waited.append(time.monotonic() - t0)

    def hand_over(self) -> None:
        """What ROS sent since the last hand-over, onto the bus: robots in scene order, each robot's messages
        in the order they came."""
        with self.cond:
            items = []
            for name, link in self.links.items():
                if link.pending:
                    items.append((name, link.pending))
                    link.pending = []
            requests, self.requests = self.requests, []
        forwarded = self.stats.forwarded
        for name, pending in items:
            pubs = self.pubs[name]
            silent = self.stamp - self.links[name].last_vel > self.command_timeout
            for kind, msg in pending:
                if kind == ACTION and silent:
                    self.stats.dropped += 1
                    continue
                pubs[kind].put(msg)
                forwarded[kind] += 1
        for msg in requests:
            self._apply_model_state(msg)

    # --- from ROS (called in rospy's threads) ---------------------------------------------------------------
    def received(self, name: str, kind: str, ros_msg: Any) -> None:
        link = self.links[name]
        with self.cond:
            stamp, tick = self.stamp, self.tick_index
            if kind == VEL:
                msg = convert.velcmd_in(ros_msg, stamp, tick)
                link.last_vel = stamp
            elif kind == ACTION:
                msg = convert.actioncmd_in(ros_msg, stamp, tick)
            else:
                msg = convert.strategy_info_in(ros_msg, stamp, tick, link.robot.rid)
                self.relayed.get(link.robot.team, {})[link.robot.rid] = (stamp, ros_msg)
            link.pending.append((kind, msg))
            if self.window_open:
                link.answered.add(kind)
                if kind == VEL:
                    link.answers += 1
                    if link.late:
                        link.late = False
                        self.say(f"{link.robot.ros} ({link.robot.name}) answers again")
                if link.complete():
                    self.cond.notify_all()
        if self.forward_now is not None:
            self.forward_now()

    def model_state_request(self, ros_msg: Any) -> None:
        try:
            msg = convert.model_state_in(ros_msg, self.names)
        except convert.BadRequest as exc:
            self.stats.refused += 1
            self.say(f"refused: {exc}")
            return
        with self.cond:  # applied by the next hand-over, in the run's thread
            self.requests.append(msg)
        if self.forward_now is not None:
            self.forward_now()

    def _apply_model_state(self, msg) -> None:
        if self.set_model_state_fn is None:  # a team process: the server applies it if the credential may
            self.pub_set_model.put(msg)
            return
        state = {
            k: float(getattr(msg, k))
            for k in ("x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz", "qw", "qx", "qy", "qz")
        }
        if not any(state[k] for k in ("qw", "qx", "qy", "qz")):
            for k in ("qw", "qx", "qy", "qz"):
                del state[k]
        try:
            self.set_model_state_fn(msg.name, **state)
        except ValueError as exc:  # CommandError: a value the simulator refuses
            self.stats.refused += 1
            self.say(f"refused: set_model_state({msg.name!r}): {exc}")

    def unknown_robot(self, topic: str) -> None:
        if topic not in self.stats.unknown_robots:
            self.stats.unknown_robots.add(topic)
            served = ", ".join(link.robot.ros for link in self.links.values()) or "none"
            self.say(f"ROS publishes {topic}, but this bridge serves no such robot (it serves {served}): ignored")

    def stop(self) -> None:
        for sub in getattr(self, "subs", []):
            sub.close()
        if self.ros is not None:
            self.ros.shutdown()
            self.ros = None
