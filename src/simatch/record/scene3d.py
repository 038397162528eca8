"""The game as a Foxglove 3D scene: two ``foxglove_msgs/msg/SceneUpdate`` channels of a recording.

``/scene/field`` is written at the start: the floor, the markings (``FieldGeometry.lines()``, the very lines
the judges read), the goals tinted with the colour of the team defending them, the boards, any named areas
and the static obstacles (boxes and cylinders at their heights); and again whenever the teams change ends
(the goals change colours). ``/scene/game`` is written a few times per simulated second: each robot as a
cylinder in its team's colour with an arrow along its kicker axis and its id above it, each drone as a flat
disc at its height with an arrow along its heading (drawn twice its size, for the eye: a nano quadrotor is
13 cm across), and the ball. Two channels, because a
viewer that seeks shows the latest message of each channel: the field must not be a message that the
next game update replaces.

A game update always has the same layout (same robots, same labels), so it is encoded once as a template
(`SceneBuilder.template`) and each update only writes the poses into a copy (`simatch.record.messagelog`'s
pose template: the recorder's message log does it in C as it logs the model states, with no Python call).

The scene is for the eye: positions are snapped to a grid of 1/1024 m (a millimetre) and the robots'
orientation quaternions to 1/4096 (three hundredths of a degree); the ball, a plain sphere, is drawn without
its spin. Snapped numbers end in zero bits, so the updates compress to half; the exact states are the
recording's ``/model_states``.
"""

from __future__ import annotations

import colorsys
import hashlib
import math
import struct

import numpy as np

from ..config.schema import Scene
from ..field import arc_points
from ..msgs.cdr import Codec
from ..robots.looks import member_looks
from . import foxglove_msgs as fg
from .messagelog import PoseSlot, fill_poses

FIELD_TOPIC = "/scene/field"
GAME_TOPIC = "/scene/game"
FRAME = "world"
GAME_RATE = 20.0  # game updates per simulated second

NAMED_COLORS = {
    "cyan": (0.0, 0.8, 0.9),
    "magenta": (0.9, 0.1, 0.8),
    "red": (0.9, 0.1, 0.1),
    "blue": (0.1, 0.3, 0.9),
    "green": (0.1, 0.7, 0.2),
    "yellow": (0.95, 0.85, 0.1),
    "orange": (1.0, 0.55, 0.0),
    "purple": (0.5, 0.2, 0.8),
    "white": (0.95, 0.95, 0.95),
    "black": (0.1, 0.1, 0.1),
    "gray": (0.5, 0.5, 0.5),
    "grey": (0.5, 0.5, 0.5),
    "pink": (1.0, 0.6, 0.75),
    "brown": (0.55, 0.35, 0.15),
}

GRID = 1024.0  # positions drawn: steps per metre
TURN_GRID = 4096.0  # orientations drawn: steps per unit of a quaternion


def color_rgb(name: str) -> tuple[float, float, float]:
    """A team colour: a known name, ``#rrggbb``, or a stable colour derived from the name."""
    key = name.strip().lower()
    if key in NAMED_COLORS:
        return NAMED_COLORS[key]
    if key.startswith("#") and len(key) == 7:
        try:
            return tuple(int(key[i : i + 2], 16) / 255.0 for i in (1, 3, 5))  # type: ignore[return-value]
        except ValueError:
            pass
    hue = hashlib.sha256(key.encode()).digest()[0] / 255.0
    return colorsys.hsv_to_rgb(hue, 0.8, 0.9)


