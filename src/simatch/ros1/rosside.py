"""The bridge's ROS side: one rospy node with the original's topics (imports rospy: see `rosenv`).

Publishers and subscriptions are made once, at start; callbacks run in rospy's threads and only hand
messages to the bridge (`RosBridge.received`), which turns them into simatch messages under its lock.
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Any

from . import convert
from . import names as N
from .rosenv import RosUnavailable, use_rospy

log = logging.getLogger(__name__)

QUEUE = 100  # rospy's queue per publisher connection and subscription (no message of a tick is dropped)
WATCH_EVERY = 1.0  # [s] how often the master's topic list is read (unknown robots, a team's own relay)


class GenpyKit:
    """`convert.Kit` for genpy's classes (the ones generated into the bridge's workspace)."""

    def __init__(self):
        import gazebo_msgs.msg
        import geometry_msgs.msg
        import nubot_common.msg
        import rosgraph_msgs.msg
        import rospy
        import std_msgs.msg

        self.rospy = rospy
        self.modules = {
            "nubot_common": nubot_common.msg,
            "gazebo_msgs": gazebo_msgs.msg,
            "geometry_msgs": geometry_msgs.msg,
            "rosgraph_msgs": rosgraph_msgs.msg,
            "std_msgs": std_msgs.msg,
        }
        self.classes: dict[str, type] = {}
        self.Header = std_msgs.msg.Header

    def cls(self, msgtype: str) -> type:
        found = self.classes.get(msgtype)
        if found is None:
            pkg, name = msgtype.split("/")
            found = self.classes[msgtype] = getattr(self.modules[pkg], name)
        return found

    def make(self, msgtype: str, **fields: Any) -> Any:
        return self.cls(msgtype)(**fields)

    def time(self, stamp: float) -> Any:
        return self.rospy.Time(*convert.stamp_ns(stamp))

    def header(self, seq: int, stamp: float, frame_id: str = "") -> Any:
        return self.Header(seq=seq, stamp=self.time(stamp), frame_id=frame_id)


class RosSide:
    def __init__(self, bridge):
        use_rospy()
        import rosgraph
        import rospy

        self.rospy = rospy
        self.bridge = bridge
        opt = bridge.opt
        names = bridge.names
        try:
            master = rosgraph.Master("/simatch")
            master.getPid()
        except Exception as exc:  # ConnectionRefused, socket errors: no master there
            raise RosUnavailable(
                f"no ROS master answers at {rosgraph.get_master_uri()} ({exc}): start `roscore` "
                f"(or give --ros-master / ROS_MASTER_URI)"
            ) from None
        self.master = master
        rospy.init_node(opt.node_name, anonymous=False, disable_signals=True, disable_rosout=False)
        self.kit = kit = GenpyKit()
        self.node_name = rospy.get_name()
        self._set_params()
        pub = rospy.Publisher
        self.pub_clock = pub(N.CLOCK, kit.cls("rosgraph_msgs/Clock"), queue_size=QUEUE) if opt.clock else None
        self.pub_models = pub(N.MODEL_STATES, kit.cls("gazebo_msgs/ModelStates"), queue_size=10) if opt.world else None
        self.pub_coach = {
            t: pub(names.team_topic(t, N.COACH), kit.cls("nubot_common/CoachInfo"), queue_size=QUEUE)
            for t in bridge.shown_teams
        }
        self.pub_redcard = {
            t: pub(names.team_topic(t, N.REDCARD), kit.cls("nubot_common/SendingOff"), queue_size=QUEUE)
            for t in bridge.shown_teams
        }
        self.pub_relay: dict[str, Any] = {}
        for team in opt.teams:
            if bridge.own_relay.get(team):
                self.pub_relay[team] = pub(
                    names.team_topic(team, N.STRATEGY), kit.cls("nubot_common/simulation_strategy"), queue_size=QUEUE
                )
        self.pub_vision = {}
        self.pub_holding = {}
        for r in bridge.shown:
            self.pub_vision[r.name] = pub(
                r.topic(N.OMNIVISION), kit.cls("nubot_common/OminiVisionInfo"), queue_size=QUEUE
            )
            self.pub_holding[r.name] = pub(
                r.topic(N.BALL_IS_HOLDING), kit.cls("nubot_common/BallIsHolding"), queue_size=QUEUE
            )
        self.subs = []
        for name, link in bridge.links.items():
            r = link.robot
            for kind, leaf, typ in (
                ("velcmd", N.VELCMD, "nubot_common/VelCmd"),
                ("actioncmd", N.ACTIONCMD, "nubot_common/ActionCmd"),
                ("strategy", N.STRATEGY, "nubot_common/StrategyInfo"),
            ):
                self.subs.append(
                    rospy.Subscriber(r.topic(leaf), kit.cls(typ), self._receiver(name, kind), queue_size=QUEUE)
                )
        if opt.world:
            self.subs.append(
                rospy.Subscriber(
                    N.SET_MODEL_STATE, kit.cls("gazebo_msgs/ModelState"), bridge.model_state_request, queue_size=QUEUE
                )
            )
        self._closing = threading.Event()
        self._watcher = threading.Thread(target=self._watch, name="ros1-watch", daemon=True)
        self._watcher.start()

    def _set_params(self) -> None:
        """What the original's Gazebo launch put on the parameter server (its team scripts read the prefix and
        the number of robots there), and /use_sim_time."""
        rospy, bridge = self.rospy, self.bridge
        spec = bridge.spec
        for team in bridge.names.teams:
            rospy.set_param(f"/{team}/prefix", bridge.names.prefixes[team])
            rospy.set_param(f"/{team}/num", len(spec.teams[team].robot_ids()))
        rospy.set_param("/field/length", float(spec.world.length))
        rospy.set_param("/field/width", float(spec.world.width))
        rospy.set_param("/football/name", N.BALL)
        if bridge.opt.sim_time and bridge.opt.clock:
            rospy.set_param("/use_sim_time", True)

    def _receiver(self, name: str, kind: str):
        received = self.bridge.received

        def on_message(msg) -> None:
            try:
                received(name, kind, msg)
            except Exception as exc:  # a message the conversion cannot read: dropped, never fatal
                self.bridge.stats.refused += 1
                log.warning("dropped a %s of %s: %s", kind, name, exc)

        return on_message

    # --- out ----------------------------------------------------------------------------------------------
    def clock(self, stamp: float) -> None:
        if self.pub_clock is not None:
            self.pub_clock.publish(convert.clock(self.kit, stamp))

    def coach(self, team: str, msg, seq: int, stamp: float) -> None:
        pub = self.pub_coach.get(team)
        if pub is not None:
            pub.publish(convert.coach_info(self.kit, msg, seq, stamp))

    def relay(self, team: str, infos: list) -> None:
        pub = self.pub_relay.get(team)
        if pub is not None:
            try:
                pub.publish(convert.simulation_strategy(self.kit, infos))
            except self.rospy.ROSException:  # unregistered meanwhile: the team relays itself
                pass

    def perception(self, robot, msg, seq: int) -> None:
        holding = self.pub_holding[robot.name]
        if holding.get_num_connections():
            holding.publish(convert.ball_is_holding(self.kit, convert.holding(msg)))
        vision = self.pub_vision[robot.name]
        if vision.get_num_connections():
            vision.publish(convert.omnivision(self.kit, msg, seq))

    def sending_off(self, robot, team_index: int, off: bool) -> None:
        pub = self.pub_redcard.get(robot.team)
        if pub is not None:
            pub.publish(convert.sending_off(self.kit, robot, team_index, off))

    def model_states(self, msg) -> None:
        pub = self.pub_models
        if pub is not None and pub.get_num_connections():
            pub.publish(convert.model_states(self.kit, msg, self.bridge.names))

    # --- the graph -----------------------------------------------------------------------------------------
    def wait_for_nodes(self, timeout: float) -> list[str]:
        """Robots whose perception nobody subscribes to, or whose velcmd nobody publishes, after ``timeout``."""
        deadline = time.monotonic() + timeout
        while True:
            missing = []
            for name, link in self.bridge.links.items():
                vel = next(s for s in self.subs if s.name == link.robot.topic(N.VELCMD))
                if not self.pub_vision[name].get_num_connections() or not vel.get_num_connections():
                    missing.append(link.robot.ros)
            if not missing or time.monotonic() >= deadline:
                return missing
            time.sleep(0.1)

    def _watch(self) -> None:
        """Every few seconds: ROS topics that command robots this bridge does not serve (a misnamed robot, or
        the other team's), and teams that run their own strategy relay (then the bridge's steps aside)."""
        bridge = self.bridge
        mine = {link.robot.topic(leaf) for link in bridge.links.values() for leaf in (N.VELCMD, N.ACTIONCMD)}
        relays = {bridge.names.team_topic(t, N.STRATEGY): t for t in bridge.opt.teams}
        while not self._closing.wait(WATCH_EVERY):
            try:
                publishers, _, _ = self.master.getSystemState()
            except Exception as exc:  # the master went away: nothing to watch
                log.debug("master not readable: %s", exc)
                continue
            for topic, nodes in publishers:
                if topic.endswith(("/" + N.VELCMD, "/" + N.ACTIONCMD)) and topic not in mine:
                    bridge.unknown_robot(topic)
                team = relays.get(topic)
                if team is not None and bridge.own_relay.get(team) and any(n != self.node_name for n in nodes):
                    bridge.own_relay[team] = False
                    pub = self.pub_relay.pop(team, None)
                    if pub is not None:
                        pub.unregister()
                    others = ", ".join(n for n in nodes if n != self.node_name)
                    bridge.say(f"{topic} is published by the team's own strategy relay ({others}): not relaying it")

    def shutdown(self) -> None:
        """Leave the master (rospy's node itself ends with the process: another bridge may follow in it)."""
        self._closing.set()
        for sub in self.subs:
            sub.unregister()
        pubs = [self.pub_clock, self.pub_models, *self.pub_coach.values(), *self.pub_redcard.values()]
        pubs += [*self.pub_relay.values(), *self.pub_vision.values(), *self.pub_holding.values()]
        for pub in pubs:
            if pub is not None:
                pub.unregister()
