"""What a learning agent observes: its robot's perception (OmniVisionInfo, team frame) and its team's game
command (CoachInfo), as one fixed-size float32 vector with a documented layout, or as a `Dict` of the same parts.

The numbers are the messages' own: a robot handed to learning perceives exactly what any robot of the scene
perceives, realism knobs (noise, dropout, latency) included. Angles are given as cosine and sine (no jump at
+-pi); the game commands as one-hot vectors. Layout, in order (``T``: the teammate slots, ``K``: the obstacle
slots; by default the team's other robots and every other robot of the scene):

========== ======= ===========================================================================================
part       size    entries
========== ======= ===========================================================================================
game       36      one-hot of CoachInfo.match_mode over the 17 commands (`COMMANDS` order), one-hot of
                   match_type, the restart spot ball_x, ball_y [m]
self       10      x, y [m], cos yaw, sin yaw, vx, vy [m/s, team frame], w [rad/s], valid, stuck, holding_ball
ball       12      seen by me (state == SEEBALLBYOWN), pos_known, velocity_known, x, y, z [m], vx, vy, vz [m/s],
                   distance [m], cos angle, sin angle (bearing from my kicker axis)
goals      6       the centre of the goal my team attacks (team frame (+L, 0), L half the field's length):
                   distance [m], cos and sin of its bearing from my kicker axis; the same for my own goal (-L, 0)
                   (from my perceived pose and the field's geometry, as the ball's bearing is from the ball's)
teammates  11 x T  per teammate, in the team's id order: present, then as self
obstacles  9 x K   per robot I see (either team), nearest first: present, x, y, vx, vy, distance, cos angle,
                   sin angle, radius
structures 6 x S   (a world with static obstacles, docs/aerial.md) per obstacle of the world's map, nearest
                   first: present, distance [m] from my centre to its outline, cos and sin of the bearing of
                   its nearest point from my kicker axis, its bounding radius [m], its height [m]
heights    2+T+K   (a scene with aerial robots) my height z [m] and climb rate vz [m/s], then each teammate
                   slot's height and each obstacle slot's height, in the slots' order (0 on the ground)
========== ======= ===========================================================================================

``S`` defaults to every static obstacle of the world (none on the MSL field: no part); the obstacles are the
map every robot has (`FieldGeometry.obstacles`, in the team frame), measured from my perceived pose.
Scenes without static obstacles or aerial robots keep the layout without those parts.

A slot nobody fills (an obstacle dropped by perception, fewer robots than slots) is all zeros, with present 0.
A policy trained with fewer slots plays in a larger scene: it sees its nearest K obstacles and first T
teammates. Every number is clipped to the space's bounds (`BOUND_*`), which only noise far beyond the field's
size can reach. Before the first perception (latency) everything but the game command is zero.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..field import Obstacle
from ..msgs import BallInfo
from ..msgs.game_commands import MatchMode

#: CoachInfo commands in one-hot order
COMMANDS: tuple[int, ...] = tuple(int(m) for m in MatchMode)
_COMMAND_INDEX = {c: i for i, c in enumerate(COMMANDS)}

GAME = ("match_mode[17]", "match_type[17]", "ball_x", "ball_y")
SELF = ("x", "y", "cos_yaw", "sin_yaw", "vx", "vy", "w", "valid", "stuck", "holding_ball")
BALL = (
    "seen_by_me",
    "pos_known",
    "velocity_known",
    "x",
    "y",
    "z",
    "vx",
    "vy",
    "vz",
    "distance",
    "cos_angle",
    "sin_angle",
)
TEAMMATE = ("present", *SELF)
GOALS = (
    "attack_distance",
    "attack_cos_angle",
    "attack_sin_angle",
    "defend_distance",
    "defend_cos_angle",
    "defend_sin_angle",
)
OBSTACLE = ("present", "x", "y", "vx", "vy", "distance", "cos_angle", "sin_angle", "radius")
GAME_SIZE = 2 * len(COMMANDS) + 2
#: per static obstacle of the world's map (boxes, cylinders: `FieldGeometry.obstacles`), nearest first
STRUCTURE = ("present", "distance", "cos_angle", "sin_angle", "radius", "height")
#: in a scene with aerial robots, a last part: my height and climb rate, then each team-mate's and each
#: obstacle's height, in the slots' order (0 on the ground)
HEIGHTS = ("z", "vz")

#: bounds of the observation space: positions and distances [m], speeds [m/s], turn rates [rad/s]
BOUND_POSITION = 250.0
BOUND_SPEED = 100.0
BOUND_TURN = 200.0
_SEEBALLBYOWN = BallInfo.SEEBALLBYOWN


class Layout:
    """The observation of one agent: sizes, names of every entry, bounds, and the encoder."""

    def __init__(self, teammates: int, obstacles: int, half_length: float, heights: bool = False, structures: int = 0):
        if teammates < 0 or obstacles < 0 or structures < 0:
            raise ValueError("teammate, obstacle and structure slots must be >= 0")
        self.teammates = int(teammates)
        self.obstacles = int(obstacles)
        self.structures = int(structures)  # slots for the world's static obstacles: see `STRUCTURE`
        self.half_length = float(half_length)
        self.heights = bool(heights)  # a part of heights (a scene with aerial robots): see `HEIGHTS`
        self.parts: dict[str, tuple[int, ...]] = {
            "game": (GAME_SIZE,),
            "self": (len(SELF),),
            "ball": (len(BALL),),
            "goals": (len(GOALS),),
        }
        if self.teammates:
            self.parts["teammates"] = (self.teammates, len(TEAMMATE))
        if self.obstacles:
            self.parts["obstacles"] = (self.obstacles, len(OBSTACLE))
        if self.structures:
            self.parts["structures"] = (self.structures, len(STRUCTURE))
        if self.heights:
            self.parts["heights"] = (len(HEIGHTS) + self.teammates + self.obstacles,)
        self.offsets: dict[str, slice] = {}
        at = 0
        for name, shape in self.parts.items():
            n = int(np.prod(shape))
            self.offsets[name] = slice(at, at + n)
            at += n
        self.size = at
        self.low, self.high = self._bounds()

    # --- description ---------------------------------------------------------------------------------------
    def names(self) -> list[str]:
        """The name of every entry of the vector, e.g. ``ball.x`` or ``obstacles[2].distance``."""
        out = [f"game.match_mode.{MatchMode(c).name}" for c in COMMANDS]
        out += [f"game.match_type.{MatchMode(c).name}" for c in COMMANDS]
        out += ["game.ball_x", "game.ball_y"]
        out += [f"self.{n}" for n in SELF] + [f"ball.{n}" for n in BALL] + [f"goals.{n}" for n in GOALS]
        out += [f"teammates[{i}].{n}" for i in range(self.teammates) for n in TEAMMATE]
        out += [f"obstacles[{i}].{n}" for i in range(self.obstacles) for n in OBSTACLE]
        out += [f"structures[{i}].{n}" for i in range(self.structures) for n in STRUCTURE]
        if self.heights:
            out += [f"heights.self.{n}" for n in HEIGHTS]
            out += [f"heights.teammates[{i}].z" for i in range(self.teammates)]
            out += [f"heights.obstacles[{i}].z" for i in range(self.obstacles)]
        return out

    def _bounds(self) -> tuple[np.ndarray, np.ndarray]:
        kinds = {
            "x": BOUND_POSITION,
            "y": BOUND_POSITION,
            "z": BOUND_POSITION,
            "ball_x": BOUND_POSITION,
            "ball_y": BOUND_POSITION,
            "distance": BOUND_POSITION,
            "radius": BOUND_POSITION,
            "height": BOUND_POSITION,
            "vx": BOUND_SPEED,
            "vy": BOUND_SPEED,
            "vz": BOUND_SPEED,
            "w": BOUND_TURN,
        }
        high = np.ones(self.size, dtype=np.float32)
        low = np.zeros(self.size, dtype=np.float32)
        for i, name in enumerate(self.names()):
            leaf = name.rsplit(".", 1)[-1]
            if leaf in kinds:
                high[i], low[i] = kinds[leaf], -kinds[leaf]
            elif leaf.endswith("distance"):
                high[i] = BOUND_POSITION
            elif "cos_" in leaf or "sin_" in leaf:
                low[i] = -1.0
        low[[i for i, n in enumerate(self.names()) if n.endswith((".distance", ".radius", ".height"))]] = 0.0
        return low, high

    def split(self, vector: np.ndarray) -> dict[str, np.ndarray]:
        """The `Dict` form of a vector: one array per part (views, shaped as `parts`)."""
        return {name: vector[self.offsets[name]].reshape(shape) for name, shape in self.parts.items()}

    # --- encoding ---------------------------------------------------------------------------------------------
    def encode(self, vision, coach, teammate_ids: list[int], structures: Sequence[Obstacle] = ()) -> np.ndarray:
        """The vector of one robot from its latest OmniVisionInfo (None before the first) and CoachInfo (None
        before the first); ``teammate_ids`` fixes the order of the teammate slots; ``structures`` are the
        world's static obstacles in the robot's team frame (its `WorldModel.field.obstacles`)."""
        out = np.zeros(self.size, dtype=np.float32)
        if coach is not None:
            out[_COMMAND_INDEX.get(int(coach.match_mode), 0)] = 1.0
            out[len(COMMANDS) + _COMMAND_INDEX.get(int(coach.match_type), 0)] = 1.0
            out[2 * len(COMMANDS)] = coach.ball_x
            out[2 * len(COMMANDS) + 1] = coach.ball_y
        if vision is not None:
            self._encode_vision(out, vision, teammate_ids, structures)
        np.clip(out, self.low, self.high, out=out)
        return out

    def _encode_vision(self, out: np.ndarray, vision, teammate_ids: list[int], structures) -> None:
        me = None
        mates = {}
        for r in vision.robots:
            if r.id == vision.robot_id:
                me = r
            else:
                mates[r.id] = r
        at = GAME_SIZE
        if me is not None:
            out[at : at + len(SELF)] = _robot(me)
            g = self.offsets["goals"].start
            for side in (1.0, -1.0):
                dx, dy = side * self.half_length - me.x, -me.y
                bearing = math.atan2(dy, dx) - me.yaw
                out[g : g + 3] = (math.hypot(dx, dy), math.cos(bearing), math.sin(bearing))
                g += 3
        at += len(SELF)
        b = vision.ball
        if b.pos_known:
            out[at : at + len(BALL)] = (
                b.state == _SEEBALLBYOWN,
                1.0,
                b.velocity_known,
                b.x,
                b.y,
                b.z,
                b.vx,
                b.vy,
                b.vz,
                b.distance,
                math.cos(b.angle),
                math.sin(b.angle),
            )
        at += len(BALL) + len(GOALS)
        for rid in teammate_ids[: self.teammates]:
            r = mates.get(rid)
            if r is not None:
                out[at] = 1.0
                out[at + 1 : at + len(TEAMMATE)] = _robot(r)
            at += len(TEAMMATE)
        at = self.offsets["obstacles"].start if self.obstacles else at
        o = vision.obstacles
        n = len(o.x)
        if n and self.obstacles:
            k = min(n, self.obstacles)
            order = np.argsort(o.distance, kind="stable")[:k]
            angle = o.angle[order].astype(np.float64)
            block = np.stack(
                (
                    np.ones(k),
                    o.x[order],
                    o.y[order],
                    o.vx[order],
                    o.vy[order],
                    o.distance[order],
                    np.cos(angle),
                    np.sin(angle),
                    o.radius[order],
                ),
                axis=1,
            )
            out[at : at + k * len(OBSTACLE)] = block.ravel()
        if self.structures and me is not None and structures:
            self._encode_structures(out, me, structures)
        if self.heights:  # my height and climb rate, my team-mates' and the obstacles' heights, slot by slot
            h = self.offsets["heights"].start
            if me is not None:
                out[h : h + 2] = (me.z, me.vz)
            h += len(HEIGHTS)
            for i, rid in enumerate(teammate_ids[: self.teammates]):
                r = mates.get(rid)
                if r is not None:
                    out[h + i] = r.z
            h += self.teammates
            if n and self.obstacles:
                out[h : h + k] = o.z[order]

    def _encode_structures(self, out: np.ndarray, me, structures: Sequence[Obstacle]) -> None:
        """The nearest static obstacles as I see them from my perceived pose: how far their outline is, in
        which direction its nearest point lies, how big and how tall they are."""
        rows = []
        for ob in structures:
            d = ob.distance(me.x, me.y)
            ax, ay = ob.away(me.x, me.y)  # the nearest point of the outline is d back along it
            bearing = math.atan2(-ay, -ax) - me.yaw
            rows.append((max(d, 0.0), math.cos(bearing), math.sin(bearing), ob.bounding_radius, ob.height))
        rows.sort(key=lambda row: row[0])
        at = self.offsets["structures"].start
        for row in rows[: self.structures]:
            out[at : at + len(STRUCTURE)] = (1.0, *row)
            at += len(STRUCTURE)


def _robot(r) -> tuple:
    """The `SELF` entries of a RobotInfo."""
    return (r.x, r.y, math.cos(r.yaw), math.sin(r.yaw), r.vx, r.vy, r.w, r.valid, r.stuck, r.holding_ball)
