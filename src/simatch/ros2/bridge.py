"""The bridge process (``simatch ros2``): a run's robots, world and game on the ROS 2 graph.

It joins a run as simatch's own processes do (docs/distributed.md), so the server treats it like any other:

* **driving** robots (``team`` and, optionally, ``robots``): it is that team's (or those robots') process,
  a `TeamProcess` whose nodes are `RosRobotNode` instead of a strategy. At each control tick a robot's
  perception goes to ROS (odom, ball, obstacles, team-mates, omni_vision) and the newest ``cmd_vel`` /
  dribble / kick from ROS goes to the simulator as VelCmd / ActionCmd, signed with the team's credential:
  the server's fair play, the simulator's checks (a NaN command is refused and counted) and its watchdog
  apply as to any process. In lockstep, ``wait_answers`` makes each tick wait (up to that many wall seconds)
  for a new ``cmd_vel`` of every driven robot: a ROS team whose nodes answer every odom with one cmd_vel then
  plays a deterministic match;
* **observing** (the organiser's ``admin`` credential): the ground truth (``/tf`` of every robot and the
  ball, markers, model states, odom of the robots it does not drive), the game state, every team's game
  commands, the events, and the privileged ``set_model_state`` topic;
* always ``/clock`` (simulated time) and its team's game commands.

rclpy runs in this process only (`graph.RosGraph`, its executors in threads of their own); the simulation's
process never loads it.
"""

from __future__ import annotations

import logging
import os
import queue
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from pathlib import Path

from .. import msgs
from ..bus import Node, NodeContext, Phase, topics
from ..bus.zenoh_bus import DEFAULT_ENDPOINT, ZenohBus
from ..distributed import credentials, protocol
from ..distributed.client import ClientError, TeamProcess
from ..distributed.connect import ConnectError, open_server_session
from ..sim.simulator import MAX_COMMAND_SPEED, MAX_COMMAND_TURN
from . import names
from .convert import model_poses, robot_pose

log = logging.getLogger(__name__)

#: how long a driven robot keeps its last cmd_vel without a new one [simulated s] (then the simulator's
#: watchdog stops it, as ROS base controllers stop on a cmd_vel timeout)
COMMAND_TIMEOUT = 0.5

#: the GIL's switch interval of a driving bridge's process [s] (Python's default: 5 ms): a cmd_vel that
#: arrives while another thread runs Python (a tick's answer, its messages to ROS) waits for the GIL at most
#: about this long before the command's thread gets it
SWITCH_INTERVAL = 0.0005


def _stderr(text: str) -> None:
    print(f"simatch ros2: {text}", file=sys.stderr, flush=True)


def _f32s(*values: float) -> list[float]:
    return [msgs.f32(v) for v in values]


