"""A world plug-in written outside simatch (named in a scene as tests.aerial.plugin_world:Corridor): a
corridor of pillars down the middle of an arena, its spacing a setting of its own (``world.params``)."""

from __future__ import annotations

from dataclasses import replace

from pydantic import BaseModel, ConfigDict, Field

from simatch.field import Obstacle
from simatch.worlds import World
from simatch.worlds.arena import Arena


class CorridorParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    spacing: float = Field(2.0, gt=0.5)
    radius: float = Field(0.2, gt=0.0)


class Corridor(World):
    name = "corridor"
    Params = CorridorParams

    def geometry(self):
        floor = Arena(self.spec, None).geometry()
        p = self.params
        pillars, x, k = [], -floor.reach_x + p.spacing, 1
        while x < floor.reach_x - 0.5:
            pillars.append(Obstacle(f"pillar_{k}", "cylinder", x, 0.0, 2.0, radius=p.radius))
            x, k = x + p.spacing, k + 1
        return replace(floor, kind=self.name, obstacles=floor.obstacles + tuple(pillars))
