"""Robot models, chosen per team in the scene (``teams.<team>.model``): a shipped name or
``"package.module:Class"`` naming a `RobotModel` subclass.

This is the robot models' public description (wheel layout and the ideal kinematics of paper Eq. 2-3,
limits, body), below the subsystems: the simulator builds its physics from it and the locomotion judge
integrates the ideal model from it, so neither reaches into the other."""

from __future__ import annotations

from ..plugins import PluginError, load
from .base import HULL_HEIGHT, OmniParams, RobotModel

SHIPPED = {
    "omni4": "simatch.robots.omni4:Omni4",
    "omni3": "simatch.robots.omni3:Omni3",
    "quadrotor": "simatch.robots.quadrotor:Quadrotor",
}


def model_class(spec: str) -> type[RobotModel]:
    cls = load(spec, SHIPPED, "robot model")
    if not (isinstance(cls, type) and issubclass(cls, RobotModel)):
        raise PluginError(f"robot model {spec!r} is not a simatch.robots.RobotModel subclass")
    if cls.locomotion == "aerial":
        from .quadrotor import Quadrotor

        # the simulator builds and flies four rotors from a quadrotor's parameters (sim/airframe.py, sim/flight.py)
        if not issubclass(cls, Quadrotor):
            raise PluginError(
                f"robot model {spec!r}: an aerial robot model is a simatch.robots.quadrotor.Quadrotor subclass "
                "(its parameters and four rotors are what the simulator flies)"
            )
        if len(cls.rotor_angles) != 4 or len(cls.rotor_spin) != 4:
            raise PluginError(
                f"robot model {spec!r}: has {len(cls.rotor_angles)} rotor angle(s) and {len(cls.rotor_spin)} "
                "spin(s); an aerial robot has exactly 4 rotors"
            )
    elif cls.locomotion != "ground":
        raise PluginError(f"robot model {spec!r}: locomotion {cls.locomotion!r} is neither 'ground' nor 'aerial'")
    return cls


__all__ = ["HULL_HEIGHT", "OmniParams", "RobotModel", "SHIPPED", "model_class"]
