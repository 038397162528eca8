"""The strategy subsystem: per robot a WorldModel and a Control (a `RobotStrategy`), per team a StrategyPub.

Strategies are plug-ins named in the scene (``teams.<team>.strategy``): a shipped name, a
``"package.module:Class"``, ``"learner"`` (the robots play what a learning environment decides),
``"none"`` (the team's robots get no node and stand still) or ``"external"``
(the team runs in its own process and connects over the bus).
"""

from __future__ import annotations

from ..plugins import PluginError, load
from .base import Command, PassIntent, RobotContext, RobotStrategy, TeamContext, TeamStrategy
from .worldmodel import WorldModel

SHIPPED = {
    "constant": "simatch.strategy.scripted:ConstantVelocity",
    "startpose": "simatch.strategy.scripted:StartPose",
    "nubot": "simatch.strategy.nubot:NubotTeam",
    "simple": "simatch.strategy.simple:SimpleRobot",
    "encircle": "simatch.strategy.encirclement:Chaser",
    "flee": "simatch.strategy.encirclement:Target",
    "learner": "simatch.strategy.learner:Learner",
    "aerial_encircle": "simatch.strategy.aerial:AerialChasers",
    "evade": "simatch.strategy.aerial:Evader",
    "pincer": "simatch.strategy.aerial:Pincer",
    "chase": "simatch.strategy.aerial:Chase",
    "evade_3d": "simatch.strategy.aerial:Evader3D",
}

#: strategies that create no node in the run that loads the scene
NO_NODES = ("none", "external")


def strategy_class(spec: str) -> type:
    cls = load(spec, SHIPPED, "strategy")
    if not (isinstance(cls, type) and issubclass(cls, (RobotStrategy, TeamStrategy))):
        raise PluginError(f"strategy {spec!r} is neither a simatch.strategy.RobotStrategy nor a TeamStrategy subclass")
    return cls


__all__ = [
    "Command",
    "NO_NODES",
    "PassIntent",
    "RobotContext",
    "RobotStrategy",
    "SHIPPED",
    "TeamContext",
    "TeamStrategy",
    "WorldModel",
    "strategy_class",
]
