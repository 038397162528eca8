"""Drive one robot and hear it with ROS 2's default QoS everywhere (a plain rclpy node, no simatch code).

    python default_qos.py NAMESPACE W SECONDS OUT.json

What most tutorials and nav2-style nodes do: every subscription ``create_subscription(T, topic, cb, 10)``
(reliable, volatile, keep last 10), no sensor-data profile. Subscribes to the robot's odom, obstacles and
teammates, /clock, /simatch/model_states and /simatch/markers; waits (up to 60 s) for the first odom, then
turns the robot on the spot at W rad/s with cmd_vel (default QoS too) for SECONDS of simulated time, and
writes how many messages of each topic came and the odom's angular speeds while turning."""

import json
import sys
import time

import rclpy
from geometry_msgs.msg import PoseArray, Twist
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from visualization_msgs.msg import MarkerArray


def main() -> None:
    ns, w, seconds, out = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
    rclpy.init()
    node = rclpy.create_node("default_qos_test")
    counts = {"odom": 0, "obstacles": 0, "teammates": 0, "clock": 0, "markers": 0}
    clock, turning = [], []
    sending = [False]

    def count(name, then=None):
        def cb(m):
            counts[name] += 1
            if then is not None:
                then(m)

        return cb

    def on_odom(m):
        if sending[0]:
            turning.append(m.twist.twist.angular.z)

    node.create_subscription(Odometry, f"{ns}/odom", count("odom", on_odom), 10)
    node.create_subscription(PoseArray, f"{ns}/obstacles", count("obstacles"), 10)
    node.create_subscription(PoseArray, f"{ns}/teammates", count("teammates"), 10)
    node.create_subscription(
        Clock, "/clock", count("clock", lambda m: clock.append(m.clock.sec + m.clock.nanosec * 1e-9)), 10
    )
    node.create_subscription(MarkerArray, "/simatch/markers", count("markers"), 10)
    models = None
    try:
        from simatch_msgs.msg import ModelStates

        counts["model_states"] = 0
        models = node.create_subscription(ModelStates, "/simatch/model_states", count("model_states"), 10)
    except ImportError:
        pass
    pub = node.create_publisher(Twist, f"{ns}/cmd_vel", 10)
    t0 = time.monotonic()
    while (counts["odom"] == 0 or not clock) and time.monotonic() - t0 < 60:
        rclpy.spin_once(node, timeout_sec=0.05)
    if counts["odom"] == 0:
        raise SystemExit(f"no odom within 60 s with the default QoS: {counts}")
    end = clock[-1] + seconds
    cmd = Twist()
    cmd.angular.z = w
    nxt = time.monotonic()
    while clock[-1] < end and time.monotonic() - t0 < 120:
        if time.monotonic() >= nxt:
            pub.publish(cmd)
            sending[0] = True
            nxt += 0.02
        rclpy.spin_once(node, timeout_sec=0.005)
    pub.publish(Twist())
    del models
    with open(out, "w") as f:
        json.dump({"counts": counts, "turning": turning}, f)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
