"""The bridge from the ROS side, with Debian's real tools against a real roscore: `simatch run msl_5v5
--ros1 cyan --realtime` (no referee), the robots driven by hand with ``rostopic pub`` as a ROS user would."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import time

import pytest

from simatch.config.loader import load_scene
from simatch.record.reader import Recording
from tests.ros1.conftest import text

pytestmark = pytest.mark.slow

RUN_SECONDS = 900.0  # longer than the tests take however loaded the machine: the last one stops the run


@pytest.fixture(scope="module")
def run(module_ros):
    ros = module_ros
    p = ros.simatch(
        "run",
        "msl_5v5",
        "--ros1",
        "cyan",
        "--realtime",
        "--ros1-wait",
        "0",
        "--duration",
        str(RUN_SECONDS),
        "--quiet",
        "--record",
        str(ros.tmp / "run.mcap"),
        "--set",
        "judge.kind=none",
        "--set",
        "teams.magenta.strategy=startpose",
        name="run",
    )
    try:
        ros.wait_topic("/NuBot2/nubotcontrol/velcmd")
    except AssertionError:
        raise AssertionError(text(p)) from None
    return ros, p


def model(ros, name: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """(x, y, z, yaw) and (vx, vy, wz) of a model, from /gazebo/model_states."""
    states = ros.echo("/gazebo/model_states")[0]
    i = states["name"].index(name)
    p, t = states["pose"][i], states["twist"][i]
    q = p["orientation"]
    yaw = math.atan2(2 * (q["w"] * q["z"] + q["x"] * q["y"]), 1 - 2 * (q["y"] ** 2 + q["z"] ** 2))
    return (p["position"]["x"], p["position"]["y"], p["position"]["z"], yaw), (
        t["linear"]["x"],
        t["linear"]["y"],
        t["angular"]["z"],
    )


def place(ros, name: str, x: float, y: float) -> None:
    state = f"{{model_name: {name}, pose: {{position: {{x: {x}, y: {y}, z: 0.11}}, orientation: {{w: 1.0}}}}}}"
    ros.run("rostopic", "pub", "-1", "/gazebo/set_model_state", "gazebo_msgs/ModelState", state)


def publish(ros, topic: str, msgtype: str, value: str, rate: float = 40.0) -> subprocess.Popen:
    return ros.start("rostopic", "pub", "-r", str(rate), topic, msgtype, value, name="pub")


def test_the_original_topics_are_on_the_master(run):
    ros, _ = run
    names = ros.topics()
    for r in ("NuBot1", "NuBot5", "rival2"):
        assert f"/{r}/omnivision/OmniVisionInfo" in names and f"/{r}/ballisholding/BallIsHolding" in names
    for r in ("NuBot1", "NuBot2", "NuBot5"):
        for leaf in ("velcmd", "actioncmd", "strategy"):
            assert f"/{r}/nubotcontrol/{leaf}" in names
    for t in (
        "/NuBot/receive_from_coach",
        "/NuBot/redcard/chatter",
        "/NuBot/nubotcontrol/strategy",
        "/rival/receive_from_coach",
    ):
        assert t in names
    assert {"/gazebo/model_states", "/gazebo/set_model_state", "/clock"} <= names
    assert "nubot_common/OminiVisionInfo" in ros.run("rostopic", "type", "/NuBot2/omnivision/OmniVisionInfo")


def test_perception_reads_the_ball_in_centimetres(run):
    ros, _ = run
    place(ros, "football", 1.5, -2.0)
    time.sleep(0.5)
    ball = ros.echo("/NuBot2/omnivision/OmniVisionInfo")[0]["ballinfo"]
    assert (ball["pos"]["x"], ball["pos"]["y"]) == pytest.approx((150.0, -200.0), abs=1.0)
    rival = ros.echo("/rival2/omnivision/OmniVisionInfo")[0]["ballinfo"]  # its team frame: mirrored
    assert (rival["pos"]["x"], rival["pos"]["y"]) == pytest.approx((-150.0, 200.0), abs=1.0)
    coach = ros.echo("/NuBot/receive_from_coach")[0]
    assert coach["MatchMode"] == 0 and coach["angleA"] == 450  # no referee: the coach says STOP


def test_nodes_on_simulated_time_follow_the_clock(run):
    ros, _ = run
    stamps = [c["clock"]["secs"] + c["clock"]["nsecs"] * 1e-9 for c in ros.echo("/clock", n=3)]
    assert stamps == sorted(stamps) and 0 < stamps[0] < RUN_SECONDS
    script = (
        "import rospy\n"
        "rospy.init_node('sim_time_probe', anonymous=True)\n"
        "rospy.sleep(0.5)\n"  # half a second of simulated time
        "print(rospy.get_param('/use_sim_time'), rospy.get_time())\n"
    )
    flag, now = ros.run("/usr/bin/python3", "-c", script).split()
    assert flag == "True" and stamps[0] < float(now) < RUN_SECONDS  # simulated, not the wall clock's 1.7e9


def test_velcmd_moves_the_robot_at_the_commanded_body_speed(run):
    ros, _ = run
    pub = publish(ros, "/NuBot2/nubotcontrol/velcmd", "nubot_common/VelCmd", "{Vx: 100.0, Vy: 50.0, w: 0.0}")
    try:
        time.sleep(2.5)
        (x, y, _, yaw), (vx, vy, _) = model(ros, "NuBot2")
    finally:
        ros.stop(pub)
    body = (math.cos(yaw) * vx + math.sin(yaw) * vy, -math.sin(yaw) * vx + math.cos(yaw) * vy)
    assert body == pytest.approx((1.0, 0.5), rel=0.02)
    assert x > load_scene("msl_5v5").spec.teams["cyan"].start[1][0] + 1.0  # it left its start pose
    time.sleep(1.0)  # its node is gone: the watchdog stops it
    _, (vx, vy, _) = model(ros, "NuBot2")
    assert math.hypot(vx, vy) < 0.05


def test_dribble_and_kick(run):
    ros, _ = run
    (x, y, _, yaw), _ = model(ros, "NuBot3")
    place(ros, "football", x + 0.45 * math.cos(yaw), y + 0.45 * math.sin(yaw))
    vel = publish(ros, "/NuBot3/nubotcontrol/velcmd", "nubot_common/VelCmd", "{Vx: 20.0, Vy: 0.0, w: 0.0}")
    hold = publish(ros, "/NuBot3/nubotcontrol/actioncmd", "nubot_common/ActionCmd", "{handle_enable: 1, shootPos: 1}")
    try:
        deadline = time.monotonic() + 20.0
        while ros.echo("/NuBot3/ballisholding/BallIsHolding")[0]["BallIsHolding"] != 1:
            assert time.monotonic() < deadline, "NuBot3 never held the ball"
        ros.stop(hold)
        (bx0, by0, _, _), _ = model(ros, "football")
        kick = publish(
            ros, "/NuBot3/nubotcontrol/actioncmd", "nubot_common/ActionCmd", "{strength: 5.0, shootPos: 1}", rate=10
        )
        deadline = time.monotonic() + 20.0
        while True:  # the first kick request that finds the ball in the mouth fires
            (bx, by, _, _), _ = model(ros, "football")
            if math.hypot(bx - bx0, by - by0) > 1.5 or time.monotonic() > deadline:
                break
        ros.stop(kick)
    finally:
        ros.stop(hold)
        ros.stop(vel)
    assert math.hypot(bx - bx0, by - by0) > 1.5, "the kick did not send the ball away"
    assert ros.echo("/NuBot3/ballisholding/BallIsHolding")[0]["BallIsHolding"] == 0


def test_bad_messages_are_refused_and_counted(run):
    ros, p = run
    for value in ("{Vx: .nan, Vy: 0.0, w: 0.0}", "{Vx: 1.0e12, Vy: 0.0, w: 0.0}"):
        ros.run("rostopic", "pub", "-1", "/NuBot4/nubotcontrol/velcmd", "nubot_common/VelCmd", value)
    ros.run("rostopic", "pub", "-1", "/NuBot9/nubotcontrol/velcmd", "nubot_common/VelCmd", "{Vx: 100.0}")
    place(ros, "NuBot7", 0.0, 0.0)
    time.sleep(3.0)  # the bridge reads the master's topics every second
    p.err.flush()
    p.err.seek(0)
    err = p.err.read()
    assert "/NuBot9/nubotcontrol/velcmd" in err and "no such robot" in err
    assert "refused: set_model_state: no model 'NuBot7'" in err


def test_the_run_logs_what_ros_did(run):
    ros, p = run
    os.killpg(p.pid, signal.SIGINT)  # Ctrl-C: the run stops, its recording is finalised
    assert p.wait(60) == 130, text(p)
    rec = Recording(ros.tmp / "run.mcap")
    events = [
        {"type": m.type, "team": m.team, "robot": int(m.robot), "detail": m.detail}
        for _, _, m in rec.messages(topics={"events"})
    ]
    bad = [e for e in events if e["type"] == "bad_command" and e.get("team") == "cyan" and e.get("robot") == 4]
    assert bad, [e for e in events if e["type"] not in ("command",)]
    stops = {(e.get("team"), e.get("robot")) for e in events if e["type"] == "watchdog_stop"}
    assert ("cyan", 2) in stops and ("cyan", 3) in stops
    p.err.seek(0)
    err = p.err.read()
    assert "bridge stopped: forwarded_velcmd" in err
