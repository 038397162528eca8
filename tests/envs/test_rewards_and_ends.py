"""Rewards come from the scene's [learning] terms and what the judge decided; episodes end on the judge's
decisions (terminated) or a time limit (truncated). The drill judge of the learning scenes judges goals, the
ball out, the ball lost and the area left."""

from __future__ import annotations

import numpy as np
import pytest

import simatch
import simatch.envs
from simatch import msgs
from simatch.envs import rewards as R

STILL = np.zeros(6, np.float32)


def test_a_goal_pays_the_goal_term_and_ends_the_episode():
    env = simatch.envs.parallel_env("striker_1v0")
    try:
        env.reset(seed=0)
        sim = env.run.sim
        sim.set_model_state("ball", x=11.0, y=0.3, z=0.11, vx=3.0, vy=0.0, vz=0.0)
        for _ in range(10):
            _, rewards, term, trunc, infos = env.step({"cyan/1": STILL})
            if term["cyan/1"]:
                break
        assert term == {"cyan/1": True} and trunc == {"cyan/1": False}
        info = infos["cyan/1"]
        assert info["end"] == "goal" and info["rewards"]["goal"] == 10.0
        assert rewards["cyan/1"] == pytest.approx(sum(info["rewards"].values()))
        assert sim.judge.result()["score"] == {"cyan": 1} and sim.judge.result()["end"] == "goal"
        goal = [e for e in sim.events if e["type"] == "goal"][0]
        assert goal["team"] == "cyan" and "over the goal line" in goal["detail"]
    finally:
        env.close()


def test_the_ball_out_ends_the_attempt_with_its_penalty():
    env = simatch.envs.parallel_env("striker_1v0")
    try:
        env.reset(seed=0)
        env.run.sim.set_model_state("ball", x=3.0, y=7.5, z=0.11, vx=0.0, vy=2.0, vz=0.0)
        for _ in range(20):
            _, _, term, _, infos = env.step({"cyan/1": STILL})
            if term["cyan/1"]:
                break
        assert infos["cyan/1"]["end"] == "ball_out" and infos["cyan/1"]["rewards"]["event"] == -2.0
    finally:
        env.close()


def test_the_attempt_is_cut_at_the_time_limit():
    env = simatch.envs.parallel_env("striker_1v0", overrides={"judge.time_limit": 0.5})
    try:
        env.reset(seed=0)
        steps = 0
        while env.agents:
            _, _, term, trunc, infos = env.step({"cyan/1": STILL})
            steps += 1
        assert steps == 20 and trunc["cyan/1"] and not term["cyan/1"] and infos["cyan/1"]["end"] == "time_limit"
    finally:
        env.close()


def test_shaping_terms_follow_the_ball_and_the_robot():
    env = simatch.envs.parallel_env("striker_1v0")

    def step(robot_vx, ball_vx):
        sim = env.run.sim
        sim.set_model_state("cyan/1", x=0.0, y=0.0, yaw=0.0, vx=robot_vx, vy=0.0, wz=0.0)
        sim.set_model_state("ball", x=4.0, y=0.0, z=0.11, vx=ball_vx, vy=0.0, vz=0.0)
        env.run._snapshot = env.run.snapshot()
        return env.step({"cyan/1": np.array([robot_vx / env.run.limits["cyan/1"].max_vel_x, 0, 0, 0, 0, 0])})[4]

    try:
        env.reset(seed=0)
        parts = step(0.0, 2.0)["cyan/1"]["rewards"]  # the ball rolls 5 cm towards the goal, away from the robot
        assert parts["ball_progress"] == pytest.approx(0.1, abs=0.01)  # weight 2
        assert parts["ball_approach"] == pytest.approx(-0.025, abs=0.003)  # weight 0.5
        parts = step(2.0, 0.0)["cyan/1"]["rewards"]  # the robot drives 5 cm towards the resting ball
        assert parts["ball_progress"] == pytest.approx(0.0, abs=1e-3)
        assert parts["ball_approach"] == pytest.approx(0.025, abs=0.003)
    finally:
        env.close()


def test_terms_count_the_events_of_the_right_team():
    def event(kind, team):
        return msgs.GameEvent(stamp=0.0, type=kind, team=team, robot=1, x=0.0, y=0.0, value=0.0, limit=0.0, detail="")

    snap = R.Snapshot((0.0, 0.0, 0.11), {"cyan/1": (0.0, 0.0)}, "cyan", {"cyan": 1, "magenta": -1})
    events = [
        event("goal", "magenta"),
        event("charging", "cyan"),
        event("pushing", "cyan"),
        event("capture", "magenta"),
    ]
    step = R.Step(snap, snap, events, 0.025)
    cyan = R.Agent("cyan/1", "cyan", 11.0)
    terms = R.make_terms(
        {
            "goal": 1,
            "conceded": -1,
            "foul": -0.5,
            "capture": 2,
            "possession": 4,
            "event": {"type": "goal", "team": "any"},
        },
        "test",
    )
    total, parts = R.reward(terms, step, cyan)
    assert parts == {"goal": 0.0, "conceded": -1.0, "foul": -1.0, "capture": 2.0, "possession": 0.1, "event": 1.0}
    assert total == pytest.approx(1.1)


