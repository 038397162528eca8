"""An arena (``world.kind = "arena"``): a walled floor of ``length`` x ``width`` with no markings and no
goals, zones (``areas``: a prison, a base), static obstacles — boxes and cylinders placed by hand
(``obstacles``) or scattered from a seed (``clutter``) — and optionally a ceiling (for drones).

The walls stand at the edge of the floor (``margin`` is 0 unless set). The soccer keys of ``[world]``
(goals, markings, penalty areas...) are refused: they are the MSL field's.

    [world]
    kind = "arena"
    length = 16.0
    width = 12.0
    areas = [{ name = "prison", x0 = 5.0, y0 = -2.0, x1 = 8.0, y1 = 2.0 }]
    obstacles = [{ shape = "cylinder", x = 0.0, y = 3.0, radius = 0.4, height = 1.2 }]
    clutter = { seed = 3, boxes = 4, cylinders = 3, gap = 1.2 }
"""

from __future__ import annotations

from dataclasses import replace

from ..field import FieldGeometry
from .base import World, zones
from .msl_field import SOCCER_KEYS


class Arena(World):
    name = "arena"
    foreign_keys = SOCCER_KEYS
    own_defaults = {"margin": 0.0}  # the walls at the edge of the floor

    def geometry(self) -> FieldGeometry:
        s = self.spec
        margin = s.margin if "margin" in s.model_fields_set else self.own_defaults["margin"]
        floor = FieldGeometry(
            length=s.length,
            width=s.width,
            margin=margin,
            markings="none",
            goals=False,
            walls=s.walls,
            wall_height=s.wall_height,
            areas=zones(s),
            kind=self.name,
            ceiling=s.ceiling,
        )
        return replace(floor, obstacles=self.obstacles(floor))
