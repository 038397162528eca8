"""The learning environments accept the aerial scenes: drones learn with their climb in the action and
every robot's height in the observation (PettingZoo's and Gymnasium's own checkers, and the physics)."""

from __future__ import annotations

import math
import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test

import simatch.envs
from simatch.envs.action import AERIAL_NAMES

from ..lockfile import skip_unless_locked


@pytest.mark.slow
def test_the_aerial_scenes_pass_the_parallel_api_test():
    for scene, learners in (("pursuit_evasion_3d", ["cyan", "magenta"]), ("aerial_encirclement", ["cyan"])):
        env = simatch.envs.parallel_env(scene, learners=learners)
        try:
            parallel_api_test(env, num_cycles=60)
        finally:
            env.close()


@pytest.mark.parametrize(
    "scene, agent, options",
    [
        ("pursuit_evasion_3d", "cyan/2", {}),
        ("pursuit_evasion_3d", "cyan/2", {"action_type": "discrete", "observation": "dict"}),
        ("aerial_encirclement", "cyan/10", {}),  # a drone of a squad, in a team of ground robots
    ],
)
def test_gymnasium_check_env_on_a_drone(scene, agent, options):
    env = gymnasium.make(f"simatch/{scene}-v0", agent=agent, **options)
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


def _nearest_points(states, name: str, obstacles) -> list[tuple[float, float, float, float]]:
    """(distance to the outline, bearing of its nearest point from the robot's heading, radius, height) of
    every obstacle, from the robot's true pose in the world frame, nearest first."""
    s = states[name]
    rows = []
    for ob in obstacles:
        ax, ay = ob.away(s.x, s.y)
        rows.append((ob.distance(s.x, s.y), math.atan2(-ay, -ax) - s.yaw, ob.bounding_radius, ob.height))
    return sorted(rows)


def test_the_world_obstacles_are_in_the_observation_in_each_team_frame():
    # a pursuer (cyan attacks +x) and the evader (magenta: its team frame is the world turned by pi)
    env = simatch.envs.parallel_env("pursuit_evasion_3d", learners=["cyan/1", "magenta/1"])
    try:
        obs, _ = env.reset(seed=0)
        turn = np.zeros(7, dtype=np.float32)
        turn[2] = 0.3  # turning, so that the bearings are not all taken at the start heading
        for _ in range(10):
            obs, *_ = env.step({"cyan/1": turn, "magenta/1": -turn})
        run = env.unwrapped.run
        world = run.sim.simulator.field.obstacles
        states = run.sim.model_states()
        assert len(world) == 8
        for agent in ("cyan/1", "magenta/1"):
            layout = run.layouts[agent]
            assert (
                layout.structures == 8 and layout.names()[layout.offsets["structures"].start] == "structures[0].present"
            )
            got = layout.split(obs[agent])["structures"]
            assert got[:, 0].tolist() == [1.0] * 8 and (np.diff(got[:, 1]) >= 0).all()  # nearest first
            want = _nearest_points(states, agent, world)
            for row, (d, bearing, radius, height) in zip(got, want):
                # from the perceived pose of the last control tick (perception is exact in this scene)
                assert row[1] == pytest.approx(d, abs=0.05)
                assert math.atan2(row[3], row[2]) == pytest.approx(math.remainder(bearing, math.tau), abs=0.05)
                assert (row[4], row[5]) == pytest.approx((radius, height), abs=1e-5)
        # the global state ends with every robot's height
        state = env.state()
        heights = [states[n].z for n in run.sim.simulator.robot_names]
        assert state.shape == env.state_space.shape and state[-4:] == pytest.approx(heights, abs=1e-5)
    finally:
        env.close()


def test_soccer_scenes_keep_their_layout():
    env = simatch.envs.parallel_env("msl_5v5", learners=["cyan/2"])
    try:
        layout = env.unwrapped.run.layouts["cyan/2"]
        assert list(layout.parts) == ["game", "self", "ball", "goals", "teammates", "obstacles"]
        assert layout.size == 36 + 10 + 12 + 6 + 4 * 11 + 9 * 9 and env.state_space.shape == (3 * 10 + 6,)
    finally:
        env.close()


@pytest.mark.slow
def test_a_drone_policy_plays_in_a_run_as_it_did_in_its_environment(tmp_path):
    """A policy saved for the evading drone (its climb in the action, heights and the pillars in its
    observation) plays as the `Policy` strategy of a plain run: the same run, bit for bit."""
    skip_unless_locked("stable-baselines3")
    import torch
    from stable_baselines3 import PPO

    from simatch.envs.policy import save_policy

    env = simatch.envs.SimatchEnv("pursuit_evasion_3d", agent="magenta/1")
    try:
        model = PPO("MlpPolicy", env, n_steps=32, batch_size=32, seed=0, device="cpu")  # untrained: any policy,
        with torch.no_grad():  # ... here one that turns and climbs (its mean action's bias)
            model.policy.action_net.bias[:] = torch.tensor([0.0, 0.0, 0.3, 0.0, 0.0, 0.0, 0.4])
        file = save_policy(model, tmp_path / "evader.zip", env)
        obs, _ = env.reset(seed=4)
        climbs = []
        for _ in range(40):  # two seconds
            a, _ = model.predict(obs, deterministic=True)
            climbs.append(float(np.clip(a, -1, 1)[-1]))
            obs, *_ = env.step(a)
        z = env.unwrapped.run.sim.model_states()["magenta/1"].z
        overrides = {
            "teams.magenta.strategy": "simatch.envs.policy:Policy",
            "teams.magenta.strategy_params": {"file": str(file)},
        }
        with simatch.Simulation("pursuit_evasion_3d", seed=4, overrides=overrides) as plain:
            plain.run(seconds=2.0)
            assert plain.state_digest() == env.unwrapped.run.sim.state_digest()
            assert plain.model_states()["magenta/1"].z == z
            assert not [e for e in plain.events if e["type"] == "strategy_error"]
    finally:
        env.close()
    assert min(climbs) > 0.3 and z > 3.0  # the policy's climb reached the drone


def test_the_pursuit_pays_the_capture_and_charges_collisions():
    env = simatch.envs.parallel_env("pursuit_evasion_3d", learners=["cyan", "magenta"])
    try:
        env.reset(seed=0)
        still = {a: np.zeros(7, dtype=np.float32) for a in env.agents}
        down = {**still, "cyan/1": np.array([0, 0, 0, 0, 0, 0, -1.0], dtype=np.float32)}  # to the floor
        paid = dict.fromkeys(env.agents, 0.0)
        for _ in range(60):
            _, rewards, *_ = env.step(down)
            for a, r in rewards.items():
                paid[a] += r
        assert paid == {"cyan/1": -0.5, "cyan/2": -0.5, "cyan/3": -0.5, "magenta/1": 0.0}  # one landing, hard
        sim = env.unwrapped.run.sim
        e = sim.model_states()["magenta/1"]
        sim.set_model_state("cyan/2", x=e.x + 0.2, y=e.y, z=e.z)
        _, rewards, terminated, _, infos = env.step(still)
        assert rewards == {"cyan/1": 10.0, "cyan/2": 10.0, "cyan/3": 10.0, "magenta/1": -10.0}
        assert all(terminated.values()) and infos["magenta/1"]["end"] == "judge" and env.agents == []
    finally:
        env.close()
