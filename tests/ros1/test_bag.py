"""``simatch export FILE.mcap --format rosbag1``: Debian's rosbag reads the bag and plays it into ROS."""

from __future__ import annotations

import math
import subprocess
import sys
import time

import pytest

from simatch.config.loader import load_scene
from tests.ros1.conftest import ROOT, SIMATCH, text

pytestmark = pytest.mark.slow


def test_a_recording_exported_as_a_ros1_bag_plays_into_ros(ros, tmp_path):
    rec = tmp_path / "match.mcap"
    run = [*SIMATCH, "run", "msl_5v5", "--duration", "3", "--quiet", "--record", str(rec)]
    subprocess.run(run, check=True, cwd=ROOT, timeout=300, capture_output=True)
    out = subprocess.run(
        [*SIMATCH, "export", str(rec), "--format", "rosbag1"], cwd=ROOT, timeout=300, capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr
    bag = tmp_path / "match.bag"
    assert str(bag) in out.stdout
    # a second export refuses to replace the bag (one line, exit 2), which stays as it was
    before = bag.read_bytes()
    again = subprocess.run(
        [*SIMATCH, "export", str(rec), "--format", "rosbag1"], cwd=ROOT, timeout=300, capture_output=True, text=True
    )
    assert again.returncode == 2 and again.stderr.startswith("simatch: error:"), again.stderr
    assert "already exists" in again.stderr and len(again.stderr.strip().splitlines()) == 1
    assert bag.read_bytes() == before
    info = ros.run("rosbag", "info", str(bag))
    for line in (
        "/NuBot2/omnivision/OmniVisionInfo     120 msgs    : nubot_common/OminiVisionInfo",
        "/rival3/nubotcontrol/velcmd           120 msgs    : nubot_common/VelCmd",
        "/gazebo/model_states                  600 msgs    : gazebo_msgs/ModelStates",
        "/NuBot/receive_from_coach",
        "/rival/nubotcontrol/strategy",
        "/clock                                120 msgs    : rosgraph_msgs/Clock",
        "nubot_common/VelCmd              [914217797e9c6227112d1ec2a4b462eb]",
        "nubot_common/CoachInfo           [7bb01a0f4328cb28beb61d4f502c2969]",
    ):
        assert line in info, info
    # rosbag play: a subscriber receives the original's message: the ball on the centre mark, seen from NuBot2's
    # start pose (cm, cut to one decimal as rostopic prints more)
    x0, y0, _ = load_scene("msl_5v5").spec.teams["cyan"].start[1]
    radius = f"radius: {math.floor(1000.0 * math.hypot(x0, y0)) / 10:.1f}"
    ros.run("rosparam", "set", "/use_sim_time", "false")
    echo = ros.start("rostopic", "echo", "-n", "1", "/NuBot2/omnivision/OmniVisionInfo/ballinfo/real_pos", name="echo")
    time.sleep(2.0)
    play = ros.run("rosbag", "play", "-q", str(bag), timeout=120, check=False)
    assert echo.wait(30) == 0, text(echo) + play
    echo.out.seek(0)
    got = echo.out.read()
    assert radius in got, got


def test_export_refuses_what_is_not_a_recording(tmp_path):
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"not an mcap file at all")
    out = subprocess.run(
        [sys.executable, "-m", "simatch", "export", str(bad), "--format", "rosbag1"],
        cwd=ROOT,
        timeout=120,
        capture_output=True,
        text=True,
    )
    assert out.returncode == 2 and out.stderr.startswith("simatch: error:"), out.stderr
    assert len(out.stderr.strip().splitlines()) == 1
