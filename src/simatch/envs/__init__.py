"""simatch as multi-agent and single-agent learning environments (docs/learning.md).

* `parallel_env(scene, ...)`: a PettingZoo `ParallelEnv`; `env(scene, ...)`: its AEC form (PettingZoo's own
  conversion). The agents are the robots the scene hands to learning (``teams.<team>.learners`` or
  ``teams.<team>.strategy = "learner"``, or ``learners=[...]`` here); every other robot plays its strategy.
* `SimatchEnv` / ``gymnasium.make("simatch/<scene>-v0")``: one learner against the scene's other robots;
  an id per shipped scene is registered when this package is imported.
* `simatch.envs.policy:Policy`: a trained policy as a strategy plug-in, to play in any run.

One step is one control period of the scene's run: the same physics, perception (noise, dropout, latency),
strategies, referee and judges as ``simatch run``, deterministic for a seed.

Needs the ``learn`` extra (``pip install 'simatch[learn]'``: gymnasium, pettingzoo, and for training
stable-baselines3 with torch).
"""

from __future__ import annotations

try:
    import gymnasium
    import pettingzoo  # noqa: F401
except ImportError as exc:  # pragma: no cover - depends on the installation
    raise ImportError(
        f"simatch.envs needs the learning extra ({exc.name} is missing): pip install 'simatch[learn]'"
    ) from None

from ..config.loader import shipped_scenes
from .core import LearningRun, hand_over
from .gym_env import SimatchEnv, default_agent
from .parallel import SimatchParallelEnv

ENV_IDS: dict[str, str] = {}


def parallel_env(scene="msl_5v5", **options) -> SimatchParallelEnv:
    """A PettingZoo ParallelEnv over ``scene`` (options: see `SimatchParallelEnv`)."""
    return SimatchParallelEnv(scene, **options)


def env(scene="msl_5v5", **options):
    """The AEC form of `parallel_env` (PettingZoo's parallel_to_aec)."""
    from pettingzoo.utils.conversions import parallel_to_aec

    return parallel_to_aec(parallel_env(scene, **options))


def register_shipped() -> dict[str, str]:
    """Register ``simatch/<scene>-v0`` with Gymnasium for every shipped scene (done on import)."""
    for name in sorted(shipped_scenes()):
        env_id = f"simatch/{name}-v0"
        if env_id not in gymnasium.registry:
            gymnasium.register(id=env_id, entry_point="simatch.envs.gym_env:SimatchEnv", kwargs={"scene": name})
        ENV_IDS[name] = env_id
    return ENV_IDS


register_shipped()

__all__ = [
    "ENV_IDS",
    "LearningRun",
    "SimatchEnv",
    "SimatchParallelEnv",
    "default_agent",
    "env",
    "hand_over",
    "parallel_env",
    "register_shipped",
]
