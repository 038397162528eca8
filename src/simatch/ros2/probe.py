"""A latency probe for `simatch bench --only ros2`: a plain rclpy program (run as ``python -m
simatch.ros2.probe OUT.json SECONDS ROBOT...``) that drives robots with cmd_vel at 40 Hz of wall time, each
message a new forward speed (0.5 m/s + sequence x 1e-4), and writes when it published which (monotonic clock,
shared by every process of the machine), so the bench can match each to the moment the simulator applied it.
It imports nothing of simatch."""

from __future__ import annotations

import json
import sys
import time

import rclpy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.qos import qos_profile_sensor_data


def main() -> None:
    out, seconds, robots = sys.argv[1], float(sys.argv[2]), sys.argv[3:]
    rclpy.init()
    node = rclpy.create_node("simatch_latency_probe")
    pubs, seen = {}, set()
    for name in robots:
        team, rid = name.split("/")
        ns = f"/{team}/robot{rid}"
        pubs[name] = node.create_publisher(Twist, f"{ns}/cmd_vel", 10)
        node.create_subscription(Odometry, f"{ns}/odom", lambda m, name=name: seen.add(name), qos_profile_sensor_data)
    t0 = time.monotonic()
    while len(seen) < len(robots) and time.monotonic() - t0 < 120:
        rclpy.spin_once(node, timeout_sec=0.05)
    sent = []
    seq = 0
    end = time.monotonic() + seconds
    nxt = time.monotonic()
    while time.monotonic() < end:
        now = time.monotonic()
        if now >= nxt:
            seq += 1
            for name, pub in pubs.items():
                t = Twist()
                t.linear.x = 0.5 + (seq % 2000) * 1e-4
                pub.publish(t)
                sent.append([name, seq % 2000, time.monotonic()])
            nxt += 0.025
        rclpy.spin_once(node, timeout_sec=max(0.0, min(0.005, nxt - time.monotonic())))
    with open(out, "w") as f:
        json.dump(sent, f)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
