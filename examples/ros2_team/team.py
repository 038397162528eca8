"""A ROS 2 soccer team for simatch: plain rclpy, five robots in one process (see README.md).

It uses only what the bridge (``simatch ros2 --team TEAM``) publishes in standard types, as a team's own ROS 2
stack would: per robot ``odom`` and ``ball`` (nav_msgs/Odometry in ``map``), ``holding_ball`` (std_msgs/Bool),
the team's ``match_mode`` (std_msgs/UInt8, the MSL game commands), and ``/tf_static`` for the team's frame
(which goal it attacks); it answers every odom of a robot with its ``cmd_vel`` (geometry_msgs/Twist, body
frame), and drives ``dribble`` (Bool) and ``kick`` (Float32, ball speed in m/s).

The play is the original demo's, simplified: in play, the robot nearest the ball goes for it and takes it
with the dribbler; after a restart (when MSL counts no goal until two robots of the scoring team have touched
the ball) it passes to the nearest team-mate, otherwise it turns towards the goal and shoots; the others keep
their places. At a stoppage everybody goes back to its place in its own half, slowing down near other robots
(a robot driving into another at more than 1.5 m/s is charging); after the other team's restart it waits
until the ball has moved (or the referee's restart time is over) before going for the ball.

    python team.py --team cyan [--robots 1 2 3 4 5]
"""

from __future__ import annotations

import argparse
import math
import time

import rclpy
from geometry_msgs.msg import PoseArray, Twist
from nav_msgs.msg import Odometry
from rclpy.executors import ExternalShutdownException
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from std_msgs.msg import Bool, Float32, UInt8
from tf2_msgs.msg import TFMessage

STOPROBOT, STARTROBOT = 0, 15
OPP_COMMANDS = {2, 4, 6, 8, 10, 12}  # the other team's kick-off, throw-in, penalty, goal kick, corner, free kick
DROPBALL = 13
GOAL_X = 11.0  # [m] the goal line of the 22 m field
RESTART_TIMEOUT = 7.0  # [s] after START the ball is in play for everybody anyway
#: each robot's place, in the team's frame (attacking +x): the goalkeeper and four field players
HOMES = {1: (-10.0, 0.0), 2: (-4.0, 1.5), 3: (-4.0, -1.5), 4: (-6.5, 3.0), 5: (-6.5, -3.0)}
MAX_SPEED, MAX_TURN = 2.5, 3.0  # [m/s], [rad/s]
KICK_SPEED = 9.0  # [m/s]
PASS_SPEED = 4.0  # [m/s]: arrives below the 3.5 m/s the dribbler can catch
NEAR = 1.5  # [m] within this of another robot, at most CAREFUL m/s
CAREFUL = 1.0

LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)


def wrap(a: float) -> float:
    return math.remainder(a, 2.0 * math.pi)


def yaw_of(q) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


