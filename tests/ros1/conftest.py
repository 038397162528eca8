"""ROS 1 tests: a real roscore on a free port, Debian's real ROS tools, real simatch processes.

Every process a test starts runs in its own process group and is stopped by the fixture that started it
(SIGINT, then SIGKILL); ROS logs go to a private ROS_HOME in the test's folder.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import xmlrpc.client
from pathlib import Path

import pytest
from ruamel.yaml import YAML

ROOT = Path(__file__).resolve().parents[2]
SIMATCH = [sys.executable, "-m", "simatch"]
#: magenta stands still at its start poses, its goalkeeper parked at the side line
GOALKEEPERLESS_STARTPOSE = [
    "--set",
    "teams.magenta.strategy=startpose",
    "--set",
    "teams.magenta.start=[[9.0,-7.6,3.14159],[2.0,-1.0,3.14159],[2.0,1.0,3.14159],[5.0,-2.0,3.14159],[5.0,2.0,3.14159]]",
]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Ros:
    """A roscore of its own and what a test starts against it."""

    def __init__(self, tmp: Path):
        if not shutil.which("roscore") or not shutil.which("rostopic"):
            pytest.fail("Debian's ROS 1 is missing: run scripts/install-system-deps.sh")
        from simatch.ros1.rosenv import environment

        self.tmp = tmp
        self.port = free_port()
        self.uri = f"http://127.0.0.1:{self.port}"
        home = tmp / "roshome"
        home.mkdir(exist_ok=True)
        base = dict(os.environ, ROS_HOME=str(home), ROS_IP="127.0.0.1", ROS_LOG_DIR=str(home / "log"))
        base["PYTHONPATH"] = str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")
        self.env = environment(base, master=self.uri)
        self.procs: list[subprocess.Popen] = []
        self.core = self.start("roscore", "-p", str(self.port), name="roscore")
        self.wait_master()

    def start(self, *args: str, name: str = "proc") -> subprocess.Popen:
        n = len(self.procs)
        out = open(self.tmp / f"{name}-{n}.out", "w+")
        err = open(self.tmp / f"{name}-{n}.err", "w+")
        p = subprocess.Popen(list(args), stdout=out, stderr=err, cwd=ROOT, env=self.env, start_new_session=True)
        p.out, p.err, p.name = out, err, name  # type: ignore[attr-defined]
        self.procs.append(p)
        return p

    def simatch(self, *args: str, name: str = "simatch") -> subprocess.Popen:
        return self.start(*SIMATCH, *args, name=name)

    def wait_master(self, timeout: float = 30.0) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                code, _, _ = xmlrpc.client.ServerProxy(self.uri).getPid("/test")
                if code == 1:
                    return
            except OSError:
                pass
            if self.core.poll() is not None:
                break
            time.sleep(0.2)
        pytest.fail(f"roscore did not come up at {self.uri}: {text(self.core)}")

    def run(self, *args: str, timeout: float = 60.0, check: bool = True) -> str:
        """A ROS tool's output (it runs to its end)."""
        done = subprocess.run(list(args), capture_output=True, text=True, env=self.env, timeout=timeout, cwd=self.tmp)
        if check and done.returncode != 0:
            raise AssertionError(f"{' '.join(args)} failed ({done.returncode}): {done.stderr[-2000:]}")
        return done.stdout

    def echo(self, topic: str, n: int = 1, timeout: float = 30.0) -> list[dict]:
        """``rostopic echo -n N TOPIC``, parsed."""
        out = self.run("rostopic", "echo", "-n", str(n), topic, timeout=timeout)
        docs = out.replace("\n---\n", "\0").replace("\n---", "\0").split("\0")
        return [YAML(typ="safe", pure=True).load(doc) for doc in docs if doc.strip()]

    def topics(self) -> set[str]:
        return set(self.run("rostopic", "list").split())

    def wait_topic(self, topic: str, timeout: float = 60.0) -> None:
        deadline = time.monotonic() + timeout
        while topic not in self.topics():
            if time.monotonic() > deadline:
                raise AssertionError(f"{topic} never appeared on the master")
            time.sleep(0.5)

    def launch_team(self, prefix: str = "NuBot", *args: str) -> subprocess.Popen:
        """The example team (16 nodes), once all of them are registered with the master."""
        p = self.start("roslaunch", "simatch_demo", "team.launch", f"prefix:={prefix}", *args, name=f"team-{prefix}")
        deadline = time.monotonic() + 90.0
        while True:
            nodes = self.run("rosnode", "list", check=False).split()
            if sum(1 for n in nodes if n.startswith(f"/{prefix}")) >= 16:
                return p
            if p.poll() is not None or time.monotonic() > deadline:
                raise AssertionError(f"the example team did not start: {text(p)}")
            time.sleep(0.5)

    def stop(self, p: subprocess.Popen, timeout: float = 15.0) -> None:
        if p.poll() is None:
            try:
                os.killpg(p.pid, signal.SIGINT)
                p.wait(timeout)
            except (subprocess.TimeoutExpired, ProcessLookupError):
                try:
                    os.killpg(p.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                p.wait(10)

    def close(self) -> None:
        for p in reversed(self.procs):
            self.stop(p)
            p.out.close()
            p.err.close()


def text(p: subprocess.Popen) -> str:
    p.out.flush()
    p.err.flush()
    p.out.seek(0)
    p.err.seek(0)
    return f"stdout:\n{p.out.read()[-3000:]}\nstderr:\n{p.err.read()[-3000:]}"


def result_of(p: subprocess.Popen, timeout: float = 600.0) -> dict:
    """The JSON a simatch run printed, once it has ended."""
    code = p.wait(timeout)
    assert code == 0, text(p)
    p.out.seek(0)
    return json.loads(p.out.read())


@pytest.fixture
def ros(tmp_path):
    r = Ros(tmp_path)
    try:
        yield r
    finally:
        r.close()


@pytest.fixture(scope="module")
def module_ros(tmp_path_factory):
    r = Ros(tmp_path_factory.mktemp("ros"))
    try:
        yield r
    finally:
        r.close()
