"""The environment is the embedded run and nothing else: the same physics, perception, referee and
determinism, one control period per step, observations that are the robots' own perception."""

from __future__ import annotations

import math

import numpy as np
import pytest

import simatch
import simatch.envs
from simatch.envs.observation import Layout


def zeros(env):
    return {a: np.zeros(env.action_space(a).shape, np.float32) for a in env.agents}


def test_a_step_is_one_control_period_and_the_run_is_held_before_the_robots_decide():
    env = simatch.envs.parallel_env("msl_5v5")
    try:
        env.reset(seed=0)
        sim = env.run.sim
        assert sim.clock.holding and sim.simulator.step_index == 0
        for k in range(1, 4):
            env.step(zeros(env))
            assert sim.simulator.step_index == 5 * k and math.isclose(sim.time, 0.025 * k)
            assert sim.clock.holding
    finally:
        env.close()


@pytest.mark.slow
def test_learners_that_stand_still_give_the_run_that_simatch_run_gives():
    """Held steps change nothing: an episode whose learners are told to stand still is bit for bit the plain
    run of the same scene and seed (where a learner with no environment stands still)."""
    seconds = 3.0
    env = simatch.envs.parallel_env("msl_5v5", learners=["cyan/2", "magenta/4"])
    try:
        env.reset(seed=7)
        for _ in range(round(seconds / 0.025)):
            env.step(zeros(env))
        overrides = {"teams.cyan.learners": [2], "teams.magenta.learners": [4]}
        with simatch.Simulation("msl_5v5", seed=7, overrides=overrides) as plain:
            plain.run(seconds=seconds)
            assert plain.state_digest() == env.run.sim.state_digest()
    finally:
        env.close()


@pytest.mark.slow
def test_the_same_seed_and_actions_give_the_same_observations_bit_for_bit():
    def episode(seed):
        env = simatch.envs.parallel_env("msl_5v5", overrides={"perception.position_noise": 0.05})
        rng = np.random.default_rng(123)
        out = []
        try:
            obs, _ = env.reset(seed=seed)
            out.append(np.concatenate([obs[a] for a in env.agents]))
            for _ in range(40):
                actions = {a: rng.uniform(-1, 1, 6).astype(np.float32) for a in env.agents}
                obs, rewards, *_ = env.step(actions)
                out.append(np.concatenate([obs[a] for a in env.agents]))
            return np.stack(out), env.run.sim.state_digest()
        finally:
            env.close()

    a, digest_a = episode(3)
    b, digest_b = episode(3)
    c, _ = episode(4)
    assert a.tobytes() == b.tobytes() and digest_a == digest_b
    assert a.tobytes() != c.tobytes()  # the noise is the seed's


def test_reset_without_a_seed_continues_from_the_last_seed():
    def firsts():
        env = simatch.envs.parallel_env("striker_1v0")
        try:
            out = [env.reset(seed=11)[0]["cyan/1"]]
            out += [env.reset()[0]["cyan/1"] for _ in range(2)]
            return out
        finally:
            env.close()

    one, two = firsts(), firsts()
    assert all(x.tobytes() == y.tobytes() for x, y in zip(one, two))
    assert one[1].tobytes() != one[2].tobytes()  # another attempt each time (the drill scatters from the seed)


