"""What a robot's body looks like to a viewer: the one description the recordings' 3D scene
(`simatch.record.scene3d`) and the web UI's pages (`simatch.web.picture`) draw from.

A ground robot is an upright cylinder of its footprint radius and height with the dribbler's mouth cut
``mouth`` deep into its front (+x of the body); a drone is four rotor discs on an X about a flat frame. A
nano quadrotor is 13 cm across, too small to see in a view of the whole field, so viewers draw drones
`DRONE_SCALE` times their size (the scale is part of the description: every viewer draws the same drone).
"""

from __future__ import annotations

from . import model_class
from .base import RobotModel

DRONE_SCALE = 2.0  # drones are drawn this much larger than they are (for the eye)


def looks(model: RobotModel) -> dict:
    """The body of ``model`` as viewers draw it (JSON-able; metres, body frame: x forward, y left)."""
    if model.aerial:
        p = model.params
        return {
            "kind": "drone",
            "radius": model.radius,
            "height": model.height,
            "rotors": [[x, y] for x, y in model.rotor_positions()],
            "rotor_radius": p.prop_radius,
            "scale": DRONE_SCALE,
        }
    return {
        "kind": "ground",
        "radius": model.radius,
        "height": model.height,
        "mouth": float(getattr(model.params, "mouth_depth", 0.0)),
    }


def member_looks(member) -> dict:
    """The body of a scene's team member (``config.schema`` Member: its ``model`` and ``model_params``)."""
    return looks(model_class(member.model)(member.model_params))
