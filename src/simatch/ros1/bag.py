"""A recording as a ROS 1 bag with the original Simatch's topics and messages (``simatch export FILE.mcap
--format rosbag1``), so that a team replays a simatch match into its own ROS tools (``rosbag play``,
rviz, rqt_plot). No ROS installation is needed to write it: rosbags serialises the messages (ROS 1 wire
format, the same md5sums as the live bridge's) and writes the bag.

What goes in, under the names the live bridge uses (`simatch.ros1.names`):

* per robot: ``/<r>/omnivision/OmniVisionInfo`` and ``/<r>/ballisholding/BallIsHolding`` (from its
  perception), ``/<r>/nubotcontrol/velcmd``, ``/<r>/nubotcontrol/actioncmd``, ``/<r>/nubotcontrol/strategy``;
* per team: ``/<p>/receive_from_coach`` (CoachInfo), ``/<p>/nubotcontrol/strategy`` (simulation_strategy,
  from the team's StrategyPub), ``/<p>/redcard/chatter`` (when a robot is sent off or comes back);
* ``/gazebo/model_states`` (every recorded physics step) and ``/clock`` (rosgraph_msgs/Clock).

Message stamps and ``/clock`` are simulated time (from 0), as a ROS recording of a Gazebo run has them; the
bag's own record times are wall-clock times as a live recording would have (the recording's creation
time plus the simulated time), since ROS refuses record times of zero. So ``rosbag play FILE.bag`` replays
it with its own ``/clock`` (nodes with ``use_sim_time`` follow it); do not add ``--clock``.
"""

from __future__ import annotations

from collections.abc import Iterator
from datetime import datetime
from pathlib import Path
from typing import Any

from rosbags.rosbag1 import Writer, WriterError
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from ..bus import topics as T
from ..record import rosbag2
from ..record.reader import Recording
from . import convert
from . import names as N
from .names import Names
from .rosenv import MESSAGE_PACKAGES, SHARE


class BagError(ValueError):
    """The bag cannot be written (one line: why)."""


def typestore():
    """ROS 1 (Noetic) standard types plus the shipped message packages, from their .msg files."""
    store = get_typestore(Stores.ROS1_NOETIC)
    types: dict = {}
    for pkg in MESSAGE_PACKAGES:
        for path in sorted((SHARE / pkg / "msg").glob("*.msg")):
            types.update(get_types_from_msg(path.read_text(), f"{pkg}/msg/{path.stem}"))
    store.register(types)
    return store


class RosbagsKit:
    """`convert.Kit` for rosbags' classes (every field given, as its dataclasses want)."""

    def __init__(self, store):
        self.store = store
        self.types = store.types
        self.Time = self.types["builtin_interfaces/msg/Time"]
        self.Header = self.types["std_msgs/msg/Header"]

    @staticmethod
    def full(msgtype: str) -> str:
        pkg, name = msgtype.split("/")
        return f"{pkg}/msg/{name}"

    def make(self, msgtype: str, **fields: Any) -> Any:
        return self.types[self.full(msgtype)](**fields)

    def time(self, stamp: float) -> Any:
        sec, nsec = convert.stamp_ns(stamp)
        return self.Time(sec=sec, nanosec=nsec)

    def header(self, seq: int, stamp: float, frame_id: str = "") -> Any:
        return self.Header(seq=seq, stamp=self.time(stamp), frame_id=frame_id)


