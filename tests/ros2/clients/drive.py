"""Drive one robot with cmd_vel and record its odom and /clock (a plain rclpy node, no simatch code).

    python drive.py NAMESPACE VX VY W SECONDS OUT.json [--nan] [--vz VZ]

A node with ``use_sim_time`` (it notes its clock at each odom). Waits (up to 60 s) for the robot's first
odom, then publishes cmd_vel at 50 Hz of wall time for SECONDS of simulated time (/clock), recording every
odom (simulated stamp, map pose, body twist) and /clock. With --nan it then publishes one cmd_vel whose
linear.x is NaN and keeps recording for one more simulated second. With --vz the cmd_vel's linear.z (an
aerial robot's upward speed) is VZ; each odom row ends with its height and upward speed.
"""

import json
import math
import sys
import time

import rclpy
from geometry_msgs.msg import PoseArray, Twist
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter
from rclpy.qos import qos_profile_sensor_data
from rosgraph_msgs.msg import Clock


def main() -> None:
    ns, vx, vy, w, seconds, out = sys.argv[1], *map(float, sys.argv[2:6]), sys.argv[6]
    nan = "--nan" in sys.argv
    vz = float(sys.argv[sys.argv.index("--vz") + 1]) if "--vz" in sys.argv else 0.0
    rclpy.init()
    # a node on simulated time, as ROS 2 users run theirs with a simulator: its clock is /clock's
    node = rclpy.create_node("drive_test", parameter_overrides=[Parameter("use_sim_time", Parameter.Type.BOOL, True)])
    node_time = []  # (odom's stamp, the node's clock when the odom came)
    odom, clock, sent = [], [], []

    def on_odom(m):
        p, t = m.pose.pose, m.twist.twist
        yaw = 2.0 * math.atan2(p.orientation.z, p.orientation.w)
        stamp = m.header.stamp.sec + m.header.stamp.nanosec * 1e-9
        odom.append(
            [
                stamp,
                p.position.x,
                p.position.y,
                yaw,
                t.linear.x,
                t.linear.y,
                t.angular.z,
                m.header.frame_id,
                m.child_frame_id,
                p.position.z,
                t.linear.z,
            ]
        )
        node_time.append([stamp, node.get_clock().now().nanoseconds * 1e-9])

    node.create_subscription(Odometry, f"{ns}/odom", on_odom, qos_profile_sensor_data)
    node.create_subscription(
        Clock, "/clock", lambda m: clock.append(m.clock.sec + m.clock.nanosec * 1e-9), qos_profile_sensor_data
    )
    obstacles = []
    node.create_subscription(
        PoseArray,
        f"{ns}/obstacles",
        lambda m: obstacles.append([[p.position.x, p.position.y] for p in m.poses]),
        qos_profile_sensor_data,
    )
    pub = node.create_publisher(Twist, f"{ns}/cmd_vel", 10)
    t0 = time.monotonic()
    while not odom and time.monotonic() - t0 < 60:
        rclpy.spin_once(node, timeout_sec=0.05)
    if not odom:
        raise SystemExit("no odom within 60 s")
    while pub.get_subscription_count() == 0 and time.monotonic() - t0 < 60:
        rclpy.spin_once(node, timeout_sec=0.05)

    def spin_for(sim_seconds: float, cmd: Twist | None) -> None:
        while not clock:
            rclpy.spin_once(node, timeout_sec=0.05)
        end = clock[-1] + sim_seconds
        nxt = time.monotonic()
        limit = time.monotonic() + 120
        while clock[-1] < end and time.monotonic() < limit:
            if cmd is not None and time.monotonic() >= nxt:
                pub.publish(cmd)
                sent.append(clock[-1] if clock else None)
                nxt += 0.02
            rclpy.spin_once(node, timeout_sec=0.005)

    cmd = Twist()
    cmd.linear.x, cmd.linear.y, cmd.linear.z, cmd.angular.z = vx, vy, vz, w
    spin_for(seconds, cmd)
    first_sent = next((s for s in sent if s is not None), None)
    nan_at = None
    if nan:
        bad = Twist()
        bad.linear.x = float("nan")
        pub.publish(bad)
        nan_at = clock[-1] if clock else None
        spin_for(1.0, None)
    with open(out, "w") as f:
        json.dump(
            {
                "odom": odom,
                "clock": clock,
                "first_sent": first_sent,
                "last_sent": sent[-1] if sent else None,
                "nan_at": nan_at,
                "obstacles": obstacles[-1] if obstacles else [],
                "node_time": node_time,
            },
            f,
        )
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
