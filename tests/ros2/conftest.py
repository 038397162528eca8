"""Fixtures of the ROS 2 tests: real rclpy processes (the ``ros2`` extra) on a DDS domain of this test run's
own, discovery on this machine only (other people's DDS tests may run at the same time)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="ROS 2 is not installed: pip install -e '.[ros2]' (make setup does)")

from simatch.ros2 import interfaces  # noqa: E402

from ..distributed.cluster import Processes  # noqa: E402

CLIENTS = Path(__file__).resolve().parent / "clients"
ROOT_EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "ros2_team"

#: one DDS domain per test session (0..232 are valid; 0 is everybody's default)
DOMAIN_ID = 100 + os.getpid() % 120


def ros_env(base: dict | None = None) -> dict:
    env = dict(base if base is not None else os.environ)
    env["ROS_DOMAIN_ID"] = str(DOMAIN_ID)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    return env


@pytest.fixture(scope="session")
def ros_interfaces():
    """simatch_msgs and tf2_msgs built with rosidl into this venv (once; minutes the first time)."""
    interfaces.build(say=lambda text: print(text, file=sys.stderr))
    assert not interfaces.missing()


class RosProcesses(Processes):
    """`Processes` on this session's ROS 2 domain, with the bridge and plain rclpy clients."""

    def __init__(self, tmp: Path):
        super().__init__(tmp)
        self.env = ros_env(self.env)

    def bridge(self, *args: str, key: str = "admin", name: str = "bridge") -> subprocess.Popen:
        return self.start(
            "ros2",
            "--connect",
            self.endpoint,
            "--run",
            self.run,
            "--key",
            str(self.creds / f"{key}.key"),
            "--wait",
            "90",
            *args,
            name=name,
        )

    def client(self, script: str, *args: str, name: str | None = None) -> subprocess.Popen:
        return self.start(*args, program=[sys.executable, str(CLIENTS / script)], name=name or script)


@pytest.fixture
def rosprocs(tmp_path, ros_interfaces):
    ps = RosProcesses(tmp_path)
    try:
        yield ps
    finally:
        ps.close()
