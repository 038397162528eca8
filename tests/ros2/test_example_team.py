"""examples/ros2_team (plain rclpy, five robots in one process) plays a refereed half through the bridge
against nubot's goalkeeper-less startpose team, and scores; its goal is in the event log like anyone's."""

from __future__ import annotations

import signal
import sys

import pytest

from .conftest import ROOT_EXAMPLES, RosProcesses

pytestmark = pytest.mark.slow

#: the opponent: simatch's plumbing team (each robot holds its start pose), without its goalkeeper
OPPONENT = [
    "--set", "teams.magenta.strategy=startpose",
    "--set", "teams.magenta.ids=[2,3,4,5]",
    "--set", "teams.magenta.start=[[2.0,-1.0,3.14159],[2.0,1.0,3.14159],[5.0,-2.0,3.14159],[5.0,2.0,3.14159]]",
    "--set", "teams.magenta.goalkeeper=2",
]  # fmt: skip


def test_the_ros2_team_scores_in_a_refereed_half(rosprocs: RosProcesses):
    ps = rosprocs
    server = ps.server(
        "msl_5v5", "--set", "teams.cyan.strategy=external", "--set", "match.half_duration=60", *OPPONENT,
        "--duration", "60",
    )  # fmt: skip
    ps.wait_for_line(server, "listening", 60)
    team = ps.start(
        "--team",
        "cyan",
        "--seconds",
        "600",
        program=[sys.executable, str(ROOT_EXAMPLES / "team.py")],
        name="rclpy-team",
    )
    ps.team("magenta")
    # lockstep: the bridge waits at each tick for the team's cmd_vel (it answers every odom): deterministic
    bridge = ps.bridge("--team", "cyan", "--wait-answers", "1.0", key="cyan", name="bridge")
    out = ps.result(server)
    ps.wait(bridge, 60)
    team.send_signal(signal.SIGINT)  # as Ctrl-C: it leaves the DDS graph cleanly (no file left in /dev/shm)
    assert ps.wait(team, 30) == 0, ps.stderr(team)
    assert out["result"]["score"]["cyan"] >= 1, [e for e in out["events"] if e.get("team") == "cyan"]
    goals = [e for e in out["events"] if e["type"] == "goal" and e.get("team") == "cyan"]
    assert goals and goals[0]["robot"] in (2, 3, 4, 5)
    assert out["result"]["stage"] in ("half_time", "first_half")
    assert not [e for e in out["events"] if e["type"] in ("refused", "bad_command")]
