"""Helpers for the distributed tests: real `simatch` processes over real Zenoh on loopback.

Every process a test starts is stopped by the fixture that started it (killed if it has not ended), and
every server gets its own port, run name and credentials folder.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SIMATCH = [sys.executable, "-m", "simatch"]
CHASER = "tests.distributed.strategies:Chaser"
PLAIN = "tests.distributed.plain_client"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def chaser_overrides(*teams: str) -> list[str]:
    out = []
    for team in teams:
        out += ["--set", f"teams.{team}.strategy={CHASER}"]
    return out


class Processes:
    """Starts `simatch` subcommands for one test and makes sure none outlives it."""

    def __init__(self, tmp: Path):
        self.tmp = tmp
        self.port = free_port()
        self.endpoint = f"tcp/127.0.0.1:{self.port}"
        self.run = f"t{os.getpid()}x{self.port}"
        self.creds = tmp / "creds"
        self.procs: list[subprocess.Popen] = []
        self.env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))

    def start(self, *args: str, name: str = "proc", program: list[str] = SIMATCH) -> subprocess.Popen:
        out = open(self.tmp / f"{name}-{len(self.procs)}.out", "w+")
        err = open(self.tmp / f"{name}-{len(self.procs)}.err", "w+")
        p = subprocess.Popen([*program, *args], stdout=out, stderr=err, cwd=ROOT, env=self.env)
        p.out, p.err, p.name = out, err, name  # type: ignore[attr-defined]
        self.procs.append(p)
        return p

    def server(self, scene: str, *args: str) -> subprocess.Popen:
        return self.start(
            "server",
            scene,
            "--listen",
            self.endpoint,
            "--run",
            self.run,
            "--credentials",
            str(self.creds),
            "--quiet",
            "--json",
            *args,
            name="server",
        )

    def client_args(self, team: str) -> list[str]:
        return ["--connect", self.endpoint, "--run", self.run, "--key", str(self.creds / f"{team}.key"), "--wait", "60"]

    def team(self, team: str, *args: str) -> subprocess.Popen:
        return self.start("team", team, *self.client_args(team), *args, name=f"team-{team}")

    def robot(self, robot: str, *args: str) -> subprocess.Popen:
        team = robot.split("/")[0]
        return self.start("robot", robot, *self.client_args(team), *args, name=f"robot-{robot.replace('/', '-')}")

    def plain(self, who: str) -> subprocess.Popen:
        """A team (TEAM) or robot (TEAM/ID) process that declines bundles: topic by topic (plain_client)."""
        team = who.split("/")[0]
        return self.start(
            who,
            *self.client_args(team)[:-2],
            program=[sys.executable, "-m", PLAIN],
            name=f"plain-{who.replace('/', '-')}",
        )

    @staticmethod
    def wait(p: subprocess.Popen, timeout: float = 120.0) -> int:
        try:
            return p.wait(timeout)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait(10)
            raise AssertionError(f"{p.name} did not end within {timeout} s:\n{Processes.stderr(p)}") from None

    @staticmethod
    def stdout(p: subprocess.Popen) -> str:
        p.out.flush()
        p.out.seek(0)
        return p.out.read()

    @staticmethod
    def stderr(p: subprocess.Popen) -> str:
        p.err.flush()
        p.err.seek(0)
        return p.err.read()

    def result(self, server: subprocess.Popen, codes: tuple[int, ...] = (0,)) -> dict:
        code = self.wait(server)
        assert code in codes, f"server exited {code}:\n{self.stderr(server)}"
        return json.loads(self.stdout(server))

    def wait_for_line(self, p: subprocess.Popen, text: str, timeout: float = 60.0) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if text in self.stderr(p):
                return
            if p.poll() is not None:
                break
            time.sleep(0.05)
        raise AssertionError(f"{p.name} never said {text!r}:\n{self.stderr(p)}")

    def close(self) -> None:
        for p in self.procs:
            if p.poll() is None:
                p.send_signal(signal.SIGKILL)
        for p in self.procs:
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                pass
            p.out.close()
            p.err.close()


def shm_segments() -> set[str]:
    """Zenoh's shared-memory files (there must be none: simatch turns shared memory off)."""
    try:
        return {n for n in os.listdir("/dev/shm") if "zenoh" in n.lower()}
    except FileNotFoundError:
        return set()
