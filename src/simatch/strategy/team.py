"""Making a team's nodes from the scene: the team strategy, its robots' RobotNodes and its StrategyPub.

Used by every process that runs a team: the embedded run, ``simatch team`` and ``simatch robot``.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from .. import frames
from ..bus import Node, stable_seed
from ..config.loader import LoadedScene, SceneError, validate_params
from . import NO_NODES, strategy_class
from .base import RobotContext, RobotStrategy, TeamContext, TeamStrategy
from .learner import Learner
from .node import RobotNode, StrategyPub
from .worldmodel import WorldModel, team_field


def _params(cls: type, raw: dict, scene: LoadedScene, team: str) -> Any:
    model = getattr(cls, "Params", None)
    key = f"teams.{team}.strategy_params"
    if model is None:
        return dict(raw)
    return validate_params(model, raw, scene.source, key)


def build_team(
    scene: LoadedScene, team: str, seed: int, robot_ids: Iterable[int] | None = None, with_strategy_pub: bool = True
) -> list[Node]:
    """The nodes of one team (all its robots, or only ``robot_ids``), in tick order."""
    spec = scene.spec
    tspec = spec.teams[team]
    learners = set(tspec.learner_ids())
    if tspec.strategy in NO_NODES and not learners:
        return []
    try:
        cls = Learner if tspec.strategy == "none" else strategy_class(tspec.strategy)
    except Exception as exc:
        raise SceneError(f"{scene.source}: teams.{team}.strategy: {exc}") from None
    sign = spec.team_sign(team)
    geo = spec.world.geometry()
    field = team_field(geo, sign)
    ids = tspec.robot_ids()
    models = {m.id: m.model for m in tspec.members()}
    starts = {}
    for rid, (x, y, yaw) in zip(ids, tspec.starts()):
        tx, ty = frames.point(sign, x, y)
        starts[rid] = (tx, ty, frames.yaw(sign, yaw))
    params = _params(cls, tspec.strategy_params, scene, team)
    if issubclass(cls, TeamStrategy):
        team_strategy = cls(
            TeamContext(team, ids, tspec.goalkeeper, field, starts, spec.control.period, params, models)
        )
        make = team_strategy.make_robot
    else:

        def make(ctx: RobotContext) -> RobotStrategy:
            return cls(ctx)

    wanted = set(ids if robot_ids is None else robot_ids)
    unknown = wanted - set(ids)
    if unknown:
        raise SceneError(f"team {team} has no robot(s) {sorted(unknown)}; its robots are {ids}")
    nodes: list[Node] = []
    if with_strategy_pub:
        nodes.append(StrategyPub(team, spec.strategy_pub_period, spec.control.strategy_stale_after))
    for rid in ids:
        if rid not in wanted:
            continue
        ctx = RobotContext(
            team=team,
            id=rid,
            goalkeeper=tspec.goalkeeper,
            ids=ids,
            field=field,
            start=starts[rid],
            control_period=spec.control.period,
            params=params,
            rng=np.random.default_rng(stable_seed(seed, "strategy", team, str(rid))),
            model=models[rid],
            models=models,
        )
        world = WorldModel(team, rid, sign, geo, tspec.goalkeeper)
        if rid in learners:
            strategy = Learner(ctx)
        elif tspec.strategy == "none":
            continue  # this robot gets no node and stands still
        else:
            strategy = make(ctx)
        nodes.append(RobotNode(team, rid, strategy, world, spec.control.period))
    return nodes
