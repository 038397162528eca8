"""Drive one robot across half time and record what it perceives beside the ground truth (a plain rclpy node).

    python ends.py NAMESPACE TEAM VX W UNTIL OUT.json

Says "ready" (stderr) once it heard the observer (its latched /tf_static). Answers every odom of the robot
with one cmd_vel (VX forward, W turning: a circle), until /clock reaches UNTIL simulated seconds; records the
robot's odom (its perception, from a team bridge), its ground_truth (from an observer bridge), each
``map -> TEAM/field`` frame on /tf_static (when it came, its yaw) and /clock.
"""

import json
import math
import sys
import time

import rclpy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from tf2_msgs.msg import TFMessage


def seconds(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def row(m: Odometry) -> list[float]:
    p, q, t = m.pose.pose.position, m.pose.pose.orientation, m.twist.twist
    yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
    return [seconds(m.header.stamp), p.x, p.y, yaw, t.linear.x, t.linear.y, t.angular.z]


def main() -> None:
    ns, team, vx, w, until, out = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4]), *sys.argv[5:7]
    until = float(until)
    rclpy.init()
    node = rclpy.create_node("ends_test")
    seen = {"odom": [], "truth": [], "field": [], "clock": []}
    cmd = node.create_publisher(Twist, f"{ns}/cmd_vel", 10)
    twist = Twist()
    twist.linear.x, twist.angular.z = vx, w

    def on_odom(m):
        seen["odom"].append(row(m))
        cmd.publish(twist)

    def on_static(m):
        for t in m.transforms:
            if t.header.frame_id == "map" and t.child_frame_id == f"{team}/field":
                r = t.transform.rotation
                yaw = math.atan2(2.0 * (r.w * r.z + r.x * r.y), 1.0 - 2.0 * (r.y * r.y + r.z * r.z))
                seen["field"].append([seen["clock"][-1] if seen["clock"] else None, yaw])

    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_subscription(Odometry, f"{ns}/odom", on_odom, qos_profile_sensor_data)
    node.create_subscription(
        Odometry, f"{ns}/ground_truth", lambda m: seen["truth"].append(row(m)), qos_profile_sensor_data
    )
    node.create_subscription(TFMessage, "/tf_static", on_static, latched)
    node.create_subscription(Clock, "/clock", lambda m: seen["clock"].append(seconds(m.clock)), qos_profile_sensor_data)
    limit = time.monotonic() + 150
    while not seen["field"] and time.monotonic() < limit:  # the observer found (its /tf_static is latched)
        rclpy.spin_once(node, timeout_sec=0.05)
    print("ready", file=sys.stderr, flush=True)
    while (not seen["clock"] or seen["clock"][-1] < until) and time.monotonic() < limit:
        rclpy.spin_once(node, timeout_sec=0.05)
    with open(out, "w") as f:
        json.dump(seen, f)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
