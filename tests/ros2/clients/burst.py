"""Publish cmd_vel in bursts: several distinct speeds back to back, faster than any control tick (a plain rclpy
node, no simatch code).

    python burst.py NAMESPACE BURSTS SIZE OUT.json

Waits (up to 120 s) for the robot's first odom and for the bridge's cmd_vel subscription, then every 0.2 s of
wall time publishes SIZE cmd_vel messages at once, each with a forward speed of its own (0.3 m/s, then
0.01 m/s more each), BURSTS times; writes the speeds it published."""

import json
import sys
import time

import rclpy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.qos import qos_profile_sensor_data


def main() -> None:
    ns, bursts, size, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
    rclpy.init()
    node = rclpy.create_node("burst_test")
    heard = []
    node.create_subscription(Odometry, f"{ns}/odom", heard.append, qos_profile_sensor_data)
    pub = node.create_publisher(Twist, f"{ns}/cmd_vel", 10)
    deadline = time.monotonic() + 120
    while (not heard or pub.get_subscription_count() == 0) and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)
    if not heard:
        sys.exit(f"no odom on {ns}/odom")
    sent = []
    for _ in range(bursts):
        for _ in range(size):
            m = Twist()
            m.linear.x = 0.3 + 0.01 * len(sent)
            pub.publish(m)
            sent.append(m.linear.x)
        end = time.monotonic() + 0.2
        while time.monotonic() < end:
            rclpy.spin_once(node, timeout_sec=0.05)
    with open(out, "w") as f:
        json.dump(sent, f)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
