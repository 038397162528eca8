"""The bridge's number conversions (no ROS needed)."""

from __future__ import annotations

import math
from types import SimpleNamespace as NS

import numpy as np

from simatch import msgs
from simatch.ros2.convert import (
    WorldPose,
    is_bad_velocity,
    model_poses,
    quaternion_of_yaw,
    robot_pose,
    stamp_of,
    velocity_of_twist,
    world_pose,
    yaw_of_quaternion,
)


def test_team_frame_to_world_and_body_twist():
    p = world_pose(-1, np.float32(2.0), np.float32(1.0), 0.0, np.float32(1.0), 0.0, 0.5)
    assert (p.x, p.y, p.yaw, p.vx, p.vy, p.w) == (-2.0, -1.0, math.pi, -1.0, 0.0, 0.5)
    assert all(type(v) is float for v in (p.x, p.y, p.yaw, p.vx, p.vy, p.w))  # never numpy scalars (see world_pose)
    bx, by, w = WorldPose(0.0, 0.0, math.pi / 2, 0.0, 2.0, 1.0).body_twist()
    assert abs(bx - 2.0) < 1e-12 and abs(by) < 1e-12 and w == 1.0


def test_quaternions_and_stamps():
    for yaw in (-3.0, -0.5, 0.0, 1.2, 3.1):
        qx, qy, qz, qw = quaternion_of_yaw(yaw)
        assert abs(yaw_of_quaternion(qw, qx, qy, qz) - yaw) < 1e-12
    assert stamp_of(12.025) == (12, 25_000_000)
    assert stamp_of(0.9999999999) == (1, 0)


def test_model_states_arrays():
    pose = np.array([1, 2, 0, math.cos(0.25), 0, 0, math.sin(0.25), 3, 4, 0.11, 1, 0, 0, 0], dtype=np.float32)
    twist = np.array([0.5, 0, 0, 0, 0, 0.2, 1, 1, 0, 0, 0, 0], dtype=np.float32)
    poses = model_poses(["cyan/1", "ball"], pose, twist)
    assert abs(poses["cyan/1"].yaw - 0.5) < 1e-6 and poses["cyan/1"].w == np.float32(0.2)
    assert poses["ball"].x == 3.0 and poses["ball"].vy == 1.0
    assert poses["cyan/1"].z == 0.0 and abs(poses["ball"].z - 0.11) < 1e-7


def test_an_aerial_robot_keeps_its_height_and_climb():
    """A drone's altitude and climb rate reach ROS: the RobotInfo's z/vz in odom, ModelStates' z and twist.z
    in the ground truth (the frames turn x and y only)."""
    drone = msgs.new(msgs.RobotInfo, id=3, x=1.0, y=-2.0, yaw=0.0, vx=0.5, z=2.5, vz=-0.75, valid=True)
    p = robot_pose(-1, drone)
    assert (p.x, p.y, p.z, p.vz, p.vx) == (-1.0, 2.0, 2.5, -0.75, -0.5)
    pose = np.array([0, 0, 3.25, 1, 0, 0, 0], dtype=np.float32)
    twist = np.array([0, 0, 1.5, 0, 0, 0], dtype=np.float32)
    g = model_poses(["blue/1"], pose, twist)["blue/1"]
    assert (g.z, g.vz) == (3.25, 1.5)


def test_cmd_vel_carries_the_upward_speed_and_refuses_absurd_ones():
    twist = NS(linear=NS(x=1.0, y=-0.5, z=0.8), angular=NS(x=9.0, y=9.0, z=0.25))
    assert velocity_of_twist(twist) == (1.0, -0.5, 0.25, 0.8)  # angular x/y mean nothing: dropped
    assert not is_bad_velocity(1.0, -0.5, 0.25, 0.8, 50.0, 100.0)
    assert is_bad_velocity(1.0, 0.0, 0.0, 60.0, 50.0, 100.0)  # a climb beyond the limit
    assert is_bad_velocity(1.0, 0.0, 0.0, float("nan"), 50.0, 100.0)
    assert is_bad_velocity(0.0, 0.0, 101.0, 0.0, 50.0, 100.0)
