"""Fixtures of the ROS 2 tests: real rclpy processes (the ``ros2`` extra) on a DDS domain of this test run's
own, discovery on this machine only (other people's DDS tests may run at the same time)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="ROS 2 is not installed: pip install -e '.[ros2]' (make setup does)")

from simatch.ros2 import domain, interfaces  # noqa: E402

from ..distributed.cluster import Processes  # noqa: E402

CLIENTS = Path(__file__).resolve().parent / "clients"
ROOT_EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "ros2_team"

#: one DDS domain per test session, held by nobody else on this machine (a lock kept while the session runs)
DOMAIN_ID, _DOMAIN_LOCK = domain.claim()


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

    def cyan_from_ros(self) -> subprocess.Popen:
        """A refereed msl_5v5 served in real time, cyan to be played from ROS 2, magenta standing; returned when it
        listens (the watchdog keeps a command 0.5 s: the machine may be busy)."""
        server = self.server(
            "msl_5v5", "--realtime", "--duration", "600", "--set", "control.command_timeout=0.5",
            "--set", "teams.cyan.strategy=external", "--set", "teams.magenta.strategy=none",
        )  # fmt: skip
        self.wait_for_line(server, "listening", 60)
        return server

    def observer_and_team(self) -> tuple[subprocess.Popen, subprocess.Popen]:
        """The organiser's observer bridge (ground truth, /clock), once it publishes, and cyan's team bridge."""
        observer = self.bridge(name="observer")
        self.wait_for_line(observer, "publishes the ground truth", 90)
        return observer, self.bridge("--team", "cyan", "--no-clock", key="cyan", name="team")

    def end(self, server: subprocess.Popen, *bridges: subprocess.Popen) -> dict:
        """Stop the server as Ctrl-C does; its result, once the bridges left with it."""
        server.send_signal(signal.SIGINT)
        result = self.result(server, codes=(130,))
        for p in bridges:
            self.wait(p, 30)
        return result

    def client(self, script: str, *args: str, name: str | None = None) -> subprocess.Popen:
        return self.start(*args, program=[sys.executable, str(CLIENTS / script)], name=name or script)

    def close(self) -> None:
        """Ctrl-C first (rclpy and the bridge then leave the DDS graph and remove their shared-memory files),
        then `Processes.close` kills what is left."""
        live = [p for p in self.procs if p.poll() is None]
        for p in live:
            p.send_signal(signal.SIGINT)
        deadline = time.monotonic() + 15.0
        for p in live:
            try:
                p.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                pass
        super().close()


def _fastdds_files() -> set[str]:
    try:
        return {
            n for n in os.listdir("/dev/shm") if n.startswith(("fastdds_", "fastrtps_", "sem.fastdds", "sem.fastrtps"))
        }
    except FileNotFoundError:
        return set()


def _mapped_shm() -> set[str]:
    """The /dev/shm files some live process has mapped (Fast DDS maps its segments; a lock file ``X_el``
    belongs to the segment ``X``)."""
    out = set()
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open(f"/proc/{pid}/maps") as f:
                out.update(line.rsplit("/", 1)[-1].strip() for line in f if "/dev/shm/" in line)
        except OSError:
            continue
    return out


@pytest.fixture(scope="session", autouse=True)
def no_fastdds_files_left():
    """Every ROS 2 process of these tests ends and leaves no Fast DDS shared-memory file behind: what appeared
    during the session and no live process uses is a leak (removed, and the session fails)."""
    before = _fastdds_files()
    yield
    time.sleep(0.5)
    new = _fastdds_files() - before
    if not new:
        return
    in_use = _mapped_shm()
    leaked = {n for n in new if n not in in_use and n.removesuffix("_el") not in in_use}
    for n in leaked:
        try:
            os.unlink(f"/dev/shm/{n}")
        except OSError:
            pass
    assert not leaked, f"Fast DDS files left in /dev/shm by the ROS 2 tests: {sorted(leaked)}"


@pytest.fixture
def rosprocs(tmp_path, ros_interfaces):
    ps = RosProcesses(tmp_path)
    try:
        yield ps
    finally:
        ps.close()
