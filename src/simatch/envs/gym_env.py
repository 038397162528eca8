"""The Gymnasium single-agent environment: one robot learns, every other robot plays its scene strategy.

import gymnasium, simatch.envs
env = gymnasium.make("simatch/striker_1v0-v0")          # one id per shipped scene, registered on import
env = simatch.envs.SimatchEnv("examples/my_scene.toml", agent="cyan/2")
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np

from ..config.loader import LoadedScene, SceneError, load_scene
from .core import LearningRun
from .spaces import action_space, check_form, check_render, observation_space


def default_agent(scene: LoadedScene) -> str:
    """The scene's one learner; a scene that hands nobody over: its first team's first robot that is not the
    goalkeeper (else its first robot)."""
    learners = scene.spec.learner_names()
    if len(learners) == 1:
        return learners[0]
    if learners:
        raise SceneError(
            f"{scene.source}: the scene hands {len(learners)} robots to learning ({', '.join(learners)}); "
            f"a single-agent environment needs one: give agent='team/id' or use simatch.envs.parallel_env"
        )
    team, tspec = next(iter(scene.spec.teams.items()))
    ids = tspec.robot_ids()
    field = [rid for rid in ids if rid != tspec.goalkeeper]
    return f"{team}/{(field or ids)[0]}"


class SimatchEnv(gymnasium.Env):
    """``scene`` and the options as `SimatchParallelEnv`; ``agent``: the robot that learns (default:
    `default_agent`). Observations and actions are that robot's."""

    metadata = {"render_modes": []}

    def __init__(
        self,
        scene: Any = "striker_1v0",
        agent: str | None = None,
        observation: str = "vector",
        overrides: dict | None = None,
        render_mode: str | None = None,
        **options: Any,
    ):
        check_render(render_mode)
        self.form = check_form(observation)
        if agent is None:
            agent = default_agent(scene if isinstance(scene, LoadedScene) else load_scene(scene, overrides))
        self.run = LearningRun(scene, learners=[agent], overrides=overrides, **options)
        if self.run.agents != [agent]:
            raise SceneError(
                f"{self.run.scene.source}: the scene hands {', '.join(self.run.agents)} to learning; a single-agent "
                f"environment for {agent} needs the others to play a strategy"
            )
        self.agent = agent
        self.render_mode = None
        self.observation_space = observation_space(self.run.layouts[agent], self.form)
        self.action_space = action_space(self.run.action_type, self.run.limits[self.agent])

    def _obs(self, obs: dict[str, np.ndarray]):
        v = obs[self.agent]
        return v if self.form == "vector" else self.run.layouts[self.agent].split(v)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.run.check_open()
        obs = self.run.reset(int(self.np_random.integers(0, 2**31 - 1)) if seed is None else seed)
        return self._obs(obs), {}

    def step(self, action):
        obs, rewards, terminated, truncated, infos = self.run.step({self.agent: action})
        a = self.agent
        return self._obs(obs), rewards[a], terminated[a], truncated[a], infos[a]

    def close(self) -> None:
        self.run.close()
