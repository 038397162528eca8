"""Dribbler, kicker and perception in simatch's own types, from a plain rclpy process (tests/ros2/clients/handle.py)
through a team bridge on a real server, with the organiser's observer bridge placing the ball: ``action_cmd``
takes and kicks the ball, ``omni_vision``, ``holding_ball``, ``teammates``, ``/<team>/coach``,
``/simatch/game_state`` and ``/simatch/model_states`` say what happened."""

from __future__ import annotations

import json

import pytest

from .conftest import RosProcesses

pytestmark = pytest.mark.slow

KICK = 4.0  # [m/s] the kick's ball speed


@pytest.fixture(scope="module")
def handled(tmp_path_factory, ros_interfaces):
    tmp = tmp_path_factory.mktemp("ros2handle")
    ps = RosProcesses(tmp)
    try:
        server = ps.cyan_from_ros()
        observer, team = ps.observer_and_team()
        handle = ps.client("handle.py", "cyan", "2", str(KICK), str(tmp / "handle.json"))
        assert ps.wait(handle, 240) == 0, ps.stderr(handle)
        result = ps.end(server, team, observer)
        yield json.loads((tmp / "handle.json").read_text()), result
    finally:
        ps.close()


def test_action_cmd_takes_the_ball_with_the_dribbler_and_kicks_it(handled):
    h, result = handled
    assert h["held_at"] is not None, h["holding"][-20:]
    assert h["still_holding"]  # the dribbler kept it while the robot stood
    after = [v for t, v in h["ball_speed"] if h["kick_at"] <= t <= h["kick_at"] + 0.5]
    assert after and abs(max(after) - KICK) <= 0.15 * KICK, after
    assert not any(held for t, held in h["holding"] if t >= h["kick_at"] + 0.3)
    assert not [e for e in result["events"] if e["type"] in ("bad_command", "refused")]


def test_omni_vision_is_the_robots_perception_in_simatchs_type(handled):
    h, _ = handled
    vision = h["vision"]
    assert vision and {v[1] for v in vision} == {2}
    assert all(v[4] == 5 and v[5] == 9 for v in vision)  # its team, self included; every other robot
    before = [v[3] for v in vision[: h["vision_before_placing"]] if v[2] == 1]  # the ball on the centre mark
    held = [v[3] for v in vision if h["held_at"] <= v[0] <= h["kick_at"]]
    assert before and held and min(before) > 3.0 and max(held) < 0.5, (before[-3:], held[:3])


def test_team_and_world_topics_in_simatchs_types(handled):
    h, _ = handled
    assert set(h["teammates"]) == {4}  # its four team-mates
    assert h["modes"][-1] == 15 and 1 in h["modes"]  # OUR_KICKOFF, then STARTROBOT (the coach is latched)
    assert h["game"] and h["game"][-1][0] == ["cyan", "magenta"] and h["game"][-1][1] == [0, 0]
    assert sorted(h["models"]) == sorted(["ball"] + [f"{t}/{i}" for t in ("cyan", "magenta") for i in range(1, 6)])