def export_rosbag1(path: str | Path, out: str | Path | None = None) -> tuple[Path, dict[str, int], Recording]:
    """Write the recording at ``path`` as a ROS 1 bag (default: beside it, ``.bag``); returns the bag's path,
    the number of messages per ROS topic, and the recording (its ``problems`` say what was skipped)."""
    target = Path(out) if out else rosbag2.beside(path, ".bag")
    if target.exists():  # as the table and rosbag2 exports: an earlier export or a user's file is never replaced
        raise BagError(f"{target} already exists (nothing was overwritten): remove it or give another --out FILE.bag")
    rec = Recording(path)
    spec = rec.scene().spec
    names = Names(spec)
    store = typestore()
    kit = RosbagsKit(store)
    counts: dict[str, int] = {}
    conns: dict[str, Any] = {}
    offset = _wall_start_ns(rec)
    try:
        with Writer(target) as writer:
            for topic, msgtype, t_ns, msg in _converted(rec, names, kit):
                conn = conns.get(topic)
                if conn is None:
                    conn = conns[topic] = writer.add_connection(
                        topic, kit.full(msgtype), typestore=store, callerid="/simatch"
                    )
                writer.write(conn, offset + t_ns, store.serialize_ros1(msg, kit.full(msgtype)))
                counts[topic] = counts.get(topic, 0) + 1
    except WriterError as exc:
        target.unlink(missing_ok=True)  # a half-written bag of ours: not left to be taken for a whole one
        raise BagError(f"cannot write {target}: {exc}") from None
    return target, counts, rec


def _wall_start_ns(rec: Recording) -> int:
    """When the recording began (its metadata), in ns since the epoch; 1 s if unknown."""
    try:
        return int(datetime.fromisoformat(rec.metadata["created"]).timestamp()) * 1_000_000_000
    except (KeyError, ValueError):
        return 1_000_000_000


def _converted(rec: Recording, names: Names, kit: RosbagsKit) -> Iterator[tuple[str, str, int, Any]]:
    """(ROS topic, type, log time [ns], message) for every recorded message the original interface has."""
    robots = {f"{r.team}/{r.rid}": r for r in names.robots}
    seq = 0
    sent_off: set[str] = set()
    for topic, t_ns, msg in rec.messages():
        parts = topic.split("/")
        robot = robots.get("/".join(parts[:2])) if len(parts) == 3 else None
        if robot is not None:
            leaf = parts[2]
            if leaf == T.OMNI_VISION:
                seq += 1
                yield robot.topic(N.OMNIVISION), "nubot_common/OminiVisionInfo", t_ns, convert.omnivision(kit, msg, seq)
                yield (
                    robot.topic(N.BALL_IS_HOLDING),
                    "nubot_common/BallIsHolding",
                    t_ns,
                    convert.ball_is_holding(kit, convert.holding(msg)),
                )
            elif leaf == T.VEL_CMD:
                yield robot.topic(N.VELCMD), "nubot_common/VelCmd", t_ns, convert.velcmd_out(kit, msg)
            elif leaf == T.ACTION_CMD:
                yield robot.topic(N.ACTIONCMD), "nubot_common/ActionCmd", t_ns, convert.actioncmd_out(kit, msg)
            elif leaf == T.STRATEGY_INFO:
                yield robot.topic(N.STRATEGY), "nubot_common/StrategyInfo", t_ns, convert.strategy_info_out(kit, msg)
            continue
        if len(parts) == 2 and parts[0] in names.prefixes:
            team = parts[0]
            if parts[1] == T.RECEIVE_FROM_COACH:
                seq += 1
                yield (
                    names.team_topic(team, N.COACH),
                    "nubot_common/CoachInfo",
                    t_ns,
                    convert.coach_info(kit, msg, seq, msg.stamp),
                )
            elif parts[1] == T.TEAM_STRATEGY:
                infos = [convert.strategy_info_out(kit, s) for s in msg.strategies]
                yield (
                    names.team_topic(team, N.STRATEGY),
                    "nubot_common/simulation_strategy",
                    t_ns,
                    convert.simulation_strategy(kit, infos),
                )
        elif topic == T.MODEL_STATES:
            yield N.MODEL_STATES, "gazebo_msgs/ModelStates", t_ns, convert.model_states(kit, msg, names)
        elif topic == T.CLOCK:
            yield N.CLOCK, "rosgraph_msgs/Clock", t_ns, convert.clock(kit, msg.stamp)
        elif topic == T.GAME_STATE:
            now_off = {str(n) for n in msg.sent_off}
            for name in sorted(now_off ^ sent_off):
                robot = names.by_name.get(name)
                if robot is not None:
                    msg_off = convert.sending_off(kit, robot, names.teams.index(robot.team), name in now_off)
                    yield names.team_topic(robot.team, N.REDCARD), "nubot_common/SendingOff", t_ns, msg_off
            sent_off = now_off
