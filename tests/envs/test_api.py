"""The environments pass PettingZoo's and Gymnasium's own checkers, on the full match, the encirclement and the
small learning scenes."""

from __future__ import annotations

import warnings

import gymnasium
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test

import simatch.envs

SCENES = ["striker_1v0", "msl_5v5", "encirclement_9v7"]


@pytest.mark.slow
@pytest.mark.parametrize("scene", SCENES)
def test_pettingzoo_parallel_api_and_seed_tests(scene):
    env = simatch.envs.parallel_env(scene)
    try:
        parallel_api_test(env, num_cycles=300)
    finally:
        env.close()
    parallel_seed_test(lambda: simatch.envs.parallel_env(scene))


@pytest.mark.slow
@pytest.mark.parametrize("scene", ["striker_1v1", "keepaway_3v2", "encirclement_4v1"])
def test_the_other_learning_scenes_pass_the_parallel_api_test(scene):
    env = simatch.envs.parallel_env(scene, observation="dict")
    try:
        parallel_api_test(env, num_cycles=200)
    finally:
        env.close()


def test_pettingzoo_aec_api_test_on_the_converted_env():
    env = simatch.envs.env("keepaway_3v2")
    try:
        api_test(env, num_cycles=100)
    finally:
        env.close()


@pytest.mark.slow
@pytest.mark.parametrize("scene", SCENES)
def test_gymnasium_check_env_without_warnings(scene):
    env = gymnasium.make(f"simatch/{scene}-v0")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            check_env(env.unwrapped)
    finally:
        env.close()


@pytest.mark.parametrize("options", [{"observation": "dict"}, {"action_type": "discrete"}])
def test_gymnasium_check_env_for_the_dict_observation_and_the_discrete_actions(options):
    env = gymnasium.make("simatch/striker_1v0-v0", **options)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            check_env(env.unwrapped)
    finally:
        env.close()


def test_every_shipped_scene_is_registered_with_gymnasium():
    from simatch.config.loader import shipped_scenes

    for name in shipped_scenes():
        assert f"simatch/{name}-v0" in gymnasium.registry
    env = gymnasium.make("simatch/striker_1v1-v0", max_vel=3.0)
    try:
        assert env.unwrapped.agent == "cyan/1"
        assert env.unwrapped.run.limits["cyan/1"].max_vel_x == 3.0
    finally:
        env.close()
