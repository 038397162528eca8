"""The RoboCup Middle Size League field (``world.kind = "msl_field"``, the default): lines, goals, boards
at the edge of the margin, named areas, and any obstacles the scene places on it. Every key of ``[world]``
is its setting; the MSL defaults are those of the rules (22 x 14 m, 2.4 m goals, 1.5 m margin)."""

from __future__ import annotations

from dataclasses import replace

from ..field import FieldGeometry
from .base import World, zones

#: the [world] keys of soccer: markings and goals (a world without them, e.g. the arena, refuses them)
SOCCER_KEYS = (
    "line_width",
    "markings",
    "center_circle_radius",
    "goal_area_depth",
    "goal_area_width",
    "penalty_area_depth",
    "penalty_area_width",
    "penalty_spot_distance",
    "corner_arc_radius",
    "goals",
    "goal_width",
    "goal_height",
    "goal_depth",
    "goal_post_size",
)


class MslField(World):
    name = "msl_field"

    def geometry(self) -> FieldGeometry:
        s = self.spec
        floor = FieldGeometry(
            length=s.length,
            width=s.width,
            margin=s.margin,
            line_width=s.line_width,
            markings=s.markings,
            center_circle_radius=s.center_circle_radius,
            goal_area_depth=s.goal_area_depth,
            goal_area_width=s.goal_area_width,
            penalty_area_depth=s.penalty_area_depth,
            penalty_area_width=s.penalty_area_width,
            penalty_spot_distance=s.penalty_spot_distance,
            corner_arc_radius=s.corner_arc_radius,
            goals=s.goals,
            goal_width=s.goal_width,
            goal_height=s.goal_height,
            goal_depth=s.goal_depth,
            goal_post_size=s.goal_post_size,
            walls=s.walls,
            wall_height=s.wall_height,
            areas=zones(s),
            kind=self.name,
            ceiling=s.ceiling,
        )
        obstacles = self.obstacles(floor)
        return replace(floor, obstacles=obstacles) if obstacles else floor