class Robot:
    def __init__(self, team: Team, rid: int):
        self.team, self.rid = team, rid
        ns = f"/{team.name}/robot{rid}"
        node = team.node
        self.pose = None  # (x, y, yaw) in map
        self.ball = None  # (x, y, seen at [s])
        self.holding = False
        self.cmd = node.create_publisher(Twist, f"{ns}/cmd_vel", 10)
        self.dribble = node.create_publisher(Bool, f"{ns}/dribble", 10)
        self.kick = node.create_publisher(Float32, f"{ns}/kick", 10)
        node.create_subscription(Odometry, f"{ns}/odom", self.on_odom, qos_profile_sensor_data)
        node.create_subscription(Odometry, f"{ns}/ball", self.on_ball, qos_profile_sensor_data)
        node.create_subscription(Bool, f"{ns}/holding_ball", self.on_holding, qos_profile_sensor_data)
        node.create_subscription(PoseArray, f"{ns}/obstacles", self.on_obstacles, qos_profile_sensor_data)
        self.obstacles: list[tuple[float, float]] = []
        self.kicked_at = -10.0

    def on_obstacles(self, m: PoseArray) -> None:
        self.obstacles = [(p.position.x, p.position.y) for p in m.poses]

    def on_ball(self, m: Odometry) -> None:
        p = m.pose.pose.position
        self.ball = (p.x, p.y, m.header.stamp.sec + m.header.stamp.nanosec * 1e-9)
        self.team.ball_seen(self.ball)

    def on_holding(self, m: Bool) -> None:
        self.holding = bool(m.data)
        if self.holding:
            self.team.touched.add(self.rid)

    def on_odom(self, m: Odometry) -> None:
        p = m.pose.pose
        self.pose = (p.position.x, p.position.y, yaw_of(p.orientation))
        now = m.header.stamp.sec + m.header.stamp.nanosec * 1e-9
        vx, vy, w, dribble, kick = self.team.decide(self, now)
        t = Twist()
        t.linear.x, t.linear.y, t.angular.z = vx, vy, w
        self.cmd.publish(t)  # one command for every odom: the bridge can wait for it (--wait-answers)
        self.dribble.publish(Bool(data=dribble))
        if kick > 0:
            self.kick.publish(Float32(data=kick))

    # --- motion -----------------------------------------------------------------------------------------------
    def towards(self, x: float, y: float, face: float, speed: float = MAX_SPEED) -> tuple[float, float, float]:
        """Body-frame velocity to (x, y) in map, turning to ``face``: slowing down near the target."""
        px, py, yaw = self.pose
        dx, dy = x - px, y - py
        dist = math.hypot(dx, dy)
        v = min(speed, 1.5 * dist)
        if dist > 1e-6:
            wx, wy = v * dx / dist, v * dy / dist
        else:
            wx = wy = 0.0
        others = [(ox, oy) for ox, oy in self.obstacles if math.hypot(ox - x, oy - y) > 0.3]
        near = [(ox - px, oy - py) for ox, oy in others if math.hypot(ox - px, oy - py) < NEAR]
        if near:  # steer around, slowly: no charging
            for ox, oy in near:
                d = max(0.3, math.hypot(ox, oy))
                wx -= 1.2 * ox / (d * d)
                wy -= 1.2 * oy / (d * d)
            n = math.hypot(wx, wy)
            if n > CAREFUL:
                wx, wy = wx * CAREFUL / n, wy * CAREFUL / n
        c, s = math.cos(yaw), math.sin(yaw)
        w = max(-MAX_TURN, min(MAX_TURN, 3.0 * wrap(face - yaw)))
        return c * wx + s * wy, -s * wx + c * wy, w


