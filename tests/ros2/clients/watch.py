"""Watch the world a simatch bridge publishes (a plain rclpy node; simatch_msgs as built for ROS 2).

    python watch.py SECONDS OUT.json TEAM [TEAM ...]

Records the robot and ball markers seen on /simatch/markers, the frames on /tf, each team's match_mode
changes, the events on /simatch/events and /clock, for SECONDS of wall time (it stops early once it has
seen a bad_command event and at least three match_mode values per team).
"""

import json
import sys
import time

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from simatch_msgs.msg import GameEvent
from std_msgs.msg import UInt8
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import Marker, MarkerArray


def main() -> None:
    seconds, out, teams = float(sys.argv[1]), sys.argv[2], sys.argv[3:]
    rclpy.init()
    node = rclpy.create_node("watch_test")
    seen = {"markers": set(), "tf": set(), "modes": {t: [] for t in teams}, "events": [], "clock": []}

    def on_markers(m):
        for mk in m.markers:
            if mk.ns == "ball" or mk.ns.startswith("robots/"):
                seen["markers"].add(f"{mk.ns}:{mk.id}:{mk.type == Marker.SPHERE}")

    def on_tf(m):
        for t in m.transforms:
            seen["tf"].add(f"{t.header.frame_id}->{t.child_frame_id}")

    def on_mode(team, m):
        modes = seen["modes"][team]
        if not modes or modes[-1][1] != m.data:
            modes.append([seen["clock"][-1] if seen["clock"] else None, m.data])

    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_subscription(MarkerArray, "/simatch/markers", on_markers, 1)
    node.create_subscription(TFMessage, "/tf", on_tf, 100)
    node.create_subscription(
        Clock, "/clock", lambda m: seen["clock"].append(m.clock.sec + m.clock.nanosec * 1e-9), qos_profile_sensor_data
    )
    node.create_subscription(
        GameEvent, "/simatch/events", lambda e: seen["events"].append([e.stamp, e.type, e.team, e.robot, e.detail]), 100
    )
    for team in teams:
        node.create_subscription(UInt8, f"/{team}/match_mode", lambda m, team=team: on_mode(team, m), latched)
    print("watching", flush=True)
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds:
        rclpy.spin_once(node, timeout_sec=0.05)
        if any(e[1] == "bad_command" for e in seen["events"]) and all(len(v) >= 3 for v in seen["modes"].values()):
            break
    with open(out, "w") as f:
        json.dump({k: sorted(v) if isinstance(v, set) else v for k, v in seen.items()}, f)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
