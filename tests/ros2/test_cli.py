"""``simatch ros2``'s refusals: one clear line, exit code 2, nothing joined."""

from __future__ import annotations

import subprocess
import sys

import pytest

from .conftest import RosProcesses, ros_env

SIMATCH = [sys.executable, "-m", "simatch", "ros2"]


@pytest.mark.parametrize(
    "args, says",
    [
        (["--robot", "cyan/x"], "not a robot name"),
        (["--robot", "cyan/1", "--robot", "magenta/2"], "one bridge drives robots of one team"),
        (["--domain-id", "500"], "a ROS 2 domain id is 0..232"),
    ],
)
def test_bad_options(args, says):
    out = subprocess.run([*SIMATCH, *args], capture_output=True, text=True, env=ros_env(), timeout=120)
    assert out.returncode == 2 and says in out.stderr, out.stderr
    assert out.stderr.strip().count("\n") == 0, out.stderr


@pytest.mark.slow
def test_a_team_credential_drives_only_its_team_and_sees_no_ground_truth(rosprocs: RosProcesses):
    ps = rosprocs
    server = ps.server("msl_5v5", "--set", "teams.cyan.strategy=external", "--team-timeout", "60")
    ps.wait_for_line(server, "listening", 60)
    other = ps.bridge("--team", "magenta", key="cyan", name="other-team")
    world = ps.bridge("--team", "cyan", "--world", key="cyan", name="world")
    for p, says in ((other, "is the credential of cyan, not of team magenta"), (world, "needs the organiser's admin")):
        assert ps.wait(p, 120) == 2, ps.stderr(p)
        assert says in ps.stderr(p), ps.stderr(p)
    assert "joined" not in ps.stderr(server)