def test_a_capture_pays_the_chasers_and_ends_the_encirclement():
    env = simatch.envs.parallel_env("encirclement_4v1")
    try:
        env.reset(seed=0)
        env.run.sim.set_model_state("magenta/1", x=4.0, y=0.0, yaw=0.0, vx=0.0, vy=0.0, wz=0.0)
        _, rewards, term, _, infos = env.step({a: STILL for a in env.agents})
        assert all(term.values()) and infos["cyan/1"]["end"] == "judge"
        assert infos["cyan/3"]["rewards"]["capture"] == 10.0
    finally:
        env.close()


def test_keepaway_ends_when_a_taker_touches_the_ball_or_the_ball_leaves_the_square():
    env = simatch.envs.parallel_env("keepaway_3v2")
    try:
        env.reset(seed=0)
        steps = 0
        while env.agents:  # the keepers stand still; the takers ('simple') go for the ball
            _, _, term, _, infos = env.step({a: STILL for a in env.agents})
            steps += 1
        assert term["cyan/1"] and infos["cyan/1"]["end"] == "ball_lost"
        assert infos["cyan/1"]["rewards"]["time"] == pytest.approx(0.025)
        lost = [e for e in env.run.sim.events if e["type"] == "ball_lost"][0]
        assert lost["team"] == "magenta" and "took the ball from cyan" in lost["detail"]
        env.reset(seed=1)
        env.run.sim.set_model_state("ball", x=0.0, y=-4.5, z=0.11, vx=0.0, vy=0.0, vz=0.0)
        _, _, term, _, infos = env.step({a: STILL for a in env.agents})
        assert term["cyan/2"] and infos["cyan/2"]["end"] == "area_left"
    finally:
        env.close()


def test_the_drill_scatters_from_the_seed_inside_its_rectangles():
    def start(seed):
        with simatch.Simulation("striker_1v0", seed=seed) as sim:
            sim.step(1)
            s = sim.model_states()
            return (s["ball"].x, s["ball"].y, s["cyan/1"].x, s["cyan/1"].y, s["cyan/1"].yaw)

    a, b, c = start(5), start(5), start(6)
    assert a == b and a != c
    for bx, by, rx, ry, _ in (a, c):
        assert 2.0 <= bx <= 8.0 and -3.5 <= by <= 3.5 and 0.0 <= rx <= 7.0 and -4.5 <= ry <= 4.5
        assert np.hypot(bx - rx, by - ry) >= 0.8


def test_drill_settings_are_checked():
    from simatch.config.loader import SceneError

    with pytest.raises(SceneError, match="end_on: unknown decision"):
        simatch.Simulation("striker_1v0", overrides={"judge.end_on": ["offside"]})
    with pytest.raises(SceneError, match="no team 'blue'"):
        simatch.Simulation("striker_1v0", overrides={"judge.keepers": "blue"})
    with pytest.raises(SceneError, match="judge.area"):
        simatch.Simulation("striker_1v0", overrides={"judge.area": "nowhere"})


def test_ball_progress_follows_the_side_a_team_attacks_when_ends_change():
    """The observation is the perception, in the team frame, which turns when the teams change ends; the
    rewards read each team's side from the simulator at every step."""
    env = simatch.envs.parallel_env("msl_5v5", learners=["cyan/2"], overrides={"judge.kind": "none"})
    try:
        env.reset(seed=0)
        sim = env.run.sim
        sim.set_model_state("ball", x=0.0, y=0.0, z=0.11, vx=2.0, vy=0.0, vz=0.0)
        env.run._snapshot = env.run.snapshot()
        forward = env.step({"cyan/2": STILL})[4]["cyan/2"]["rewards"]["ball_progress"]
        sim.simulator.signs[:] *= -1  # the frames as a referee turns them at half time
        sim.set_model_state("ball", x=0.0, y=0.0, z=0.11, vx=2.0, vy=0.0, vz=0.0)
        env.run._snapshot = env.run.snapshot()
        backward = env.step({"cyan/2": STILL})[4]["cyan/2"]["rewards"]["ball_progress"]
        assert forward == pytest.approx(0.05 * 0.05, rel=0.1)  # 5 cm at weight 0.05
        assert backward == pytest.approx(-forward, rel=0.05)
    finally:
        env.close()
