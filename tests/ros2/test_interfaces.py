"""simatch_msgs and tf2_msgs built with ROS 2's rosidl tools: rclpy announces the same RIHS01 type hashes as
the bus's type store (rosbags) and as every ROS 2 installation (tf2_msgs), and makes the same CDR bytes."""

from __future__ import annotations

import json
import subprocess
import sys

from rosbags.typesys import Stores, get_typestore

from simatch import msgs
from simatch.ros2 import interfaces

from .conftest import CLIENTS, ros_env


def test_rclpy_sees_the_same_types_as_the_bus(ros_interfaces):
    names = msgs.names() + ["tf2_msgs/msg/TFMessage"]
    out = subprocess.run(
        [sys.executable, str(CLIENTS / "hashes.py"), *names],
        capture_output=True,
        text=True,
        env=ros_env(),
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    for name in msgs.names():
        assert got[name] == msgs.typestore.hash_rihs01(name), name
    assert got["tf2_msgs/msg/TFMessage"] == get_typestore(Stores.ROS2_KILTED).hash_rihs01("tf2_msgs/msg/TFMessage")
    cmd = msgs.new(msgs.VelCmd, stamp=1.5, tick=3, vx=1.0, vy=-0.5, w=0.25)
    assert bytes.fromhex(got["velcmd_cdr"]) == msgs.encode(cmd)  # the bridge forwards the bus's bytes as they are


def test_built_once_and_up_to_date(ros_interfaces):
    assert interfaces.missing() == []
    assert interfaces.build() == []  # nothing to do: the stamps match the definitions
    pkgs = {p.name: p for p in interfaces.packages()}
    assert set(pkgs["simatch_msgs"].messages) == {n.rsplit("/", 1)[1] for n in msgs.names()}