class RosRobotNode(Node):
    """A robot driven from ROS: perception out to ROS, the newest ROS commands in, every control tick."""

    phase = Phase.ROBOT

    def __init__(self, bridge: Bridge, team: str, rid: int, period: float):
        self.bridge = bridge
        self.team, self.rid = team, rid
        self.name = f"{team}/{rid}/ros2"
        self.period = period
        self.ports = bridge.graph.add_robot(team, rid, driven=True)
        self.tick_no = 0
        self.seen = 0  # the cmd_vel version the last tick saw
        self.expects_answer = False

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        bus = ctx.bus
        self.sub = bus.subscribe(
            topics.robot_topic(self.team, self.rid, topics.OMNI_VISION), msgs.OmniVisionInfo, self._on_vision
        )
        # express: a command sent between ticks leaves from the executor's thread, without waking Zenoh's own
        self.pub_vel = bus.publisher(topics.robot_topic(self.team, self.rid, topics.VEL_CMD), msgs.VelCmd, express=True)
        self.pub_action = bus.publisher(topics.robot_topic(self.team, self.rid, topics.ACTION_CMD), msgs.ActionCmd)
        # in a real-time run a cmd_vel is sent on as it arrives (the server applies it at its next physics
        # step), not held until the next control tick: ROS commands then reach the simulator as quickly as
        # a simatch team's; in lockstep the tick sends it, so that the match stays deterministic
        self.ports.command.on_velocity = self._forward_velocity

    def _on_vision(self, info) -> None:
        self.tick_no = int(info.tick)
        graph = self.bridge.graph
        graph.set_time(info.stamp)
        sign = self.bridge.signs[self.team]  # the team frame of now: it turns when the teams change ends
        self.bridge.to_ros(graph.publish_perception, self.ports, sign, info)
        me = next((r for r in info.robots if r.id == self.rid), None)
        #: an odom went out this tick: with --wait-answers, a cmd_vel is waited for (not from a robot sent off)
        self.expects_answer = me is not None and me.valid
        if self.expects_answer:
            self.bridge.own_poses[f"{self.team}/{self.rid}"] = robot_pose(sign, me)

    def _forward_velocity(self) -> None:
        """The new cmd_vel onto the bus at once (the cmd_vel executor's thread), when the run is real time."""
        bridge = self.bridge
        proc = bridge.proc
        if proc is None or proc.mode == protocol.LOCKSTEP:
            return

        def send() -> None:
            vel, now = bridge.graph.take_velocity(self.ports.command, bridge.command_timeout)
            if vel is not None:
                self._send_velocity(now, vel)

        proc.between_ticks(send)

    def _send_velocity(self, now: float, vel: tuple) -> None:
        vx, vy, w, vz = _f32s(*vel)
        self.pub_vel.put(msgs.VelCmd(stamp=now, tick=self.tick_no, vx=vx, vy=vy, w=w, vz=vz))

    def tick(self, now: float) -> None:
        bridge, graph, slot = self.bridge, self.bridge.graph, self.ports.command
        bridge.before_robot_ticks(now)
        vel, dribble, kick, lob = graph.take(slot, now, bridge.command_timeout)
        self.seen = slot.version
        if vel is None:  # no command: nothing is sent, the simulator's watchdog stops the robot
            return
        self._send_velocity(now, vel)
        self.pub_action.put(
            msgs.new(
                msgs.ActionCmd,
                stamp=now,
                tick=self.tick_no,
                dribble=bool(dribble),
                kick_speed=msgs.f32(kick),
                kick_type=msgs.ActionCmd.KICK_LOB if lob else msgs.ActionCmd.KICK_GROUND,
            )
        )

    def stop(self) -> None:
        sub = getattr(self, "sub", None)
        if sub is not None:
            sub.close()


class RosTeamProcess(TeamProcess):
    """The bridge's team (or robot) process: `TeamProcess` with ROS-driven nodes in place of a strategy."""

    runs_strategy = False

    def __init__(self, bridge: Bridge, team: str, robots: Sequence[int] | None, **kwargs):
        super().__init__(team, robots, **kwargs)
        self.bridge = bridge

    def nodes(self) -> list:
        scene = self.scene
        if self.bridge.graph is None:  # the ROS side first: the nodes create their topics on it
            self.bridge._graph(scene)
        spec = scene.spec
        ids = self.robots if self.robots is not None else spec.teams[self.team].robot_ids()
        nodes = [RosRobotNode(self.bridge, self.team, rid, spec.control.period) for rid in ids]
        self.bridge.ros_nodes = nodes
        return nodes

    def _answer(self) -> None:
        super()._answer()
        self.bridge.publish_held()
        self.bridge.flush_requests()

    def between_ticks(self, send: Callable[[], None]) -> None:
        """Run ``send`` (which puts on the bus) from another thread than the bus's, one at a time with the
        ticks' answers, while the process is joined."""
        with self._delivering:
            if self.bus is not None and self.joined and not self.ended:
                send()