class SceneBuilder:
    """Makes the CDR bytes of the field update and of each game update of one scene."""

    def __init__(self, scene: Scene):
        self.scene = scene
        self.geometry = scene.world.geometry()
        self.codec = Codec(fg.typestore)
        self._T = fg.typestore.types
        self._template: bytes | None = None
        self._names: list[str] | None = None
        self._slots: list[PoseSlot] = []

    # --- message helpers -----------------------------------------------------------------------------------
    def _msg(self, short: str, **fields):
        name = short if "/" in short else f"{fg.PACKAGE}/msg/{short}"
        cls = self._T[name]
        return cls(**fields)

    def _pose(self, x=0.0, y=0.0, z=0.0, yaw=0.0):
        P = self._T
        return P["geometry_msgs/msg/Pose"](
            position=P["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=float(z)),
            orientation=P["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)),
        )

    def _vec(self, x, y, z):
        return self._T["geometry_msgs/msg/Vector3"](x=float(x), y=float(y), z=float(z))

    def _color(self, rgb, a=1.0):
        return self._msg("Color", r=float(rgb[0]), g=float(rgb[1]), b=float(rgb[2]), a=float(a))

    def _entity(self, eid: str, **prims):
        T = self._T
        fields = {
            k: prims.get(k, [])
            for k in ("arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models")
        }
        return self._msg(
            "SceneEntity",
            timestamp=T["builtin_interfaces/msg/Time"](sec=0, nanosec=0),
            frame_id=FRAME,
            id=eid,
            lifetime=T["builtin_interfaces/msg/Duration"](sec=0, nanosec=0),
            frame_locked=False,
            metadata=[],
            **fields,
        )

    def _cube(self, x, y, z, sx, sy, sz, rgb, a=1.0, yaw=0.0):
        return self._msg(
            "CubePrimitive", pose=self._pose(x, y, z, yaw), size=self._vec(sx, sy, sz), color=self._color(rgb, a)
        )

    def _line(self, points, width, rgb, z=0.003, loop=False):
        P = self._T["geometry_msgs/msg/Point"]
        return self._msg(
            "LinePrimitive",
            type=1 if loop else 0,
            pose=self._pose(),
            thickness=float(width),
            scale_invariant=False,
            points=[P(x=float(px), y=float(py), z=z) for px, py in points],
            color=self._color(rgb),
            colors=[],
            indices=np.zeros(0, dtype=np.uint32),
        )

    def _update(self, entities) -> bytes:
        return self.codec.encode(self._msg("SceneUpdate", deletions=[], entities=entities), fg.SCENE_UPDATE)

    # --- the field -----------------------------------------------------------------------------------------
    def field_update(self, signs: dict[str, int] | None = None) -> bytes:
        """The field; ``signs`` (team -> +1 attacking +x, -1 attacking -x) says who defends which goal now
        (default: the scene's team frames)."""
        F = self.geometry
        L, W, m = F.half_length, F.half_width, F.margin
        white = (0.97, 0.97, 0.97)
        cubes = [self._cube(0.0, 0.0, -0.01, 2 * (L + m), 2 * (W + m), 0.02, (0.13, 0.45, 0.18))]
        lines, cylinders = [], []
        for item in F.lines():
            if item["kind"] == "polyline":
                lines.append(self._line(item["points"], F.line_width, white))
            elif item["kind"] == "arc":
                lines.append(self._line(arc_points(item, 72), F.line_width, white))
            elif item["kind"] == "dot":
                (cx, cy), r = item["center"], item["radius"]
                cylinders.append(
                    self._msg(
                        "CylinderPrimitive",
                        pose=self._pose(cx, cy, 0.003),
                        size=self._vec(2 * r, 2 * r, 0.004),
                        bottom_scale=1.0,
                        top_scale=1.0,
                        color=self._color(white),
                    )
                )
        for area in F.areas:
            lines.append(
                self._line(
                    [(area.x0, area.y0), (area.x1, area.y0), (area.x1, area.y1), (area.x0, area.y1)],
                    F.line_width,
                    (0.95, 0.85, 0.1),
                    loop=True,
                )
            )
        if F.walls:
            h, t = F.wall_height, 0.05
            board = (0.25, 0.25, 0.28)
            for sx in (-1, 1):
                cubes.append(self._cube(sx * (L + m + t / 2), 0.0, h / 2, t, 2 * (W + m + t), h, board))
            for sy in (-1, 1):
                cubes.append(self._cube(0.0, sy * (W + m + t / 2), h / 2, 2 * (L + m), t, h, board))
        if F.goals:
            cubes += self._goals(signs)
        rock = (0.36, 0.38, 0.42)
        for ob in F.obstacles:
            if ob.shape == "cylinder":
                cylinders.append(
                    self._msg(
                        "CylinderPrimitive",
                        pose=self._pose(ob.x, ob.y, ob.height / 2),
                        size=self._vec(2 * ob.radius, 2 * ob.radius, ob.height),
                        bottom_scale=1.0,
                        top_scale=1.0,
                        color=self._color(rock),
                    )
                )
            else:
                cubes.append(
                    self._cube(ob.x, ob.y, ob.height / 2, 2 * ob.half_x, 2 * ob.half_y, ob.height, rock, yaw=ob.yaw)
                )
        field = self._entity("field", cubes=cubes, lines=lines, cylinders=cylinders)
        return self._update([field])

    def _goals(self, signs: dict[str, int] | None = None) -> list:
        F = self.geometry
        L, p, gw, gh, gd = F.half_length, F.goal_post_size, F.goal_width, F.goal_height, F.goal_depth
        defenders = {}
        for team in self.scene.teams:
            sign = (signs or {}).get(team, self.scene.team_sign(team))
            defenders[-sign] = team  # attacking +x means defending the goal at -x
        out = []
        for side in (-1, 1):
            x = side * (L + p / 2)
            for sy in (-1, 1):
                out.append(self._cube(x, sy * (gw / 2 + p / 2), gh / 2, p, p, gh, (1.0, 1.0, 1.0)))
            out.append(self._cube(x, 0.0, gh + p / 2, p, gw + 2 * p, p, (1.0, 1.0, 1.0)))
            team = defenders.get(side)
            tint = color_rgb(self.scene.team_color(team)) if team else (0.8, 0.8, 0.8)
            out.append(self._cube(side * (L + p + gd / 2), 0.0, gh / 2, gd, gw, gh, tint, a=0.25))
        return out

    # --- the game ------------------------------------------------------------------------------------------
    def game_update(self, names: list[str], pose: np.ndarray) -> bytes:
        """``names`` and ``pose`` (M x 7: x y z qw qx qy qz, world frame) as in ModelStates."""
        template, slots = self.template(names)
        return fill_poses(template, slots, pose, GRID, TURN_GRID)

    def template(self, names: list[str]) -> tuple[bytes, list[PoseSlot]]:
        """The game update of these models encoded once, and where each pose lies in it: the ball with its
        own height, the robots (planar: their quaternion is a turn about z) and their labels at a fixed height."""
        if self._template is None or names != self._names:
            self._build_template(list(names))
        return self._template, self._slots

    def _bodies(self) -> dict[str, dict]:
        """Every robot's body as viewers draw it (`simatch.robots.looks`), by name."""
        return {f"{team}/{m.id}": member_looks(m) for team, spec in self.scene.teams.items() for m in spec.members()}

    def _drone_entity(self, name: str, k: int, body: dict, mark):
        """A drone: a flat disc in its team's colour at its height, turned with its heading, an arrow along
        the heading and its id (all at its centre: the template writes one pose per model)."""
        team, _, rid = name.partition("/")
        rgb = color_rgb(self.scene.team_color(team)) if team in self.scene.teams else (0.6, 0.6, 0.6)
        span = 2 * body["radius"] * body["scale"]  # drawn larger than it is, as every viewer draws it
        body = self._msg(
            "CylinderPrimitive",
            pose=mark(k, "drone", 0.0),
            size=self._vec(span, span, 0.04),
            bottom_scale=1.0,
            top_scale=1.0,
            color=self._color(rgb),
        )
        nose = self._msg(
            "ArrowPrimitive",
            pose=mark(k, "drone", 0.0),
            shaft_length=0.6 * span,
            shaft_diameter=0.02,
            head_length=0.25 * span,
            head_diameter=0.06,
            color=self._color((0.1, 0.1, 0.1)),
        )
        label = self._msg(
            "TextPrimitive",
            pose=mark(k, "drone", 0.0),
            billboard=True,
            font_size=0.25,
            scale_invariant=False,
            color=self._color((1.0, 1.0, 1.0)),
            text=rid or name,
        )
        return self._entity(name, cylinders=[body], arrows=[nose], texts=[label])

    def _build_template(self, names: list[str]) -> None:
        """Encode one update with a distinct sentinel in every pose, then note where each pose lies."""
        sentinels: list[tuple[int, float, str, float]] = []

        def mark(k: int, kind: str, z: float):
            value = 7.0e5 + len(sentinels) / 64.0  # exact in binary, never a real coordinate
            sentinels.append((k, value, kind, z))
            return self._pose(value, 0.0, z)

        entities = []
        bodies = self._bodies()
        for k, name in enumerate(names):
            body = bodies.get(name)
            if body is not None and body["kind"] == "drone":
                entities.append(self._drone_entity(name, k, body, mark))
                continue
            if name == "ball":
                r = self.scene.ball.radius
                entities.append(
                    self._entity(
                        "ball",
                        spheres=[
                            self._msg(
                                "SpherePrimitive",
                                pose=mark(k, "ball", 0.0),
                                size=self._vec(2 * r, 2 * r, 2 * r),
                                color=self._color((1.0, 0.5, 0.0)),
                            )
                        ],
                    )
                )
                continue
            team, _, rid = name.partition("/")
            radius, height = (body["radius"], body["height"]) if body is not None else (0.25, 0.8)
            rgb = color_rgb(self.scene.team_color(team)) if team in self.scene.teams else (0.6, 0.6, 0.6)
            body = self._msg(
                "CylinderPrimitive",
                pose=mark(k, "robot", height / 2),
                size=self._vec(2 * radius, 2 * radius, height),
                bottom_scale=1.0,
                top_scale=1.0,
                color=self._color(rgb),
            )
            kicker = self._msg(
                "ArrowPrimitive",
                pose=mark(k, "robot", height + 0.02),
                shaft_length=0.8 * radius,
                shaft_diameter=0.06,
                head_length=0.2 * radius + 0.05,
                head_diameter=0.14,
                color=self._color((0.1, 0.1, 0.1)),
            )
            label = self._msg(
                "TextPrimitive",
                pose=mark(k, "text", height + 0.35),
                billboard=True,
                font_size=0.4,
                scale_invariant=False,
                color=self._color((1.0, 1.0, 1.0)),
                text=rid or name,
            )
            entities.append(self._entity(name, cylinders=[body], arrows=[kicker], texts=[label]))
        template = self._update(entities)
        slots = []
        for k, value, kind, z in sentinels:
            pattern = struct.pack("<d", value)
            off = template.find(pattern)
            if off < 0 or template.find(pattern, off + 1) >= 0:
                raise RuntimeError(f"scene template: pose sentinel {value} not found exactly once")
            slots.append((off, k, math.nan if kind in ("ball", "drone") else z, kind in ("robot", "drone")))
        self._template, self._names, self._slots = template, names, slots
