"""World plug-ins, chosen by the scene's ``world.kind``: a shipped name or ``"package.module:Class"``.

A world makes, from the scene's ``[world]`` table, the one description of the place (`FieldGeometry`:
floor, walls, markings, goals, zones, static obstacles, ceiling) that the simulator builds its solids
from, viewers draw, judges and strategies read. Shipped: ``msl_field`` (the RoboCup MSL field, the
default) and ``arena`` (a walled floor with obstacles, given or scattered from a seed, and zones).
"""

from __future__ import annotations

from ..plugins import PluginError, load
from .base import World, WorldError

SHIPPED = {
    "msl_field": "simatch.worlds.msl_field:MslField",
    "arena": "simatch.worlds.arena:Arena",
}


def world_class(spec: str) -> type[World]:
    cls = load(spec, SHIPPED, "world")
    if not (isinstance(cls, type) and issubclass(cls, World)):
        raise PluginError(f"world {spec!r} is not a simatch.worlds.World subclass")
    return cls


def make_world(spec) -> World:
    """The world plug-in of a scene's ``[world]`` (a `WorldSpec`), its ``params`` checked by its model;
    raises `PluginError` or `WorldError` (pydantic's ValidationError for bad ``params``)."""
    cls = world_class(spec.kind)
    return cls(spec, cls.Params.model_validate(dict(spec.params)))


__all__ = ["SHIPPED", "World", "WorldError", "make_world", "world_class"]
