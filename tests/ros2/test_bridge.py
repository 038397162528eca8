"""The bridge against a real server, checked from separate rclpy processes (tests/ros2/clients: plain rclpy).

One refereed msl_5v5 run in real time (the watchdog keeps a command 0.5 s: the machine may be busy): cyan
is played from ROS 2 through a team bridge (cyan's credential), magenta stands; an observer bridge (the
organiser's credential) publishes the ground truth and /clock. A client drives cyan/2 with cmd_vel and
records its odom and /clock, then sends a NaN command; another turns cyan/4 with ROS 2's default QoS on every
topic; another watches markers, /tf, both teams'
match_mode and the events; at the end a third places the ball through the observer (the organiser's
set_model_state, forwarded to the server's world service).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from simatch.config.loader import load_scene

from .conftest import RosProcesses

pytestmark = pytest.mark.slow

VX = -1.0  # [m/s] cyan/2 drives back from its start (-3.5, 1): nothing in its way for 3 m
TURN = 1.0  # [rad/s] cyan/4 turns on the spot, driven and heard by a node with ROS 2's default QoS
BALL_AT = (3.0, -2.0)  # [m] where the organiser's client places the ball (world frame), after the driving


@pytest.fixture(scope="module")
def match(tmp_path_factory, ros_interfaces):
    tmp = tmp_path_factory.mktemp("ros2match")
    ps = RosProcesses(tmp)
    try:
        server = ps.cyan_from_ros()
        watch = ps.client("watch.py", "90", str(tmp / "watch.json"), "cyan", "magenta")
        observer, team = ps.observer_and_team()
        drive = ps.client("drive.py", "/cyan/robot2", str(VX), "0", "0", "2.5", str(tmp / "drive.json"), "--nan")
        default = ps.client("default_qos.py", "/cyan/robot4", str(TURN), "2.0", str(tmp / "default.json"))
        assert ps.wait(drive, 150) == 0, ps.stderr(drive)
        assert ps.wait(default, 150) == 0, ps.stderr(default)
        assert ps.wait(watch, 150) == 0, ps.stderr(watch)
        place = ps.client("place.py", *map(str, BALL_AT), str(tmp / "place.json"))
        assert ps.wait(place, 120) == 0, ps.stderr(place)
        result = ps.end(server, team, observer)
        yield {
            "drive": json.loads((tmp / "drive.json").read_text()),
            "watch": json.loads((tmp / "watch.json").read_text()),
            "place": json.loads((tmp / "place.json").read_text()),
            "default": json.loads((tmp / "default.json").read_text()),
            "result": result,
            "team_err": ps.stderr(team),
            "observer_err": ps.stderr(observer),
        }
    finally:
        ps.close()


def test_the_robot_moves_at_the_commanded_body_speed(match):
    d = match["drive"]
    odom = np.array(sorted(o[:7] for o in d["odom"]), dtype=float)  # best effort: may come out of order
    assert all(o[7] == "map" and o[8] == "cyan/robot2/base_link" for o in d["odom"])
    moving = odom[np.hypot(odom[:, 4], odom[:, 5]) > 0.5 * abs(VX), 0]
    assert moving.size, "the robot never moved"
    # steady state: from 0.5 s after it started moving to the last command sent before the NaN
    steady = odom[(odom[:, 0] >= moving[0] + 0.5) & (odom[:, 0] <= d["last_sent"])]
    assert len(steady) >= 20, f"{len(steady)} odom messages in the steady part"
    speed = np.hypot(steady[:, 4], steady[:, 5])
    assert np.all(np.abs(speed - abs(VX)) <= 0.02 * abs(VX)), speed
    # and the pose agrees: distance over simulated time
    dist = math.hypot(steady[-1, 1] - steady[0, 1], steady[-1, 2] - steady[0, 2])
    assert abs(dist / (steady[-1, 0] - steady[0, 0]) - abs(VX)) <= 0.02 * abs(VX)
    assert np.all(steady[:, 1][1:] <= steady[:, 1][:-1] + 1e-6)  # backwards, in the world's -x


def test_a_node_with_the_default_qos_drives_and_hears_its_robot(match):
    """Reliable subscriptions (ROS 2's default, what most tutorials and nav2-style nodes make) get every state
    topic: the bridge publishes reliable, which best-effort (sensor-data) subscribers also match."""
    d = match["default"]
    assert all(n > 0 for n in d["counts"].values()), d["counts"]
    steady = d["turning"][len(d["turning"]) // 2 :]
    assert len(steady) >= 10, d
    assert all(abs(w - TURN) <= 0.02 * TURN for w in steady), steady


def test_clock_is_simulated_time_and_stamps_odom(match):
    d = match["drive"]
    clock = np.array(d["clock"])
    assert len(clock) > 50
    assert np.all(np.diff(clock) > 0)
    steps = np.diff(clock)
    assert np.allclose(np.median(steps), 0.025, atol=1e-9)  # one /clock per control period
    stamps = {round(o[0], 6) for o in d["odom"]}
    assert stamps & {round(c, 6) for c in clock}
    # a use_sim_time node's clock is simulated time (not the wall's 1.7e9 s): mostly the odom's own stamp (the odom
    # of a tick goes out just after that tick's /clock), a few periods off when the busy machine delays a message
    lag = np.array([now - stamp for stamp, now in d["node_time"] if now > 0.0])
    assert len(lag) > 50 and np.median(np.abs(lag)) <= 0.0251 and np.max(np.abs(lag)) < 1.0, lag


def test_markers_and_tf_have_every_robot_and_the_ball(match):
    w = match["watch"]
    robots = [f"robots/{t}:{i}" for t in ("cyan", "magenta") for i in range(1, 6)]
    markers = {m.rsplit(":", 1)[0] for m in w["markers"]}
    assert set(robots) <= markers
    assert "ball:0:True" in w["markers"]  # a sphere
    frames = {f"map->{t}/robot{i}/base_link" for t in ("cyan", "magenta") for i in range(1, 6)} | {"map->ball"}
    assert frames <= set(w["tf"])


def test_game_command_changes_reach_every_team_mirrored(match):
    modes = match["watch"]["modes"]
    cyan = [m for _, m in modes["cyan"]]
    magenta = [m for _, m in modes["magenta"]]
    assert len(cyan) >= 3 and len(magenta) >= 3, modes
    # the kick-off is cyan's: OUR_KICKOFF (1) for cyan, OPP_KICKOFF (2) for magenta, then START (15)
    assert 1 in cyan and 2 in magenta
    assert cyan.index(1) < len(cyan) - 1 and 15 in cyan[cyan.index(1) :]


def test_a_nan_cmd_vel_is_refused_and_counted(match):
    d, w = match["drive"], match["watch"]
    bad = [e for e in w["events"] if e[1] == "bad_command"]
    assert bad and bad[0][2] == "cyan" and bad[0][3] == 2, w["events"]
    assert "nan" in bad[0][4].lower()
    assert any(e["type"] == "bad_command" and e.get("team") == "cyan" for e in match["result"]["events"])
    # not repeated: the robot has no command then, and the watchdog stops it
    assert any(
        e["type"] == "watchdog_stop" and e.get("robot") == 2 and e["t"] >= d["nan_at"]
        for e in match["result"]["events"]
    )
    assert "1 refused as bad" in match["team_err"], match["team_err"]


def test_perceived_obstacles_are_where_the_robots_stand(match):
    seen = np.array(match["drive"]["obstacles"])
    assert len(seen) == 9  # every other robot
    for x, y, _ in load_scene("msl_5v5").spec.teams["magenta"].start:  # magenta stands at its start (world frame)
        assert np.min(np.hypot(seen[:, 0] - x, seen[:, 1] - y)) < 0.05, (x, y, seen)


def test_the_organisers_bridge_places_the_ball_on_the_server(match):
    after = match["place"]["after"]
    assert any(abs(x - BALL_AT[0]) < 0.05 and abs(y - BALL_AT[1]) < 0.05 for _, x, y in after), after
