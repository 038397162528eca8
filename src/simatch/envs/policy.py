"""A trained policy as a strategy plug-in: it plays in any run like any other strategy.

```toml
[teams.cyan]
strategy = "simatch.envs.policy:Policy"
strategy_params = { file = "striker.zip" }
```

or ``simatch run striker_1v0 --set teams.cyan.strategy=simatch.envs.policy:Policy --set
teams.cyan.strategy_params.file=striker.zip``. The file is a Stable-Baselines3 model (any algorithm: PPO, A2C,
SAC, ...) saved with `save_policy`, which writes beside it (``striker.json``) what the policy was trained on:
the observation's slots, the action's type and scales. Each control period the robot encodes its own
perception and game command exactly as the environment did (`observation.Layout`), asks the model for an
action (deterministic by default) and plays it (`action.Limits`). In a scene with more robots than it was
trained with, the policy sees the nearest obstacles and first teammates its slots hold.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from ..config.loader import SceneError
from ..strategy import Command, RobotStrategy
from . import action as actions
from .observation import Layout

FORMAT = "simatch-policy-1"


def _meta_path(file: Path) -> Path:
    return file.with_suffix(".json")


def save_policy(model: Any, file: str | Path, env: Any, agent: str | None = None, normalize: Any = None) -> Path:
    """Save an SB3 ``model`` trained on ``env`` (a SimatchEnv, SimatchParallelEnv or LearningRun, or a
    gymnasium wrapper of one) to ``file`` (.zip) and what it needs to play beside it (.json): with
    ``normalize``, the SB3 `VecNormalize` it was trained behind (its observation statistics are kept, so the
    policy sees observations scaled as in training)."""
    file = Path(file).with_suffix(".zip")
    run = getattr(getattr(env, "unwrapped", env), "run", env)
    agent = agent or getattr(getattr(env, "unwrapped", env), "agent", None) or run.agents[0]
    layout, limits = run.layouts[agent], run.limits[agent]
    model.save(str(file))
    meta = {
        "format": FORMAT,
        "algorithm": type(model).__name__,
        "scene": run.scene.name,
        "agent": agent,
        "observation": {
            "teammates": layout.teammates,
            "obstacles": layout.obstacles,
            "heights": layout.heights,
            "structures": layout.structures,
            "size": layout.size,
        },
        "action": {"type": run.action_type, **limits.__dict__},
    }
    if normalize is not None and getattr(normalize, "norm_obs", False):
        rms = normalize.obs_rms
        meta["normalize"] = {
            "mean": [float(v) for v in rms.mean],
            "var": [float(v) for v in rms.var],
            "epsilon": float(normalize.epsilon),
            "clip": float(normalize.clip_obs),
        }
    _meta_path(file).write_text(json.dumps(meta, indent=2) + "\n", encoding="utf-8")
    return file


class PolicyParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    file: str = Field(min_length=1, description="the saved policy (.zip written by simatch.envs.policy.save_policy)")
    deterministic: bool = Field(True, description="play the policy's most likely action (else sample it)")


def _load_model(file: Path, algorithm: str):
    try:
        import stable_baselines3 as sb3
    except ImportError:
        raise SceneError("simatch.envs.policy:Policy needs stable-baselines3: pip install 'simatch[learn]'") from None
    cls = getattr(sb3, algorithm, None)
    if cls is None:
        raise SceneError(f"{file}: algorithm {algorithm!r} is not one of stable-baselines3's")
    return cls.load(str(file), device="cpu")


class Policy(RobotStrategy):
    Params = PolicyParams
    _cache: dict[tuple[str, float], tuple[Any, dict]] = {}

    def __init__(self, ctx):
        super().__init__(ctx)
        file = Path(ctx.params.file).expanduser()
        if file.suffix != ".zip":
            file = file.with_suffix(".zip")
        meta_file = _meta_path(file)
        if not file.is_file() or not meta_file.is_file():
            raise SceneError(
                f"teams.{ctx.team}.strategy_params.file: {file} (and {meta_file.name} beside it) must exist: a policy "
                f"saved with simatch.envs.policy.save_policy"
            )
        key = (str(file.resolve()), file.stat().st_mtime)
        if key not in self._cache:
            meta = json.loads(meta_file.read_text(encoding="utf-8"))
            if meta.get("format") != FORMAT:
                raise SceneError(f"{meta_file}: not a simatch policy description (format {meta.get('format')!r})")
            self._cache[key] = (_load_model(file, meta["algorithm"]), meta)
        self.model, meta = self._cache[key]
        obs, act = meta["observation"], dict(meta["action"])
        self.layout = Layout(
            obs["teammates"],
            obs["obstacles"],
            ctx.field.half_length,
            obs.get("heights", False),
            obs.get("structures", 0),
        )
        self.discrete = act.pop("type") == "discrete"
        self.limits = actions.Limits(**act)
        self.mates = [rid for rid in ctx.ids if rid != ctx.id]
        norm = meta.get("normalize")
        self.norm = None
        if norm is not None:
            mean, var = np.asarray(norm["mean"], np.float64), np.asarray(norm["var"], np.float64)
            if mean.shape != (self.layout.size,) or var.shape != mean.shape:
                raise SceneError(f"{meta_file}: normalize: expected {self.layout.size} means and variances")
            self.norm = (mean, np.sqrt(var + norm["epsilon"]), norm["clip"])
        self.name = f"{ctx.team}/{ctx.id}"

    def decide(self, world) -> Command:
        obs = self.layout.encode(world.vision, world.coach, self.mates, world.field.obstacles)
        if self.norm is not None:
            mean, std, clip = self.norm
            obs = np.clip((obs - mean) / std, -clip, clip).astype(np.float32)
        a, _ = self.model.predict(obs, deterministic=self.ctx.params.deterministic)
        if self.discrete:
            return self.limits.discrete(actions.check_discrete(self.name, a, self.limits.moves))
        return self.limits.command(actions.check_box(self.name, np.asarray(a).ravel(), size=self.limits.size))