def test_the_observation_is_the_robots_own_perception_in_its_team_frame():
    env = simatch.envs.parallel_env("msl_5v5", learners=["magenta"])
    try:
        obs, _ = env.reset(seed=0)
        layout = env.run.layouts["magenta/2"]
        parts = layout.split(obs["magenta/2"])
        world = env.run.sim.robot_nodes["magenta/2"].world
        me = world.me
        # magenta/2 starts at world (3.5, -1) facing -x: in its team frame (turned by pi) at (-3.5, 1) facing +x
        assert parts["self"][:4].tolist() == pytest.approx([-3.5, 1.0, 1.0, 0.0], abs=1e-6)
        assert parts["self"][0] == np.float32(me.x) and parts["self"][1] == np.float32(me.y)
        ball = world.vision.ball
        assert parts["ball"][3] == np.float32(ball.x) and parts["ball"][9] == np.float32(ball.distance)
        # the goal it attacks (cyan's, world (-11, 0)) is at (11, 0) in its team frame: 14.5 m ahead, 1 m to the right
        a, d = math.atan2(-1, 14.5), math.atan2(-1, -7.5)
        expected = [math.hypot(14.5, 1), math.cos(a), math.sin(a), math.hypot(7.5, 1), math.cos(d), math.sin(d)]
        assert parts["goals"].tolist() == pytest.approx(expected, abs=1e-5)
        assert parts["teammates"].shape == (4, 11) and parts["teammates"][:, 0].tolist() == [1, 1, 1, 1]
        distances = parts["obstacles"][:, 5]
        assert parts["obstacles"].shape == (9, 9) and (np.diff(distances) >= 0).all()  # nearest first
        assert len(layout.names()) == layout.size == obs["magenta/2"].size
        assert layout.names()[layout.offsets["ball"].start + 3] == "ball.x"
    finally:
        env.close()


def test_the_game_command_is_in_the_observation():
    env = simatch.envs.parallel_env("msl_5v5")
    try:
        obs, _ = env.reset(seed=0)
        names = env.run.layouts["cyan/1"].names()
        mode = [n for n, v in zip(names, obs["cyan/1"]) if n.startswith("game.match_mode.") and v == 1]
        assert mode == ["game.match_mode.STOPROBOT"]  # the referee's first command: the match begins
        for _ in range(round(2.5 / 0.025)):
            obs, *_ = env.step(zeros(env))
        mode = [n for n, v in zip(names, obs["cyan/1"]) if n.startswith("game.match_mode.") and v == 1]
        assert mode == ["game.match_mode.OUR_KICKOFF"]
    finally:
        env.close()


def test_realism_knobs_apply_to_learners_as_to_any_robot():
    env = simatch.envs.parallel_env("striker_1v0", overrides={"perception.ball_dropout": 1.0})
    try:
        obs, _ = env.reset(seed=0)
        ball = env.run.layouts["cyan/1"].split(obs["cyan/1"])["ball"]
        assert not ball.any()  # never seen: every entry zero, pos_known 0
    finally:
        env.close()


def test_a_policy_trained_on_few_slots_reads_a_larger_scene():
    small = Layout(teammates=1, obstacles=2, half_length=11.0)
    env = simatch.envs.parallel_env("msl_5v5")
    try:
        env.reset(seed=0)
        world = env.run.sim.robot_nodes["cyan/3"].world
        v = small.encode(world.vision, world.coach, [1, 2, 4, 5])
        full = env.run.observations()["cyan/3"]
        big = env.run.layouts["cyan/3"]
        assert v.size == small.size
        assert small.split(v)["obstacles"].tolist() == big.split(full)["obstacles"][:2].tolist()
        assert small.split(v)["teammates"].tolist() == big.split(full)["teammates"][:1].tolist()
    finally:
        env.close()


def test_self_play_both_teams_learn():
    env = simatch.envs.parallel_env("msl_5v5", learners=["cyan", "magenta"])
    try:
        env.reset(seed=0)
        assert len(env.agents) == 10
        env.step(zeros(env))
    finally:
        env.close()


def test_the_state_is_the_true_world_in_the_world_frame():
    env = simatch.envs.parallel_env("striker_1v1")
    try:
        env.reset(seed=2)
        s = env.state()
        states = env.run.sim.model_states()
        assert env.state_space.contains(s) and s.shape == (3 * 2 + 6,)
        assert s[:3].tolist() == pytest.approx([states["cyan/1"].x, states["cyan/1"].y, states["cyan/1"].yaw], abs=1e-5)
        assert s[6:9].tolist() == pytest.approx([states["ball"].x, states["ball"].y, states["ball"].z], abs=1e-5)
    finally:
        env.close()
