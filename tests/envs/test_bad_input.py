"""Bad actions get a clear error naming the agent (or are clipped, as documented) and never reach the physics;
an environment used after close() raises."""

from __future__ import annotations

import numpy as np
import pytest

import simatch.envs


@pytest.fixture
def env():
    e = simatch.envs.parallel_env("striker_1v0")
    e.reset(seed=0)
    yield e
    e.close()


def fingerprint(env):
    run = env.run
    return run.sim.state_digest(), run.sim.simulator.step_index, run._learners["cyan/1"].command


@pytest.mark.parametrize(
    "action, message",
    [
        (np.zeros(5), "expected shape (6,)"),
        (np.zeros((2, 6)), "expected shape (6,)"),
        ([0.0, 0.0, float("nan"), 0.0, 0.0, 0.0], "w=nan is not a finite number"),
        ([float("inf"), 0.0, 0.0, 0.0, 0.0, 0.0], "vx=inf is not a finite number"),
        (["fast", 0, 0, 0, 0, 0], "expected 6 numbers"),
        (None, "expected"),
    ],
)
def test_a_bad_action_is_refused_with_the_agent_named_and_nothing_changes(env, action, message):
    env.step({"cyan/1": np.array([0.5, 0, 0, 1, 0, 0], np.float32)})
    before = fingerprint(env)
    with pytest.raises(ValueError, match="action of cyan/1") as err:
        env.step({"cyan/1": action})
    assert message in str(err.value)
    assert fingerprint(env) == before  # no step taken, the robot's command as it was
    env.step({"cyan/1": np.zeros(6, np.float32)})  # and the environment goes on
    assert env.run.sim.simulator.step_index == before[1] + 5


def test_unknown_and_missing_agents_are_refused(env):
    with pytest.raises(ValueError, match="unknown agent"):
        env.step({"cyan/1": np.zeros(6), "magenta/1": np.zeros(6)})
    with pytest.raises(ValueError, match="no action for agent"):
        env.step({})
    with pytest.raises(ValueError, match="must be a dict"):
        env.step([np.zeros(6)])


def test_out_of_bounds_numbers_are_clipped_or_refused_when_strict(env):
    env.step({"cyan/1": np.array([7.0, -3.0, 0.0, 0.0, 0.0, 0.0])})
    cmd = env.run._learners["cyan/1"].command
    limits = env.run.limits["cyan/1"]
    assert cmd.vx == pytest.approx(limits.max_vel_x) and cmd.vy == pytest.approx(-limits.max_vel_y)
    strict = simatch.envs.parallel_env("striker_1v0", strict_actions=True)
    try:
        strict.reset(seed=0)
        with pytest.raises(ValueError, match=r"vx=7 outside \[-1, 1\]"):
            strict.step({"cyan/1": np.array([7.0, 0, 0, 0, 0, 0])})
    finally:
        strict.close()


def test_huge_numbers_are_clipped_and_the_physics_stays_sane(env):
    for _ in range(40):
        env.step({"cyan/1": np.full(6, 1e30)})
    state = env.run.sim.model_states()["cyan/1"]
    assert np.isfinite([state.x, state.y, state.vx, state.vy]).all()
    assert np.hypot(state.vx, state.vy) < 8.0  # the wheel limits hold


def test_discrete_actions_are_checked():
    env = simatch.envs.parallel_env("striker_1v0", action_type="discrete")
    try:
        env.reset(seed=0)
        env.step({"cyan/1": 1})
        env.step({"cyan/1": np.int64(10)})
        for bad in (12, -1, 2.5, "kick", float("nan"), [1, 2]):
            with pytest.raises(ValueError, match="action of cyan/1"):
                env.step({"cyan/1": bad})
    finally:
        env.close()


def test_use_after_close_raises():
    env = simatch.envs.parallel_env("striker_1v0")
    env.reset(seed=0)
    env.close()
    with pytest.raises(RuntimeError, match="closed"):
        env.step({"cyan/1": np.zeros(6)})
    with pytest.raises(RuntimeError, match="closed"):
        env.reset(seed=0)
    with pytest.raises(RuntimeError, match="closed"):
        env.state()
    env.close()  # closing twice is harmless
    gym = simatch.envs.SimatchEnv("striker_1v0")
    gym.close()
    with pytest.raises(RuntimeError, match="closed"):
        gym.reset(seed=0)


def test_step_before_reset_and_after_the_end_raises():
    env = simatch.envs.parallel_env("striker_1v0", episode_time=0.05)
    try:
        with pytest.raises(RuntimeError, match="reset"):
            env.step({"cyan/1": np.zeros(6)})
        env.reset(seed=0)
        env.step({"cyan/1": np.zeros(6)})
        _, _, term, trunc, infos = env.step({"cyan/1": np.zeros(6)})
        assert trunc == {"cyan/1": True} and term == {"cyan/1": False} and infos["cyan/1"]["end"] == "episode_time"
        assert env.agents == []
        with pytest.raises(RuntimeError, match="reset"):
            env.step({"cyan/1": np.zeros(6)})
    finally:
        env.close()


def test_bad_options_and_scenes_are_refused_clearly():
    from simatch.config.loader import SceneError

    with pytest.raises(SceneError, match="no team 'blue'"):
        simatch.envs.parallel_env("msl_5v5", learners=["blue"])
    with pytest.raises(SceneError, match="'cyan/9' is not a robot"):
        simatch.envs.parallel_env("msl_5v5", learners=["cyan/9"])
    with pytest.raises(ValueError, match="action_type"):
        simatch.envs.parallel_env("striker_1v0", action_type="joystick")
    with pytest.raises(ValueError, match="observation form"):
        simatch.envs.parallel_env("striker_1v0", observation="pixels")
    with pytest.raises(ValueError, match="max_vel must be a positive number"):
        simatch.envs.parallel_env("striker_1v0", max_vel=-1.0)
    with pytest.raises(ValueError, match="do not render"):
        simatch.envs.parallel_env("striker_1v0", render_mode="human")
    with pytest.raises(SceneError, match="needs one"):
        simatch.envs.SimatchEnv("keepaway_3v2")
    with pytest.raises(SceneError, match=r"learning.rewards.scored: unknown reward term 'scored'"):
        simatch.envs.parallel_env("striker_1v0", overrides={"learning.rewards.scored": 1.0})
    with pytest.raises(SceneError, match=r"learning.rewards.event.team"):
        simatch.envs.parallel_env("striker_1v0", overrides={"learning.rewards.event": {"type": "x", "team": "us"}})
    with pytest.raises(SceneError, match=r"teams.cyan: learners: the team has no robot\(s\) \[7\]"):
        simatch.envs.parallel_env("msl_5v5", overrides={"teams.cyan.learners": [7]})
