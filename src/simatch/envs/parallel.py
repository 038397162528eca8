"""The PettingZoo `ParallelEnv` over any scene: every robot the scene hands to learning is an agent.

    import simatch.envs
    env = simatch.envs.parallel_env("striker_1v1")
    observations, infos = env.reset(seed=0)
    while env.agents:
        actions = {agent: env.action_space(agent).sample() for agent in env.agents}
        observations, rewards, terminations, truncations, infos = env.step(actions)

The AEC form is PettingZoo's own conversion (`simatch.envs.env`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from .core import LearningRun
from .observation import BOUND_POSITION as BOUND
from .spaces import action_space, check_form, check_render, observation_space


class SimatchParallelEnv(ParallelEnv):
    """``scene``: a shipped scene name, a .toml path or a LoadedScene; ``learners``: team names or robots
    (``"cyan/2"``) handed to learning besides the scene's own (default: the scene's, else its first team);
    ``overrides``: ``{"dotted.key": value}`` as ``--set``; ``observation``: ``"vector"`` or ``"dict"``;
    ``action_type``: ``"box"`` or ``"discrete"``; ``max_vel``/``max_w``: caps on the action's velocity scale;
    ``strict_actions``: refuse numbers outside [-1, 1] instead of clipping; ``teammates``/``obstacles``/
    ``structures``: slots in the observation (team-mates, robots seen, the world's static obstacles);
    ``episode_time``: cut episodes after this many simulated seconds."""

    metadata = {"name": "simatch_v0", "render_modes": [], "is_parallelizable": True}

    def __init__(self, scene: Any = "msl_5v5", observation: str = "vector", render_mode: str | None = None, **options):
        check_render(render_mode)
        self.form = check_form(observation)
        self.run = LearningRun(scene, **options)
        self.possible_agents = list(self.run.agents)
        self.agents: list[str] = []
        self.render_mode = None
        self._obs_spaces = {a: observation_space(self.run.layouts[a], self.form) for a in self.possible_agents}
        self._act_spaces = {a: action_space(self.run.action_type, self.run.limits[a]) for a in self.possible_agents}
        n = (4 if self.run.airborne else 3) * len(self.run.team_of_robot) + 6
        self.state_space = spaces.Box(-BOUND, BOUND, shape=(n,), dtype=np.float32)
        self._seeds: np.random.Generator | None = None

    @property
    def scene(self):
        return self.run.scene

    def observation_space(self, agent: str):
        return self._obs_spaces[agent]

    def action_space(self, agent: str):
        return self._act_spaces[agent]

    def _next_seed(self, seed: int | None) -> int:
        if seed is not None:
            self._seeds = np.random.default_rng(seed)
        elif self._seeds is None:
            self._seeds = np.random.default_rng()
        return int(self._seeds.integers(0, 2**31 - 1)) if seed is None else int(seed)

    def _form(self, obs: dict[str, np.ndarray]) -> dict:
        if self.form == "vector":
            return obs
        return {a: self.run.layouts[a].split(v) for a, v in obs.items()}

    def reset(self, seed: int | None = None, options: dict | None = None):
        """A new episode; the same ``seed`` gives the same episode bit for bit (None: the next of the seeds
        drawn from the last one given)."""
        self.run.check_open()
        obs = self.run.reset(self._next_seed(seed))
        self.agents = list(self.possible_agents)
        return self._form(obs), {a: {} for a in self.agents}

    def step(self, actions: dict):
        obs, rewards, terminated, truncated, infos = self.run.step(actions)
        if self.run.over:
            self.agents = []
        return self._form(obs), rewards, terminated, truncated, infos

    def state(self) -> np.ndarray:
        """The world's true state (world frame): x, y, yaw of every robot, then the ball's x, y, z, vx, vy, vz;
        in a scene with aerial robots, then every robot's height z (in `Simulator.robot_names` order)."""
        self.run.check_open()
        sim = self.run.sim
        if sim is None:
            raise RuntimeError("call reset() first")
        parts = [sim.simulator.robot_array()[:, :3].ravel(), sim.simulator.ball_array()]
        if self.run.airborne:
            _, pose, _ = sim.simulator.model_state_arrays()
            parts.append(pose[:-1, 2])  # the robots' heights (the ball is last)
        state = np.concatenate(parts).astype(np.float32)
        return np.clip(state, -BOUND, BOUND, out=state)

    def render(self):
        return None

    def close(self) -> None:
        self.run.close()
        self.agents = []
