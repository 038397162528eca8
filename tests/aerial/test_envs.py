"""The learning environments accept the aerial scenes: drones learn with their climb in the action and
every robot's height in the observation (PettingZoo's and Gymnasium's own checkers, and the physics)."""

from __future__ import annotations

import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test

import simatch.envs
from simatch.envs.action import AERIAL_NAMES


@pytest.mark.slow
def test_the_aerial_scenes_pass_the_parallel_api_test():
    for scene, learners in (("pursuit_evasion_3d", ["cyan", "magenta"]), ("aerial_encirclement", ["cyan"])):
        env = simatch.envs.parallel_env(scene, learners=learners)
        try:
            parallel_api_test(env, num_cycles=60)
        finally:
            env.close()


@pytest.mark.parametrize("options", [{}, {"action_type": "discrete", "observation": "dict"}])
def test_gymnasium_check_env_on_a_drone(options):
    env = gymnasium.make("simatch/pursuit_evasion_3d-v0", agent="cyan/2", **options)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            check_env(env.unwrapped)
    finally:
        env.close()


def test_a_drone_agent_climbs_and_sees_heights():
    env = simatch.envs.parallel_env("aerial_encirclement", learners=["cyan/2", "cyan/11"])
    try:
        obs, _ = env.reset(seed=0)
        assert env.action_space("cyan/2").shape == (6,) and env.action_space("cyan/11").shape == (7,)
        names = env.unwrapped.run.layouts["cyan/11"].names()
        z_at = names.index("heights.self.z")
        assert obs["cyan/11"][z_at] == pytest.approx(0.0, abs=0.02)  # landed
        climb = np.zeros(len(AERIAL_NAMES), dtype=np.float32)
        climb[AERIAL_NAMES.index("vz")] = 1.0  # full climb: its controller's max_climb
        for _ in range(40):  # two seconds
            obs, *_ = env.step({"cyan/2": np.zeros(6, dtype=np.float32), "cyan/11": climb})
        z = env.unwrapped.run.sim.model_states()["cyan/11"].z
        assert z > 2.0 and obs["cyan/11"][z_at] == pytest.approx(z, abs=0.2)
        # a ground robot's observation holds the drone's height among its obstacles'
        ground = env.unwrapped.run.layouts["cyan/2"].names()
        heights = [obs["cyan/2"][i] for i, n in enumerate(ground) if n.startswith("heights.teammates")]
        assert max(heights) > 2.0
        with pytest.raises(ValueError, match=r"cyan/11: expected shape \(7,\) \(vx, vy, w, dribble, kick, lob, vz\)"):
            env.step({"cyan/2": np.zeros(6, dtype=np.float32), "cyan/11": np.zeros(6, dtype=np.float32)})
    finally:
        env.close()
