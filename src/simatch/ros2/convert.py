"""Numbers between simatch's messages and ROS 2's standard types, with no ROS import (tested on their own).

simatch's perception is in the team frame (magenta's turned by pi: every team attacks +x), ROS's odometry
in ``map`` (the world frame) with the twist in the body frame (nav_msgs/Odometry's convention: the twist is
in ``child_frame_id``). `frames` turns team into world coordinates; this module does the rest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .. import frames


@dataclass(frozen=True)
class WorldPose:
    """A robot's or the ball's pose and velocity in the world frame: x, y [m], yaw [rad], vx, vy [m/s], w
    [rad/s], and the height z [m] and upward speed vz [m/s] (0 for a ground robot, whose origin is on the
    floor; an aerial robot's altitude and climb rate, the ball's centre)."""

    x: float
    y: float
    yaw: float
    vx: float = 0.0
    vy: float = 0.0
    w: float = 0.0
    z: float = 0.0
    vz: float = 0.0

    def body_twist(self) -> tuple[float, float, float]:
        """The velocity in the body frame (x forward, y left): what nav_msgs/Odometry's twist holds."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return c * self.vx + s * self.vy, -s * self.vx + c * self.vy, self.w


def quaternion_of_yaw(yaw: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation by ``yaw`` about z (geometry_msgs/Quaternion's order)."""
    return 0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)


def yaw_of_quaternion(qw: float, qx: float, qy: float, qz: float) -> float:
    return math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


def world_pose(
    sign: int,
    x: float,
    y: float,
    yaw: float,
    vx: float = 0.0,
    vy: float = 0.0,
    w: float = 0.0,
    z: float = 0.0,
    vz: float = 0.0,
) -> WorldPose:
    """A pose and velocity given in a team frame (``sign``: +1 attacking +x, -1 attacking -x), in the world
    (heights are the same in both). Python floats: rclpy takes a numpy float32 (an element of a message's
    array) for a float64 field without converting it, and serialises garbage."""
    wx, wy = frames.point(sign, float(x), float(y))
    wvx, wvy = frames.point(sign, float(vx), float(vy))
    return WorldPose(wx, wy, frames.yaw(sign, float(yaw)), wvx, wvy, float(w), float(z), float(vz))


def robot_pose(sign: int, robot) -> WorldPose:
    """A RobotInfo (team frame) as a world pose, with its height (an aerial robot's altitude)."""
    return world_pose(sign, robot.x, robot.y, robot.yaw, robot.vx, robot.vy, robot.w, robot.z, robot.vz)


def model_poses(names, pose, twist) -> dict[str, WorldPose]:
    """ModelStates' arrays (pose: M x 7 = x y z qw qx qy qz, twist: M x 6 = v w; world frame) as world poses
    keyed by model name (``cyan/2``, ``ball``): heading, planar and upward motion (a ground robot's origin
    is on the floor, so its z is 0)."""
    out = {}
    for k, name in enumerate(names):
        p = pose[7 * k : 7 * k + 7]
        t = twist[6 * k : 6 * k + 6]
        yaw = yaw_of_quaternion(float(p[3]), float(p[4]), float(p[5]), float(p[6]))
        out[name] = WorldPose(
            float(p[0]), float(p[1]), yaw, float(t[0]), float(t[1]), float(t[5]), float(p[2]), float(t[2])
        )
    return out


def velocity_of_twist(twist) -> tuple[float, float, float, float]:
    """A geometry_msgs/Twist (body frame, SI) as VelCmd's (vx, vy, w, vz): ``linear.z`` is an aerial robot's
    upward speed (a ground robot ignores it, as the simulator does); angular x and y mean nothing to either
    and are ignored. Values are passed on as they are (the simulator refuses and counts NaN, infinite or
    absurd commands, as from any other process)."""
    lin = twist.linear
    return float(lin.x), float(lin.y), float(twist.angular.z), float(lin.z)


def is_bad_velocity(vx: float, vy: float, w: float, vz: float, max_speed: float, max_turn: float) -> bool:
    """True for what the simulator will refuse: not finite, or beyond its absurdity limits."""
    return not (abs(vx) <= max_speed and abs(vy) <= max_speed and abs(vz) <= max_speed and abs(w) <= max_turn)


def stamp_of(seconds: float) -> tuple[int, int]:
    """builtin_interfaces/Time's (sec, nanosec) of a simulated time; the nanoseconds rounded, carried over."""
    ns = round(float(seconds) * 1e9)
    return ns // 1_000_000_000, ns % 1_000_000_000