class Team:
    def __init__(self, node, name: str, rids: list[int]):
        self.node, self.name = node, name
        self.sign = 1.0  # +1: we attack +x in map (from /tf_static: map -> <team>/field)
        self.mode = STOPROBOT
        self.last_stoppage = STOPROBOT
        self.started_at = 0.0
        self.ball_at_start = None
        self.ball = None
        self.touched: set[int] = set()  # our robots that held the ball since the last restart
        self.passer: tuple[int, float] | None = None  # who passed last, when: it does not chase for a while
        node.create_subscription(UInt8, f"/{name}/match_mode", self.on_mode, LATCHED)
        node.create_subscription(TFMessage, "/tf_static", self.on_static, LATCHED)
        self.robots = {rid: Robot(self, rid) for rid in rids}
        self.now = 0.0

    def on_static(self, m: TFMessage) -> None:
        for t in m.transforms:
            if t.header.frame_id == "map" and t.child_frame_id == f"{self.name}/field":
                self.sign = 1.0 if abs(wrap(yaw_of(t.transform.rotation))) < 1.0 else -1.0

    def on_mode(self, m: UInt8) -> None:
        if m.data == STARTROBOT and self.mode != STARTROBOT:
            self.started_at = self.now
            self.ball_at_start = self.ball
            self.touched = set()
        elif m.data != STARTROBOT:
            self.last_stoppage = m.data
        self.mode = m.data

    def ball_seen(self, ball) -> None:
        if self.ball is None or ball[2] >= self.ball[2]:
            self.ball = ball

    def home(self, rid: int) -> tuple[float, float]:
        hx, hy = HOMES.get(rid, (-5.0, 0.0))
        return self.sign * hx, self.sign * hy

    def in_play(self) -> bool:
        """The ball may be played: START was given, and after the other team's restart it has moved (or the
        restart time is over)."""
        if self.mode != STARTROBOT:
            return False
        if self.last_stoppage not in OPP_COMMANDS and self.last_stoppage != DROPBALL:
            return True
        if self.now - self.started_at > RESTART_TIMEOUT + 0.5:
            return True
        b0, b = self.ball_at_start, self.ball
        return b0 is not None and b is not None and math.hypot(b[0] - b0[0], b[1] - b0[1]) > 0.6

    def chaser(self) -> int | None:
        ball = self.ball
        if ball is None:
            return None
        resting = self.passer[0] if self.passer is not None and self.now - self.passer[1] < 2.5 else None
        known = [r for r in self.robots.values() if r.pose is not None and r.rid not in (1, resting)]
        if not known:
            return None
        return min(known, key=lambda r: math.hypot(r.pose[0] - ball[0], r.pose[1] - ball[1])).rid

    def decide(self, r: Robot, now: float):
        """(vx, vy, w, dribble, kick) for robot ``r`` at simulated time ``now``."""
        self.now = max(self.now, now)
        goal_face = 0.0 if self.sign > 0 else math.pi
        if not self.in_play() or self.ball is None or r.rid != self.chaser():
            hx, hy = self.home(r.rid)
            return (*r.towards(hx, hy, goal_face, 2.0), False, 0.0)
        bx, by, _ = self.ball
        px, py, yaw = r.pose
        if r.holding:
            passing = len(self.touched) < 2
            aim = self.receiver(r) if passing else self.aim(r)
            err = wrap(math.atan2(aim[1] - py, aim[0] - px) - yaw)
            if abs(err) < 0.06 and now - r.kicked_at > 0.5:
                r.kicked_at = now
                if passing:
                    self.passer = (r.rid, now)
                return 0.0, 0.0, 0.0, False, PASS_SPEED if passing else KICK_SPEED
            return 0.0, 0.0, max(-2.0, min(2.0, 2.5 * err)), True, 0.0
        face = math.atan2(by - py, bx - px)
        dist = math.hypot(bx - px, by - py)
        speed = MAX_SPEED if dist > 1.5 else 1.0
        vx, vy, w = r.towards(bx, by, face, speed)
        return vx, vy, w, True, 0.0

    def receiver(self, r: Robot) -> tuple[float, float]:
        """The nearest field player of ours that has not touched the ball since the restart."""
        mates = [m for m in self.robots.values() if m is not r and m.rid != 1 and m.pose is not None]
        fresh = [m for m in mates if m.rid not in self.touched] or mates
        if not fresh:
            return self.aim(r)
        px, py, _ = r.pose
        m = min(fresh, key=lambda m: math.hypot(m.pose[0] - px, m.pose[1] - py))
        return m.pose[0], m.pose[1]

    def aim(self, r: Robot) -> tuple[float, float]:
        """The side of the opponents' goal with the wider gap to our team's other robots' idea of the field:
        simply the post farther from the shooter's line, 0.7 m inside it."""
        gx = self.sign * GOAL_X
        px, py, _ = r.pose
        side = -1.0 if py > 0 else 1.0
        return gx, side * 0.7


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--team", default="cyan")
    ap.add_argument("--robots", type=int, nargs="*", default=[1, 2, 3, 4, 5])
    ap.add_argument("--seconds", type=float, default=None, help="stop after this many wall seconds")
    args = ap.parse_args()
    rclpy.init()
    node = rclpy.create_node(f"{args.team}_ros2_team")
    Team(node, args.team, args.robots)
    t0 = time.monotonic()
    try:
        while rclpy.ok() and (args.seconds is None or time.monotonic() - t0 < args.seconds):
            rclpy.spin_once(node, timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):  # Ctrl-C: rclpy's handler has shut the context down
        pass
    finally:
        node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()


if __name__ == "__main__":
    main()
