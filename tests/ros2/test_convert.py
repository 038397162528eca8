"""The bridge's number conversions (no ROS needed)."""

from __future__ import annotations

import math

import numpy as np

from simatch.ros2.convert import Pose2D, model_poses, quaternion_of_yaw, stamp_of, world_pose, yaw_of_quaternion


def test_team_frame_to_world_and_body_twist():
    p = world_pose(-1, np.float32(2.0), np.float32(1.0), 0.0, np.float32(1.0), 0.0, 0.5)
    assert (p.x, p.y, p.yaw, p.vx, p.vy, p.w) == (-2.0, -1.0, math.pi, -1.0, 0.0, 0.5)
    assert all(type(v) is float for v in (p.x, p.y, p.yaw, p.vx, p.vy, p.w))  # never numpy scalars (see world_pose)
    bx, by, w = Pose2D(0.0, 0.0, math.pi / 2, 0.0, 2.0, 1.0).body_twist()
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
