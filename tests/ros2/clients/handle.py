"""Take the ball and kick it with simatch's own types from ROS 2 (simatch_msgs as built for ROS 2; a plain rclpy
program, no simatch code).

    python handle.py TEAM ID KICK_SPEED OUT.json

Once the game is on (``/<team>/coach``: STARTROBOT) it places the ball 0.5 m in front of the robot with the
organiser's ``/simatch/set_model_state``, drives the robot at it with the dribbler on (``action_cmd``) until
``holding_ball`` says it holds it, keeps it for half a second, then kicks it (``action_cmd.kick_speed``) and
records the ball's speed from ``/simatch/model_states`` for a second; all along it records the robot's
``omni_vision``, ``teammates``, ``/simatch/game_state`` and ``/clock``.
"""

import json
import math
import sys
import time

import rclpy
from geometry_msgs.msg import PoseArray, Twist
from nav_msgs.msg import Odometry
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from simatch_msgs.msg import ActionCmd, CoachInfo, GameState, ModelState, ModelStates, OmniVisionInfo
from std_msgs.msg import Bool


def main() -> None:
    team, rid, kick_speed, out = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
    ns = f"/{team}/robot{rid}"
    rclpy.init()
    node = rclpy.create_node("handle_test")
    seen = {"vision": [], "holding": [], "modes": [], "game": [], "teammates": [], "ball_speed": [], "models": []}
    now = [0.0]
    truth = []

    def on_vision(m):
        b = m.ball
        seen["vision"].append([m.stamp, m.robot_id, b.state, b.distance, len(m.robots), len(m.obstacles.x)])

    def on_models(m):
        if not seen["models"]:
            seen["models"] = list(m.name)
        if "ball" in m.name:
            i = list(m.name).index("ball")
            seen["ball_speed"].append([m.stamp, math.hypot(m.twist[6 * i], m.twist[6 * i + 1])])

    def on_truth(m):
        p = m.pose.pose
        truth.append((p.position.x, p.position.y, 2.0 * math.atan2(p.orientation.z, p.orientation.w)))

    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    sensor = qos_profile_sensor_data
    node.create_subscription(OmniVisionInfo, f"{ns}/omni_vision", on_vision, sensor)
    node.create_subscription(Bool, f"{ns}/holding_ball", lambda m: seen["holding"].append([now[0], m.data]), sensor)
    node.create_subscription(PoseArray, f"{ns}/teammates", lambda m: seen["teammates"].append(len(m.poses)), sensor)
    node.create_subscription(Odometry, f"{ns}/ground_truth", on_truth, sensor)
    node.create_subscription(CoachInfo, f"/{team}/coach", lambda m: seen["modes"].append(m.match_mode), latched)
    node.create_subscription(
        GameState, "/simatch/game_state", lambda m: seen["game"].append([list(m.teams), list(m.score)]), latched
    )
    node.create_subscription(ModelStates, "/simatch/model_states", on_models, sensor)
    node.create_subscription(
        Clock, "/clock", lambda m: now.__setitem__(0, m.clock.sec + m.clock.nanosec * 1e-9), sensor
    )
    pub_vel = node.create_publisher(Twist, f"{ns}/cmd_vel", 10)
    pub_action = node.create_publisher(ActionCmd, f"{ns}/action_cmd", 10)
    pub_place = node.create_publisher(ModelState, "/simatch/set_model_state", 10)

    def spin_until(done, wall: float, every=None) -> bool:
        t0 = time.monotonic()
        while time.monotonic() - t0 < wall:
            if every is not None:
                every()
            rclpy.spin_once(node, timeout_sec=0.02)
            if done():
                return True
        return False

    def command(vx: float, dribble: bool, kick: float = 0.0) -> None:
        t = Twist()
        t.linear.x = vx
        pub_vel.publish(t)
        pub_action.publish(ActionCmd(dribble=dribble, kick_speed=kick, kick_type=ActionCmd.KICK_GROUND))

    # the game on, and this client hearing the robot's pose and its perception of the ball before it moves the ball
    # (on a busy machine the sensor topics' first samples come a while after the latched coach's)
    seen_ball = lambda: any(v[2] == 1 for v in seen["vision"])  # noqa: E731
    ok = spin_until(lambda: truth and seen_ball() and seen["modes"] and seen["modes"][-1] == CoachInfo.STARTROBOT, 120)
    ok = ok and spin_until(lambda: pub_place.get_subscription_count() > 0, 30)
    if ok:
        x, y, yaw = truth[-1]
        pub_place.publish(ModelState(name="ball", x=x + 0.5 * math.cos(yaw), y=y + 0.5 * math.sin(yaw), z=0.11))
        seen["placed_at"] = now[0]
        seen["vision_before_placing"] = len(seen["vision"])  # what the robot had perceived when the ball was moved
        holding = lambda: any(h for t, h in seen["holding"][-3:]) and seen["holding"][-1][1]  # noqa: E731
        seen["held_at"] = now[0] if spin_until(holding, 30, lambda: command(0.4, True)) else None
        if seen["held_at"] is not None:
            t_hold = now[0]
            spin_until(lambda: now[0] >= t_hold + 0.5, 30, lambda: command(0.0, True))
            seen["still_holding"] = seen["holding"][-1][1]
            command(0.0, False, kick_speed)
            seen["kick_at"] = now[0]
            t_kick = now[0]
            spin_until(lambda: now[0] >= t_kick + 1.0, 30, lambda: command(0.0, False))
    with open(out, "w") as f:
        json.dump(seen, f)
    node.destroy_node()
    rclpy.shutdown()
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
