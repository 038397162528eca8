"""A team of ROS nodes in the original's process layout (the example team simatch_demo, 16 rospy nodes)
plays through the bridge: it scores in a refereed match, deterministically in lockstep, and plays a
refereed half against nubot in a distributed run, where fair play and the watchdog hold through the bridge."""

from __future__ import annotations

import time

import pytest

from tests.distributed.cluster import free_port
from tests.ros1.conftest import GOALKEEPERLESS_STARTPOSE, result_of, text

pytestmark = pytest.mark.slow


def embedded_match(ros, seconds: float) -> dict:
    team = ros.launch_team("NuBot")
    try:
        p = ros.simatch(
            "run", "msl_5v5", "--ros1", "cyan", "--duration", str(seconds), "--json", "--quiet",
            *GOALKEEPERLESS_STARTPOSE, name="match",
        )  # fmt: skip
        return result_of(p, timeout=seconds * 10)
    finally:
        ros.stop(team)


def test_the_ros_team_scores_in_a_refereed_match_and_plays_deterministically(ros):
    first = embedded_match(ros, 25.0)
    goals = [e for e in first["events"] if e["type"] == "goal"]
    assert first["result"]["score"]["cyan"] >= 1, [e for e in first["events"] if e["type"] != "command"]
    assert goals[0]["team"] == "cyan" and goals[0]["t"] < 25.0
    assert not [e for e in first["events"] if e["type"] == "watchdog_stop"]
    second = embedded_match(ros, 25.0)  # a fresh team, the same scene and seed: the same match
    assert second["state_digest"] == first["state_digest"]
    assert second["result"]["score"] == first["result"]["score"]


def test_a_refereed_half_against_nubot_on_a_server(ros, tmp_path):
    port = free_port()
    endpoint, run, creds = f"tcp/127.0.0.1:{port}", f"ros{port}", tmp_path / "creds"
    server = ros.simatch(
        "server", "msl_5v5", "--listen", endpoint, "--run", run, "--credentials", str(creds), "--json", "--quiet",
        "--set", "match.halves=1", "--set", "match.half_duration=120", "--team-timeout", "120",
        name="server",
    )  # fmt: skip
    team = ros.launch_team("NuBot")
    client = ["--connect", endpoint, "--run", run, "--wait", "60"]
    bridge = ros.simatch("ros1", "cyan", *client, "--key", str(creds / "cyan.key"), name="bridge")
    magenta = ros.simatch("team", "magenta", *client, "--key", str(creds / "magenta.key"), name="magenta")
    try:
        ros.wait_topic("/NuBot/receive_from_coach")
        # a team's bridge carries that team only: no world, no opponents' robots
        names = ros.topics()
        assert "/gazebo/model_states" not in names and "/gazebo/set_model_state" not in names
        assert "/rival2/omnivision/OmniVisionInfo" not in names
        rogue = ros.start(
            "rostopic", "pub", "-r", "10", "/rival2/nubotcontrol/velcmd", "nubot_common/VelCmd", "{Vx: 300.0}"
        )
        time.sleep(20.0)
        ros.stop(rogue)
        ros.run("rosnode", "kill", "/NuBot4_nubot_hwcontroller")  # a node dies: its robot stops, play goes on
        out = result_of(server, timeout=900)
        assert bridge.wait(60) == 0, text(bridge)
    finally:
        ros.stop(team)
    r, events = out["result"], out["events"]
    assert r["ended"] and out["sim_seconds"] >= 120.0
    cyan = [e for e in events if e.get("team") == "cyan" and e["type"] not in ("command", "process_joined")]
    assert any(e["type"] in ("ball_in_play", "goal", "goal_disallowed", "ball_out") for e in cyan), cyan
    stops = [e for e in events if e["type"] == "watchdog_stop"]
    assert [(e["team"], e["robot"]) for e in stops] == [("cyan", 4)], stops
    refused = [e for e in events if e["type"] == "refused"]
    assert not refused  # the bridge never even sent the opponent's command: it serves cyan only
    bridge.err.seek(0)
    err = bridge.err.read()
    assert "/rival2/nubotcontrol/velcmd" in err and "NuBot4" in err and "forwarded_velcmd" in err
    assert magenta.wait(60) == 0


def test_the_original_habits_play_a_whole_match_through_the_bridge(ros):
    """The example team with the original Simatch's own habits at the opponents' restarts (``original:=true``:
    3.2 m from the ball, and for the ball at START whoever's restart it is), against nubot, embedded: the
    original's code froze such a match (one free kick retaken 30 times); now its robots are cautioned and
    sent off, no restart is taken again more than three times in a row, and the match reaches its end."""
    team = ros.launch_team("NuBot", "original:=true")
    try:
        p = ros.simatch(
            "run", "msl_5v5", "--ros1", "cyan", "--json", "--quiet",
            "--set", "match.half_duration=90", "--set", "match.half_time=5", name="match",
        )  # fmt: skip
        out = result_of(p, timeout=1500)
    finally:
        ros.stop(team)
    r, events = out["result"], out["events"]
    assert r["ended"] and out["sim_seconds"] >= 185.0
    retaken = [e for e in events if e["type"] == "set_piece_distance" and "taken again" in e["detail"]]
    cautions = [e for e in events if e["type"] == "yellow_card" and "respecting the distance" in e["detail"]]
    assert retaken and len(cautions) == len(retaken), [e for e in events if e["type"] != "command"]
    assert all(e["team"] == "cyan" for e in cautions)
    assert sum(e["type"] == "ball_in_play" for e in events) >= 3