class Bridge:
    """``simatch ros2``: see the module's text. ``team``/``robots``: what it drives (None: nothing, an
    observer); ``key``: the credential (default: the admin's for an observer, the team's otherwise, from the
    run's credentials folder on this machine); ``world``: publish the ground truth (needs admin; default: when
    the credential is admin)."""

    def __init__(
        self,
        *,
        connect: str = DEFAULT_ENDPOINT,
        run: str = "default",
        key: str | Path | None = None,
        team: str | None = None,
        robots: Sequence[int] | None = None,
        world: bool | None = None,
        wait_answers: float = 0.0,
        command_timeout: float = COMMAND_TIMEOUT,
        markers_period: float = 0.05,
        clock: bool = True,
        wait: float = 30.0,
        say: Callable[[str], None] = _stderr,
    ):
        if robots is not None and team is None:
            raise ValueError("robots are given with their team")
        self.connect, self.run_name = connect, run
        self.team, self.robots = team, list(robots) if robots is not None else None
        default_key = credentials.ADMIN if team is None else team
        self.key = Path(key) if key else credentials.default_dir(run) / f"{default_key}.key"
        if team is None and key is None:
            self.key = credentials.default_dir(run) / f"{credentials.ADMIN}.key"
        self.world = world
        self.wait_answers = float(wait_answers)
        self.command_timeout = float(command_timeout)
        self.markers_period = markers_period
        self.clock = clock
        self.wait = wait
        self.say = say
        self.graph = None
        self.proc: RosTeamProcess | None = None
        self.bus: ZenohBus | None = None
        self.own_poses: dict = {}
        #: each team's frame now (+1: the world frame, the team attacks +x; -1: turned by pi), from the scene at
        #: start, then from the game state's ``attacks``: the teams change ends at half time (docs/referee.md)
        self.signs: dict[str, int] = {}
        self._requests: queue.SimpleQueue = queue.SimpleQueue()
        #: what a real-time tick's answer has for ROS, published once the answer has let go of the bus (`to_ros`)
        self._held: deque = deque()
        self._publishing = threading.Lock()  # one thread at a time publishes what was held, in order
        self._pub_set_model = None
        self.ros_nodes: list[RosRobotNode] = []
        self._models_at = -1.0
        self.observing = False
        self.mode = protocol.LOCKSTEP
        self.offer: dict = {}
        self._waited_at: float | None = None
        self.ended: str | None = None
        self._server_lost_at: float | None = None
        self._stop: BaseException | None = None
        self._switch_interval: float | None = None  # the process's own, while this bridge drives robots

    # --- what the robot nodes call --------------------------------------------------------------------------------
    def before_robot_ticks(self, now: float) -> None:
        """Once per tick, before the driven robots take their commands: in lockstep with ``wait_answers``, wait
        for a new cmd_vel of every driven robot (the perception of this tick went out when it was delivered)."""
        if self._waited_at == now:
            return
        self._waited_at = now
        if self.wait_answers > 0 and self.proc is not None and self.proc.mode == protocol.LOCKSTEP:
            waiting = [(n.ports.command, n.seen) for n in self.ros_nodes if n.expects_answer]
            self.graph.wait_for_commands(waiting, self.wait_answers)
        if self.own_poses and not self.observing:
            self.to_ros(self.graph.publish_own_frames, now, dict(self.own_poses))

    def to_ros(self, publish: Callable[..., None], *args) -> None:
        """``publish(*args)`` (something for ROS), at once or, when a real-time run's tick is being answered,
        once the answer has let go of the process's bus (`publish_held`): making and publishing rclpy
        messages takes milliseconds, and a ``cmd_vel`` sent on between ticks (`RosRobotNode._forward_velocity`)
        waits for the bus meanwhile. In lockstep everything is published at once, before the tick's commands
        are taken (what ``wait_answers`` waits for answers to)."""
        if self.proc is not None and self.proc.mode != protocol.LOCKSTEP:
            self._held.append((publish, args))
        else:
            publish(*args)

    def publish_held(self) -> None:
        """Publish what `to_ros` held, oldest first (from whichever thread answered the tick)."""
        held = self._held
        with self._publishing:
            while held:
                publish, args = held.popleft()
                try:
                    publish(*args)
                except Exception as exc:  # what ROS could not take (as the bus's delivery, never a stop)
                    log.warning("not published to ROS 2 (%s): %s", getattr(publish, "__name__", publish), exc)

    def flush_requests(self) -> None:
        """Send what ROS asked for meanwhile (set_model_state), from the thread that owns the bus."""
        bus = self.proc.bus if self.proc is not None else self.bus
        while True:
            try:
                req = self._requests.get_nowait()
            except queue.Empty:
                return
            if bus is not None and self._pub_set_model is not None:
                self._pub_set_model.put(req)

    # --- running -----------------------------------------------------------------------------------------------------
    def run(self) -> str:
        """Join the run, bridge it until it ends (returns the server's reason); ClientError if it cannot."""
        self.open()
        try:
            return self.serve()
        finally:
            self.close()

    def open(self) -> None:
        cred = self._credential()
        admin = cred.name == credentials.ADMIN
        if self.world and not admin:
            raise ClientError(
                f"the ground truth (--world) needs the organiser's {credentials.ADMIN} credential, not {cred.name}'s"
            )
        self.observing = admin if self.world is None else bool(self.world)
        if self.team is not None:
            names.check_team(self.team)
            self._switch_interval = sys.getswitchinterval()
            sys.setswitchinterval(SWITCH_INTERVAL)
            self.proc = RosTeamProcess(
                self,
                self.team,
                self.robots,
                connect=self.connect,
                run=self.run_name,
                key=self.key,
                wait=self.wait,
                say=self.say,
            )
            self.proc.open()  # builds the ROS side (`RosTeamProcess.nodes`)
            self.mode = self.proc.mode
            bus = self.proc.bus
        else:
            bus = self.bus = self._observer_bus(cred)
            self._graph(self._ask_scene(bus))
        self._subscribe(bus)

    def _credential(self) -> credentials.Credential:
        try:
            return credentials.await_file(self.key, self.wait)
        except credentials.CredentialError as exc:
            raise ClientError(str(exc)) from None

    def _ask_scene(self, bus: ZenohBus):
        deadline = time.monotonic() + self.wait
        while True:
            for ok, payload in bus.query(protocol.SCENE, b"{}", timeout=2.0):
                if ok:
                    offer = protocol.loads(payload, "scene", "seed")
                    self.mode = offer.get("mode", protocol.LOCKSTEP)
                    self.offer = offer
                    return protocol.scene_from_offer(offer)
            if time.monotonic() >= deadline:
                raise ClientError(f"no simatch server for run {self.run_name!r} answers at {self.connect}")
            time.sleep(0.2)

    def _observer_bus(self, cred) -> ZenohBus:
        try:
            session = open_server_session(cred, self.connect, self.key, self.wait, say=self.say)
        except ConnectError as exc:
            raise ClientError(str(exc)) from None
        return ZenohBus(session, self.run_name, signer=cred.signer(self.run_name))

    def _graph(self, scene):
        from .graph import RosGraph  # rclpy: in this process only

        self.scene = scene
        spec = scene.spec
        for team in spec.teams:
            names.check_team(team)
        self.signs = {team: spec.team_sign(team) for team in spec.teams}
        what = self.team if self.team is not None else "observer"
        if self.robots is not None:
            what += "_" + "_".join(map(str, self.robots))
        graph = RosGraph(
            what,
            spec,
            self.signs,
            max_speed=MAX_COMMAND_SPEED,
            max_turn=MAX_COMMAND_TURN,
            markers_period=self.markers_period,
            clock=self.clock,
        )
        self.graph = graph
        return graph

    def _subscribe(self, bus: ZenohBus) -> None:
        spec, graph = self.scene.spec, self.graph
        # an embedded run's tap (`simatch.ros2.extension`) sends what an observer hears as one feed per tick
        feed = self.offer.get("ros2_feed") if self.proc is None else None
        if feed:
            bus.take_feed(feed["topic"], feed["covers"])
        bus.subscribe(topics.CLOCK, msgs.Clock, self._on_clock)
        graph.add_game_state()
        bus.subscribe(topics.GAME_STATE, msgs.GameState, self._on_game_state)
        teams = list(spec.teams) if self.observing else [self.team]
        for team in teams:
            graph.add_team(team)
            bus.subscribe(
                topics.team_topic(team, topics.RECEIVE_FROM_COACH),
                msgs.CoachInfo,
                lambda m, team=team: self.to_ros(graph.publish_coach, team, m, msgs.encode(m)),
            )
        if self.observing:
            admin = credentials.read(self.key).name == credentials.ADMIN
            self._pub_set_model = bus.publisher(topics.SET_MODEL_STATE, msgs.ModelState) if admin else None
            graph.add_world(self._requests.put if admin else None)
            for name in spec.robot_names():
                team, rid = topics.split_robot_name(name)
                graph.add_robot(team, rid, driven=False)
            bus.subscribe(topics.MODEL_STATES, msgs.ModelStates, self._on_models)
            bus.subscribe(topics.EVENTS, msgs.GameEvent, lambda m: self.to_ros(graph.publish_event, msgs.encode(m)))
        if self.proc is None:
            bus.subscribe_raw(protocol.END, self._on_end, verify=False)
            bus.watch_liveliness(protocol.SERVER_ALIVE, self._on_server)
        if feed:
            bus.declare_token(feed["ready"])
        self.say(self._summary())

    def _summary(self) -> str:
        driven = (
            f"drives {self.team}" + (f" robots {','.join(map(str, self.robots))}" if self.robots else "")
            if self.team
            else "drives nothing"
        )
        world = "publishes the ground truth" if self.observing else "publishes its team's view"
        domain = os.environ.get("ROS_DOMAIN_ID", "0")
        return f"bridge of run {self.run_name!r} at {self.connect} on ROS 2 domain {domain}: {driven}, {world}"

    def _on_game_state(self, m) -> None:
        """Forward the game state; when the teams changed ends, turn their frames: the perception is in the new
        team frame from the next observation on (the server sends this game state before it), so odom, ball,
        obstacles and team-mates stay right in ``map``, and ``<team>/field`` on /tf_static turns."""
        changed = False
        for team, side in zip(m.teams, m.attacks):
            sign = {"+x": 1, "-x": -1}.get(side)
            if sign is not None and team in self.signs and self.signs[team] != sign:
                self.signs[team] = sign
                changed = True
        if changed:
            self.to_ros(self.graph.set_team_signs, dict(self.signs))
        self.to_ros(self.graph.publish_game_state, msgs.encode(m))

    def _on_clock(self, m) -> None:
        self.graph.set_time(m.stamp)
        self.to_ros(self.graph.publish_clock, m.stamp)

    def _on_models(self, m) -> None:
        # the server sends them every physics step; ROS gets them once per control period
        if m.stamp - self._models_at < self.scene.spec.control.period - 1e-9:
            return
        self._models_at = m.stamp
        poses = model_poses(m.name, m.pose, m.twist)
        graph = self.graph
        graph.set_time(m.stamp)
        self.to_ros(graph.publish_ground_truth, m.stamp, poses)
        if graph.heard(graph.pub_models):
            self.to_ros(graph.publish_models, msgs.encode(m))

    def _on_end(self, topic, payload, attachment, arrival) -> None:
        try:
            self.ended = str(protocol.loads(payload, "reason")["reason"])
        except protocol.ProtocolError:
            self.ended = "ended"

    def _on_server(self, topic: str, alive: bool) -> None:
        self._server_lost_at = None if alive else time.monotonic()

    def stop_soon(self, exc: BaseException) -> bool:
        if self.proc is not None:
            return self.proc.stop_soon(exc)
        if self._stop is not None:
            return False
        self._stop = exc
        return True

    def serve(self) -> str:
        if self.proc is not None:
            return self.proc.serve()
        bus = self.bus
        while not self.ended:
            bus.pump(0.1)
            self.flush_requests()
            if self._stop is not None:
                raise self._stop
            lost = self._server_lost_at
            if lost is not None and time.monotonic() - lost > 5.0:
                raise ClientError(f"lost the server at {self.connect}")
        return self.ended

    def stats(self) -> dict:
        """Commands received from ROS, refused (bad) and malformed, per driven robot."""
        out = {}
        if self.graph is not None:
            for name, ports in self.graph.robots.items():
                if ports.driven:
                    c = ports.command
                    out[name] = {"received": c.received, "bad": c.bad, "malformed": c.malformed}
        return out

    def close(self) -> None:
        try:
            if self.proc is not None:
                self.proc.close()
            if self.bus is not None:
                self.bus.close()
                self.bus = None
        finally:
            if self.graph is not None:
                self.graph.close()
            if self._switch_interval is not None:
                sys.setswitchinterval(self._switch_interval)
                self._switch_interval = None
