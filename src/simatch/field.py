"""Field geometry: one description of the playing area that the physics, the judges, the strategies and
the viewers all read, so that a line drawn in a viewer is the line the referee judges.

World frame: origin at the field centre, +x towards magenta's goal (cyan defends -x), z up; metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cached_property


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
class Obstacle:
    """A static solid standing on the floor (world frame): a box turned by ``yaw``, or an upright cylinder.

    Robots cannot pass through it, a ground robot's line of sight stops at it (``perception.line_of_sight``),
    drones fly over it when it is low enough; viewers draw it and strategies plan around it."""

    name: str
    shape: str  # "box" or "cylinder"
    x: float
    y: float
    height: float
    half_x: float = 0.0  # a box's half length along its own x (turned by yaw)
    half_y: float = 0.0
    yaw: float = 0.0
    radius: float = 0.0  # a cylinder's

    @cached_property
    def bounding_radius(self) -> float:
        """Radius of the smallest circle about the centre that holds the outline [m]."""
        return self.radius if self.shape == "cylinder" else math.hypot(self.half_x, self.half_y)

    @cached_property
    def _turn(self) -> tuple[float, float]:
        return (math.cos(self.yaw), math.sin(self.yaw))

    def local(self, x: float, y: float) -> tuple[float, float]:
        """A world point in the obstacle's own frame (a box's axes)."""
        dx, dy = x - self.x, y - self.y
        c, s = self._turn
        return (c * dx + s * dy, -s * dx + c * dy)

    def distance(self, x: float, y: float) -> float:
        """Signed horizontal distance of a point from the outline: negative inside [m]."""
        if self.shape == "cylinder":
            return math.hypot(x - self.x, y - self.y) - self.radius
        lx, ly = self.local(x, y)
        qx, qy = abs(lx) - self.half_x, abs(ly) - self.half_y
        outside = math.hypot(max(qx, 0.0), max(qy, 0.0))
        return outside + min(max(qx, qy), 0.0)

    def away(self, x: float, y: float) -> tuple[float, float]:
        """The unit direction (world frame) in which the distance from the outline grows fastest at (x, y)."""
        if self.shape == "cylinder":
            dx, dy = x - self.x, y - self.y
            d = math.hypot(dx, dy)
            return (dx / d, dy / d) if d > 1e-9 else (1.0, 0.0)
        lx, ly = self.local(x, y)
        qx, qy = abs(lx) - self.half_x, abs(ly) - self.half_y
        if qx > 0.0 or qy > 0.0:
            gx, gy = max(qx, 0.0) * math.copysign(1.0, lx), max(qy, 0.0) * math.copysign(1.0, ly)
        elif qx > qy:
            gx, gy = math.copysign(1.0, lx), 0.0
        else:
            gx, gy = 0.0, math.copysign(1.0, ly)
        n = math.hypot(gx, gy) or 1.0
        c, s = self._turn
        return ((c * gx - s * gy) / n, (s * gx + c * gy) / n)

    def contains(self, x: float, y: float, margin: float = 0.0) -> bool:
        return self.near(x, y, margin) and self.distance(x, y) < margin

    def near(self, x: float, y: float, margin: float) -> bool:
        """A quick test: (x, y) may lie within ``margin`` of the outline (it is within the bounding circle's)."""
        r = self.bounding_radius + margin
        dx, dy = x - self.x, y - self.y
        return dx * dx + dy * dy <= r * r

    def corners(self) -> list[tuple[float, float]]:
        """A box's four corners, counter-clockwise (world frame)."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        out = []
        for lx, ly in ((1, 1), (-1, 1), (-1, -1), (1, -1)):
            px, py = lx * self.half_x, ly * self.half_y
            out.append((self.x + c * px - s * py, self.y + s * px + c * py))
        return out

    def turned(self) -> Obstacle:
        """The obstacle in a frame turned by pi about z (a team that attacks -x)."""
        return replace(self, x=-self.x, y=-self.y, yaw=math.remainder(self.yaw + math.pi, 2 * math.pi))

    def describe(self) -> dict:
        out = {"name": self.name, "shape": self.shape, "x": self.x, "y": self.y, "height": self.height}
        if self.shape == "cylinder":
            out["radius"] = self.radius
        else:
            out.update(half_x=self.half_x, half_y=self.half_y, yaw=self.yaw)
        return out


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
    #: the world plug-in that made this description (``world.kind``)
    kind: str = "msl_field"
    obstacles: tuple[Obstacle, ...] = field(default_factory=tuple)
    ceiling: float | None = None  # height of a ceiling over the whole world [m]; None: open sky

    @property
    def half_length(self) -> float:
        return 0.5 * self.length

    @property
    def half_width(self) -> float:
        return 0.5 * self.width

    @property
    def reach_x(self) -> float:
        """Half length of the floor inside the walls (lines plus margin) [m]."""
        return self.half_length + self.margin

    @property
    def reach_y(self) -> float:
        return self.half_width + self.margin

    def obstacle_at(self, x: float, y: float, margin: float = 0.0) -> Obstacle | None:
        """The first obstacle nearer than ``margin`` to (x, y) (inside it for margin 0), if any."""
        for ob in self.obstacles:
            if ob.contains(x, y, margin):
                return ob
        return None

    def free(self, x: float, y: float, margin: float = 0.0) -> bool:
        """(x, y) is on the floor, ``margin`` or more from the walls and from every obstacle."""
        return (
            abs(x) <= self.reach_x - margin
            and abs(y) <= self.reach_y - margin
            and self.obstacle_at(x, y, margin) is None
        )

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
            "kind": self.kind,
            "wall_height": self.wall_height,
            "obstacles": [ob.describe() for ob in self.obstacles],
            "ceiling": self.ceiling,
        }


def arc_points(item: dict, per_turn: int) -> list[tuple[float, float]]:
    """The points of an ``arc`` of `FieldGeometry.lines` as a polyline, ``per_turn`` segments for a whole
    circle (at least four), for viewers that draw lines only."""
    (cx, cy), r = item["center"], item["radius"]
    a0, a1 = item["start"], item["end"]
    n = max(4, int(abs(a1 - a0) / (2 * math.pi) * per_turn))
    return [
        (cx + r * math.cos(a0 + (a1 - a0) * k / n), cy + r * math.sin(a0 + (a1 - a0) * k / n)) for k in range(n + 1)
    ]
