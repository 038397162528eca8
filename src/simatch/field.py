"""Field geometry: one description of the playing area that the physics, the judges, the strategies and
the viewers all read, so that a line drawn in a viewer is the line the referee judges.

World frame: origin at the field centre, +x towards magenta's goal (cyan defends -x), z up; metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Area:
    """A named axis-aligned rectangle on the floor (e.g. a prison area), world frame."""

    name: str
    x0: float
    y0: float
    x1: float
    y1: float

    def contains(self, x: float, y: float) -> bool:
        return self.x0 <= x <= self.x1 and self.y0 <= y <= self.y1

    @property
    def center(self) -> tuple[float, float]:
        return (0.5 * (self.x0 + self.x1), 0.5 * (self.y0 + self.y1))


@dataclass(frozen=True)
class FieldGeometry:
    length: float = 22.0  # between the goal lines
    width: float = 14.0  # between the side lines
    margin: float = 1.5  # floor beyond the lines
    line_width: float = 0.125
    markings: str = "msl"  # "msl" (soccer lines) or "none"
    center_circle_radius: float = 2.0
    goal_area_depth: float = 0.75
    goal_area_width: float = 3.9
    penalty_area_depth: float = 2.25
    penalty_area_width: float = 6.9
    penalty_spot_distance: float = 3.0  # from the goal line
    corner_arc_radius: float = 0.75
    goals: bool = True
    goal_width: float = 2.4  # inner mouth, between the posts
    goal_height: float = 1.0  # lower edge of the crossbar
    goal_depth: float = 0.6
    goal_post_size: float = 0.125
    walls: bool = True  # boards at the outer edge of the margin
    wall_height: float = 0.5
    areas: tuple[Area, ...] = field(default_factory=tuple)

    @property
    def half_length(self) -> float:
        return 0.5 * self.length

    @property
    def half_width(self) -> float:
        return 0.5 * self.width

    def area(self, name: str) -> Area:
        for a in self.areas:
            if a.name == name:
                return a
        names = ", ".join(a.name for a in self.areas) or "none"
        raise KeyError(f"the world has no area named {name!r} (world.areas: {names})")

    # --- the lines belong to what they bound -----------------------------------------------------------
    # Every line is drawn centred on its nominal coordinate with `line_width` (see `lines`), and, as in
    # soccer, a line belongs to the region it bounds: the field's lines to the field (a ball is out, or in
    # the goal, only once it is wholly past the line's outer edge), an area's lines to the area (a robot
    # whose centre is on the painted line is in the area). The judges read these limits, the viewers draw
    # the same lines.
    @property
    def outer_half_length(self) -> float:
        """|x| of the goal lines' outer edges."""
        return self.half_length + 0.5 * self.line_width

    @property
    def outer_half_width(self) -> float:
        """|y| of the side lines' outer edges."""
        return self.half_width + 0.5 * self.line_width

    def area_limits(self, kind: str) -> tuple[float, float]:
        """(x_in, y_half) of the ``"penalty"`` or ``"goal"`` area, its lines included: a point is in the area
        of side s when ``s * x >= x_in`` (towards its goal line) and ``|y| <= y_half``."""
        if kind == "penalty":
            depth, width = self.penalty_area_depth, self.penalty_area_width
        elif kind == "goal":
            depth, width = self.goal_area_depth, self.goal_area_width
        else:
            raise ValueError(f"an area is 'penalty' or 'goal', not {kind!r}")
        half = 0.5 * self.line_width
        return (self.half_length - depth - half, 0.5 * width + half)

    # --- soccer regions (side = -1 for the goal at -x, cyan's; +1 for magenta's) ---------------------
    def in_field(self, x: float, y: float, margin: float = 0.0) -> bool:
        return abs(x) <= self.half_length + margin and abs(y) <= self.half_width + margin

    def in_penalty_area(self, x: float, y: float, side: int) -> bool:
        """On the field side of the goal line (its line included) and in the penalty area, its lines included."""
        x_in, y_half = self.area_limits("penalty")
        return x_in <= side * x <= self.outer_half_length and abs(y) <= y_half

    def in_goal_area(self, x: float, y: float, side: int) -> bool:
        """On the field side of the goal line (its line included) and in the goal area, its lines included."""
        x_in, y_half = self.area_limits("goal")
        return x_in <= side * x <= self.outer_half_length and abs(y) <= y_half

    def goal_center(self, side: int) -> tuple[float, float]:
        return (side * self.half_length, 0.0)

    def penalty_spot(self, side: int) -> tuple[float, float]:
        return (side * (self.half_length - self.penalty_spot_distance), 0.0)

    # --- what viewers draw ------------------------------------------------------------------------------
    def lines(self) -> list[dict]:
        """Field markings as drawing primitives (world frame): polylines and arcs with the line width."""
        if self.markings == "none":
            return []
        L, W = self.half_length, self.half_width
        out: list[dict] = [
            {"kind": "polyline", "points": [(-L, -W), (L, -W), (L, W), (-L, W), (-L, -W)]},
            {"kind": "polyline", "points": [(0.0, -W), (0.0, W)]},
            {
                "kind": "arc",
                "center": (0.0, 0.0),
                "radius": self.center_circle_radius,
                "start": 0.0,
                "end": 2 * math.pi,
            },
            {"kind": "dot", "center": (0.0, 0.0), "radius": 0.1},
        ]
        for side in (-1, 1):
            for depth, width in (
                (self.penalty_area_depth, self.penalty_area_width),
                (self.goal_area_depth, self.goal_area_width),
            ):
                x_in = side * (L - depth)
                out.append(
                    {
                        "kind": "polyline",
                        "points": [
                            (side * L, -width / 2),
                            (x_in, -width / 2),
                            (x_in, width / 2),
                            (side * L, width / 2),
                        ],
                    }
                )
            out.append({"kind": "dot", "center": self.penalty_spot(side), "radius": 0.1})
        r = self.corner_arc_radius
        for cx, cy, a0 in ((-L, -W, 0.0), (L, -W, 0.5 * math.pi), (L, W, math.pi), (-L, W, 1.5 * math.pi)):
            out.append({"kind": "arc", "center": (cx, cy), "radius": r, "start": a0, "end": a0 + 0.5 * math.pi})
        return out

    def describe(self) -> dict:
        """Everything a viewer needs to draw the field, as plain JSON-able data."""
        return {
            "length": self.length,
            "width": self.width,
            "margin": self.margin,
            "line_width": self.line_width,
            "goals": self.goals,
            "goal_width": self.goal_width,
            "goal_depth": self.goal_depth,
            "goal_height": self.goal_height,
            "goal_post_size": self.goal_post_size,
            "walls": self.walls,
            "lines": self.lines(),
            "areas": [{"name": a.name, "x0": a.x0, "y0": a.y0, "x1": a.x1, "y1": a.y1} for a in self.areas],
        }
