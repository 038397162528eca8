"""The ROS 2 side of the bridge: one rclpy node, its publishers and subscriptions, spun in a thread of its own;
a driving bridge's ``cmd_vel`` subscriptions on a second node with an executor and a thread of their own
(`RosGraph._commands`).

Imported only in the bridge's process (`simatch ros2`): it imports rclpy, whose shared libraries the ``ros2``
extra's wheels put on ``LD_LIBRARY_PATH`` when this Python starts (their ``ros_wheels_bootstrapper``).

Quality of service, as ROS 2 simulators and drivers choose it:

* commands in (``cmd_vel``, ``dribble``, ``kick``, ``lob``, ``action_cmd``, ``set_model_state``): reliable,
  keep last 10 (ROS 2's default: what ``ros2 topic pub`` and a plain publisher offer);
* game state and commands (``match_mode``, ``match_type``, ``coach``, ``game_state``): reliable and
  transient local, keep last 1: a node that starts late still gets the current command;
* high-rate state (``odom``, the perception, ``model_states``) and ``/clock``: reliable, keep last 5 (``/clock``
  keep last 1), as Gazebo's ROS 2 plugins publish: a reliable publisher is matched by both kinds of
  subscriber, the default (reliable, ``create_subscription(T, topic, cb, 10)``) and the sensor-data profile
  (best effort, ``qos_profile_sensor_data``) that a ``use_sim_time`` node's clock uses; a best-effort one
  would leave a default subscriber with nothing (DDS does not match a reliable reader to a best-effort
  writer). Keep-last history means a slow subscriber never holds the bridge back: the writer drops what it
  no longer keeps;
* ``/tf`` reliable, keep last 100 and ``/tf_static`` reliable transient local (tf2's own profiles), markers
  reliable keep last 1 (RViz's default subscription).
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import rclpy
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Pose, PoseArray, TransformStamped, Twist
from nav_msgs.msg import Odometry
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Bool, Float32, UInt8
from visualization_msgs.msg import MarkerArray

from .. import msgs
from . import markers, names
from .convert import WorldPose, is_bad_velocity, quaternion_of_yaw, robot_pose, stamp_of, velocity_of_twist, world_pose

log = logging.getLogger(__name__)

try:  # built by `simatch ros2 --build-interfaces` (simatch.ros2.interfaces)
    import simatch_msgs.msg as _smsg
except ImportError:  # the standard types alone
    _smsg = None
try:
    from tf2_msgs.msg import TFMessage
except ImportError:
    TFMessage = None

COMMANDS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE, history=HistoryPolicy.KEEP_LAST)
LATCHED = QoSProfile(
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
    history=HistoryPolicy.KEEP_LAST,
)
SENSOR = QoSProfile(depth=5, reliability=ReliabilityPolicy.RELIABLE, history=HistoryPolicy.KEEP_LAST)
CLOCK = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, history=HistoryPolicy.KEEP_LAST)
TF = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE, history=HistoryPolicy.KEEP_LAST)
MARKERS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, history=HistoryPolicy.KEEP_LAST)


def has_simatch_msgs() -> bool:
    return _smsg is not None


def _time(seconds: float) -> Time:
    sec, nsec = stamp_of(seconds)
    return Time(sec=sec, nanosec=nsec)


@dataclass
class CommandSlot:
    """What ROS said last for one robot, written by the executor's thread and read at the run's ticks."""

    vx: float = 0.0
    vy: float = 0.0
    w: float = 0.0
    vz: float = 0.0  # an aerial robot's upward speed (cmd_vel's linear.z)
    vel_at: float | None = None  # simulated time of the bridge when the last cmd_vel arrived (None: none yet)
    vel_bad: bool = False  # the last cmd_vel is one the simulator refuses: passed on once, then not repeated
    vel_sent: bool = False
    version: int = 0  # cmd_vel messages so far
    dribble: bool = False
    kick: float = 0.0  # a kick request waiting for the next tick [m/s]
    lob: bool = False
    received: int = 0
    bad: int = 0
    malformed: int = 0
    #: called (in the executor's thread, outside the graph's lock) after each new cmd_vel: the bridge sends
    #: it on at once in a real-time run instead of at the next control tick
    on_velocity: Callable[[], None] | None = None


@dataclass
class RobotPorts:
    team: str
    rid: int
    driven: bool
    odom: object = None
    ball: object = None
    obstacles: object = None
    teammates: object = None
    holding: object = None
    vision: object = None
    command: CommandSlot = field(default_factory=CommandSlot)


class RosGraph:
    """One rclpy node in its own context, spun by a thread of its own."""

    def __init__(
        self,
        what: str,
        spec,
        signs: dict[str, int],
        *,
        max_speed: float,
        max_turn: float,
        markers_period: float = 0.05,
        clock: bool = True,
    ):
        """``signs``: each team's frame (+1 the world's, -1 turned by pi; `set_team_signs` when they change);
        ``clock``: publish /clock (one publisher per ROS domain: a second bridge on the same graph leaves it to
        the first, see docs/ros.md)."""
        self.spec = spec
        self.signs = dict(signs)
        self.max_speed, self.max_turn = max_speed, max_turn
        self.context = rclpy.Context()
        rclpy.init(context=self.context, args=[])
        self.node = rclpy.create_node(names.node_name(what), context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._what = what
        self.command_node = None  # the cmd_vel subscriptions' node, with the first driven robot (`_commands`)
        self.command_executor = None
        self.now = 0.0  # simulated time of the newest clock or tick
        self._cond = threading.Condition()
        self.robots: dict[str, RobotPorts] = {}
        self.markers_period = markers_period
        self._listeners: dict = {}  # publisher -> (when looked up, anybody subscribed)
        self._markers_at = -math.inf
        self._field_markers = markers.field(spec)
        n = self.node
        self.pub_clock = n.create_publisher(Clock, names.CLOCK, CLOCK) if clock else None
        self.pub_tf = n.create_publisher(TFMessage, names.TF, TF) if TFMessage is not None else None
        self.pub_tf_static = n.create_publisher(TFMessage, names.TF_STATIC, LATCHED) if TFMessage is not None else None
        self.pub_markers = None
        self.pub_models = None
        self.pub_game = None
        self.pub_events = None
        self.team_pubs: dict[str, tuple] = {}
        self.malformed = 0
        self._threads: list[threading.Thread] = []
        self._start(self.executor, "rclpy-executor")
        self._static_frames()

    def _start(self, executor, name: str) -> None:
        thread = threading.Thread(target=self._spin, args=(executor,), name=name, daemon=True)
        self._threads.append(thread)
        thread.start()

    @staticmethod
    def _spin(executor) -> None:
        try:
            executor.spin()
        except (ExternalShutdownException, rclpy.executors.ShutdownException):
            pass
        except Exception:  # keep the bridge's own thread informed through the log
            log.exception("the ROS 2 executor stopped")

    def _commands(self):
        """The node of the cmd_vel subscriptions, spun by an executor and a thread of their own: an rclpy
        executor builds its wait set in Python from every entity of its nodes at each wake-up (on the main
        node, its publishers, subscriptions and their QoS event handlers: milliseconds of the GIL), so a
        command waits far less on a node that has only them. Named as the bridge's node, with
        ``names.COMMANDS_SUFFIX``."""
        if self.command_node is None:
            self.command_node = rclpy.create_node(
                names.node_name(self._what) + names.COMMANDS_SUFFIX,
                context=self.context,
                start_parameter_services=False,
            )
            self.command_executor = SingleThreadedExecutor(context=self.context)
            self.command_executor.add_node(self.command_node)
            self._start(self.command_executor, "rclpy-commands")
        return self.command_node

    # --- set-up ------------------------------------------------------------------------------------------------
    def add_world(self, set_model_state: Callable[[object], None] | None) -> None:
        """The observer's topics: markers, model states, the game's state and events; with
        ``set_model_state`` (the organiser's credential), the privileged request topic."""
        n = self.node
        self.pub_markers = n.create_publisher(MarkerArray, names.MARKERS, MARKERS)
        if _smsg is not None:
            self.pub_models = n.create_publisher(_smsg.ModelStates, names.MODEL_STATES, SENSOR)
            self.pub_events = n.create_publisher(_smsg.GameEvent, names.EVENTS, COMMANDS)
            if set_model_state is not None:

                def on_set(raw: bytes) -> None:
                    try:
                        req = msgs.decode(msgs.ModelState, raw)
                    except msgs.MessageError as exc:
                        self.malformed += 1
                        log.warning("dropped a malformed set_model_state request: %s", exc)
                        return
                    set_model_state(req)

                n.create_subscription(_smsg.ModelState, names.SET_MODEL_STATE, on_set, COMMANDS, raw=True)
        self.add_game_state()

    def add_game_state(self) -> None:
        if self.pub_game is None and _smsg is not None:
            self.pub_game = self.node.create_publisher(_smsg.GameState, names.GAME_STATE, LATCHED)

    def add_team(self, team: str) -> None:
        if team in self.team_pubs:
            return
        n = self.node
        self.team_pubs[team] = (
            n.create_publisher(UInt8, names.team_topic(team, names.MATCH_MODE), LATCHED),
            n.create_publisher(UInt8, names.team_topic(team, names.MATCH_TYPE), LATCHED),
            n.create_publisher(_smsg.CoachInfo, names.team_topic(team, names.COACH), LATCHED) if _smsg else None,
        )

    def add_robot(self, team: str, rid: int, driven: bool) -> RobotPorts:
        """A robot's topics; a ``driven`` robot also takes commands (cmd_vel, dribble, kick, lob, action_cmd)."""
        name = f"{team}/{rid}"
        ports = self.robots.get(name)
        if ports is not None:
            return ports
        n = self.node
        topic = lambda leaf: names.robot_topic(team, rid, leaf)  # noqa: E731
        ports = RobotPorts(team, rid, driven)
        # a driven robot's odom is its perception; the observer's is the ground truth, on a topic of its own
        ports.odom = n.create_publisher(Odometry, topic(names.ODOM if driven else names.GROUND_TRUTH), SENSOR)
        if driven:
            ports.ball = n.create_publisher(Odometry, topic(names.BALL_SEEN), SENSOR)
            ports.obstacles = n.create_publisher(PoseArray, topic(names.OBSTACLES), SENSOR)
            ports.teammates = n.create_publisher(PoseArray, topic(names.TEAMMATES), SENSOR)
            ports.holding = n.create_publisher(Bool, topic(names.HOLDING_BALL), SENSOR)
            if _smsg is not None:
                ports.vision = n.create_publisher(_smsg.OmniVisionInfo, topic(names.OMNI_VISION), SENSOR)
            slot = ports.command
            self._commands().create_subscription(
                Twist, topic(names.CMD_VEL), lambda m: self._on_cmd_vel(slot, m), COMMANDS
            )
            n.create_subscription(Bool, topic(names.DRIBBLE), lambda m: self._on_dribble(slot, m), COMMANDS)
            n.create_subscription(Float32, topic(names.KICK), lambda m: self._on_kick(slot, m, False), COMMANDS)
            n.create_subscription(Float32, topic(names.LOB), lambda m: self._on_kick(slot, m, True), COMMANDS)
            if _smsg is not None:
                n.create_subscription(
                    _smsg.ActionCmd, topic(names.ACTION_CMD), lambda raw: self._on_action(slot, raw), COMMANDS, raw=True
                )
        self.robots[name] = ports
        return ports

    def set_team_signs(self, signs: dict[str, int]) -> None:
        """The teams changed ends: their frames on /tf_static from now on (the newest message replaces the
        last one for late subscribers too: transient local, keep last 1)."""
        self.signs = dict(signs)
        self._static_frames(self.now)

    def _static_frames(self, at: float = 0.0) -> None:
        """``map`` -> ``<team>/field`` for every team: each team's own frame, turned by pi for a team attacking -x."""
        if self.pub_tf_static is None:
            return
        out = []
        for team in self.spec.teams:
            t = TransformStamped()
            t.header.stamp = _time(at)
            t.header.frame_id = names.MAP
            t.child_frame_id = names.team_frame(team)
            qx, qy, qz, qw = quaternion_of_yaw(0.0 if self.signs[team] > 0 else math.pi)
            t.transform.rotation.x, t.transform.rotation.y = qx, qy
            t.transform.rotation.z, t.transform.rotation.w = qz, qw
            out.append(t)
        self.pub_tf_static.publish(TFMessage(transforms=out))

    # --- commands from ROS (the executor's thread) ---------------------------------------------------------------
    def _on_cmd_vel(self, slot: CommandSlot, m) -> None:
        vx, vy, w, vz = velocity_of_twist(m)
        bad = is_bad_velocity(vx, vy, w, vz, self.max_speed, self.max_turn)
        with self._cond:
            slot.vx, slot.vy, slot.w, slot.vz = vx, vy, w, vz
            slot.vel_at = self.now
            slot.vel_bad, slot.vel_sent = bad, False
            slot.version += 1
            slot.received += 1
            if bad:
                slot.bad += 1
            self._cond.notify_all()
        if slot.on_velocity is not None:
            slot.on_velocity()

    def _on_dribble(self, slot: CommandSlot, m) -> None:
        with self._cond:
            slot.dribble = bool(m.data)

    def _on_kick(self, slot: CommandSlot, m, lob: bool) -> None:
        with self._cond:
            slot.kick, slot.lob = float(m.data), lob  # the simulator refuses a bad speed (and counts it)

    def _on_action(self, slot: CommandSlot, raw: bytes) -> None:
        try:
            a = msgs.decode(msgs.ActionCmd, raw)
        except msgs.MessageError as exc:
            with self._cond:
                slot.malformed += 1
            log.warning("dropped a malformed action_cmd: %s", exc)
            return
        with self._cond:
            slot.dribble = bool(a.dribble)
            if a.kick_speed != 0.0:
                slot.kick, slot.lob = float(a.kick_speed), a.kick_type == msgs.ActionCmd.KICK_LOB

    def wait_for_commands(self, slots: list[tuple[CommandSlot, int]], timeout: float) -> bool:
        """Wait up to ``timeout`` wall seconds until every slot has a cmd_vel newer than its given version."""
        with self._cond:
            return self._cond.wait_for(lambda: all(s.version > v for s, v in slots), timeout)

    @staticmethod
    def _velocity(slot: CommandSlot, now: float, timeout: float):
        """(vx, vy, w, vz) to send at ``now``, marked sent; None when none came within ``timeout`` simulated
        seconds (the simulator's watchdog then stops the robot) or the last one was refused already. Under the
        graph's lock."""
        if slot.vel_at is None or now - slot.vel_at > timeout or (slot.vel_bad and slot.vel_sent):
            return None
        slot.vel_sent = True
        return (slot.vx, slot.vy, slot.w, slot.vz)

    def take_velocity(self, slot: CommandSlot, timeout: float):
        """(velocity or None, the bridge's newest simulated time): the velocity to send now, between ticks
        (the kick request stays for the tick)."""
        with self._cond:
            return self._velocity(slot, self.now, timeout), self.now

    def take(self, slot: CommandSlot, now: float, timeout: float):
        """The command to send at simulated time ``now``: (velocity or None, see `_velocity`; dribble, kick,
        lob), the kick request consumed."""
        with self._cond:
            vel = self._velocity(slot, now, timeout)
            kick, lob = slot.kick, slot.lob
            slot.kick = 0.0
            return vel, slot.dribble, kick, lob

    # --- state to ROS (the bridge's thread) ----------------------------------------------------------------------
    def set_time(self, t: float) -> None:
        with self._cond:
            self.now = max(self.now, float(t))

    def publish_clock(self, t: float) -> None:
        if self.pub_clock is not None:
            self.pub_clock.publish(Clock(clock=_time(t)))

    def publish_perception(self, ports: RobotPorts, sign: int, info) -> None:
        """A robot's OmniVisionInfo (team frame) as odom, ball, obstacles, team-mates (``map``), holding_ball
        and, when simatch_msgs is built, the message itself (``omni_vision``, team frame as on the bus)."""
        stamp = _time(info.stamp)
        heard = self.heard
        me = next((r for r in info.robots if r.id == ports.rid), None)
        if me is not None and me.valid and heard(ports.odom):
            self._odom(ports.odom, stamp, names.base_link(ports.team, ports.rid), robot_pose(sign, me))
        if me is not None and heard(ports.holding):
            ports.holding.publish(Bool(data=bool(me.holding_ball)))
        ball = info.ball
        if ball.pos_known and heard(ports.ball):
            p = world_pose(sign, ball.x, ball.y, 0.0, ball.vx, ball.vy, 0.0, ball.z, ball.vz)
            self._odom(ports.ball, stamp, names.BALL, p, body=False)
        if heard(ports.obstacles):
            obs = info.obstacles
            heights = obs.z if len(obs.z) == len(obs.x) else [0.0] * len(obs.x)  # none from an older sender
            poses = [world_pose(sign, x, y, 0.0, z=z) for x, y, z in zip(obs.x, obs.y, heights)]
            ports.obstacles.publish(self._poses(stamp, poses))
        if heard(ports.teammates):
            mates = [robot_pose(sign, r) for r in info.robots if r.id != ports.rid and r.valid]
            ports.teammates.publish(self._poses(stamp, mates))
        if heard(ports.vision):
            ports.vision.publish(msgs.encode(info))

    def heard(self, pub) -> bool:
        """Somebody subscribes to ``pub`` (looked up at most twice a second of wall time per publisher): what
        nobody listens to is not built (making and sending rclpy messages is most of the bridge's work)."""
        if pub is None:
            return False
        now = time.monotonic()
        known = self._listeners.get(pub)
        if known is None or now - known[0] >= 0.5:
            known = self._listeners[pub] = (now, pub.get_subscription_count() > 0)
        return known[1]

    def publish_ground_truth(self, t: float, poses: dict[str, WorldPose]) -> None:
        """Every model's true pose: /tf (map -> each base_link, map -> ball), each robot's ``ground_truth``
        odometry, and the markers (at most every ``markers_period`` simulated seconds). Heights are the
        poses' own: the ball's centre, an aerial robot's altitude, 0 for a ground robot."""
        stamp = _time(t)
        tfs = []
        for name, p in poses.items():
            if name == names.BALL:
                child = names.BALL
            else:
                team, _, rid = name.partition("/")
                child = names.base_link(team, int(rid))
                ports = self.robots.get(name)
                if ports is not None and not ports.driven and self.heard(ports.odom):
                    self._odom(ports.odom, stamp, child, p)
            tfs.append(self._transform(stamp, child, p))
        if self.heard(self.pub_tf):
            self.pub_tf.publish(TFMessage(transforms=tfs))
        if self.heard(self.pub_markers) and t - self._markers_at >= self.markers_period - 1e-9:
            self._markers_at = t
            self.pub_markers.publish(markers.markers(self.spec, self._field_markers, stamp, poses))

    def publish_own_frames(self, t: float, poses: dict[str, WorldPose]) -> None:
        """/tf of the robots a team bridge perceives itself (no ground truth for a team's credential)."""
        if not poses or not self.heard(self.pub_tf):
            return
        stamp = _time(t)
        tfs = []
        for name, p in poses.items():
            team, _, rid = name.partition("/")
            tfs.append(self._transform(stamp, names.base_link(team, int(rid)), p))
        self.pub_tf.publish(TFMessage(transforms=tfs))

    def publish_models(self, raw: bytes) -> None:
        if self.heard(self.pub_models):
            self.pub_models.publish(raw)

    def publish_coach(self, team: str, info, raw: bytes) -> None:
        pubs = self.team_pubs.get(team)
        if pubs is None:
            return
        mode, mtype, coach = pubs
        mode.publish(UInt8(data=int(info.match_mode)))
        mtype.publish(UInt8(data=int(info.match_type)))
        if coach is not None:
            coach.publish(raw)

    def publish_game_state(self, raw: bytes) -> None:
        if self.pub_game is not None:
            self.pub_game.publish(raw)

    def publish_event(self, raw: bytes) -> None:
        if self.pub_events is not None:
            self.pub_events.publish(raw)

    # --- building messages ---------------------------------------------------------------------------------------
    @staticmethod
    def _odom(pub, stamp, child: str, p: WorldPose, body: bool = True) -> None:
        m = Odometry()
        m.header.stamp = stamp
        m.header.frame_id = names.MAP
        m.child_frame_id = child
        pose = m.pose.pose
        pose.position.x, pose.position.y, pose.position.z = p.x, p.y, p.z
        qx, qy, qz, qw = quaternion_of_yaw(p.yaw)
        pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = qx, qy, qz, qw
        vx, vy, w = p.body_twist() if body else (p.vx, p.vy, p.w)
        lin = m.twist.twist.linear
        lin.x, lin.y, lin.z, m.twist.twist.angular.z = vx, vy, p.vz, w
        pub.publish(m)

    @staticmethod
    def _transform(stamp, child: str, p: WorldPose) -> TransformStamped:
        t = TransformStamped()
        t.header.stamp = stamp
        t.header.frame_id = names.MAP
        t.child_frame_id = child
        tr = t.transform
        tr.translation.x, tr.translation.y, tr.translation.z = p.x, p.y, p.z
        tr.rotation.x, tr.rotation.y, tr.rotation.z, tr.rotation.w = quaternion_of_yaw(p.yaw)
        return t

    @staticmethod
    def _poses(stamp, poses: list[WorldPose]) -> PoseArray:
        out = PoseArray()
        out.header.stamp = stamp
        out.header.frame_id = names.MAP
        for p in poses:
            q = Pose()
            q.position.x, q.position.y, q.position.z = p.x, p.y, p.z
            q.orientation.x, q.orientation.y, q.orientation.z, q.orientation.w = quaternion_of_yaw(p.yaw)
            out.poses.append(q)
        return out

    # --- closing -------------------------------------------------------------------------------------------------
    def close(self) -> None:
        for executor in (self.command_executor, self.executor):
            try:
                if executor is not None:
                    executor.shutdown(timeout_sec=1.0)
            except Exception:  # shutting down twice, or a context already gone
                pass
        try:
            if self.command_node is not None:
                self.command_node.destroy_node()
            self.node.destroy_node()
        finally:
            if self.context.ok():
                rclpy.shutdown(context=self.context)
        for thread in self._threads:
            thread.join(timeout=2.0)
