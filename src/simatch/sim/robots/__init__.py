"""Robot models, chosen per team in the scene (``teams.<team>.model``): a shipped name or
``"package.module:Class"`` naming a `RobotModel` subclass."""

from __future__ import annotations

from ...plugins import PluginError, load
from .base import HULL_HEIGHT, OmniParams, RobotModel

SHIPPED = {
    "omni4": "simatch.sim.robots.omni4:Omni4",
    "omni3": "simatch.sim.robots.omni3:Omni3",
}


def model_class(spec: str) -> type[RobotModel]:
    cls = load(spec, SHIPPED, "robot model")
    if not (isinstance(cls, type) and issubclass(cls, RobotModel)):
        raise PluginError(f"robot model {spec!r} is not a simatch.sim.robots.RobotModel subclass")
    return cls


def check_models(scene) -> None:
    """Check every team's robot model and its parameters; SceneError naming the file and the key."""
    from ...scene.loader import SceneError, validate_params

    for team, tspec in scene.spec.teams.items():
        try:
            cls = model_class(tspec.model)
        except PluginError as exc:
            raise SceneError(f"{scene.source}: teams.{team}.model: {exc}") from None
        validate_params(cls.Params, tspec.model_params, scene.source, f"teams.{team}.model_params")


__all__ = ["HULL_HEIGHT", "OmniParams", "RobotModel", "SHIPPED", "check_models", "model_class"]
