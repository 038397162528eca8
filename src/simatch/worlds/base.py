"""The base of world plug-ins, and what every world shares: static obstacles placed by hand or scattered.

A world turns the scene's ``[world]`` table into a `FieldGeometry`. The keys every world understands are
the floor's size (``length``, ``width``, ``margin``), the walls, ``areas`` (named zones: a prison, a base),
``obstacles`` (boxes and cylinders at given poses), ``clutter`` (obstacles scattered from a seed) and
``ceiling``; a world kind may refuse keys that belong to another kind (``foreign_keys``) and take its own
settings from ``world.params`` (its ``Params`` model).

Scattering is deterministic: the same ``clutter`` table gives the same obstacles on every machine (its
own ``seed``, not the run's), so every process of a run, every viewer and every judge computes the same
world from the scene file alone.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict

from ..field import Area, FieldGeometry, Obstacle

#: attempts to place one scattered obstacle before giving up
_TRIES = 4000


class WorldError(ValueError):
    """A world that cannot be made from its settings; the message names the key."""


class NoParams(BaseModel):
    model_config = ConfigDict(extra="forbid")


class World:
    """A world plug-in. Subclasses give ``name`` and `geometry` (and may give ``Params``)."""

    name: ClassVar[str] = "world"
    Params: ClassVar[type[BaseModel]] = NoParams
    #: ``[world]`` keys this kind does not understand (they belong to another kind): setting one is a mistake
    foreign_keys: ClassVar[tuple[str, ...]] = ()
    #: ``[world]`` keys whose value, when the scene does not set them, is this kind's own, not the schema's
    own_defaults: ClassVar[dict[str, Any]] = {}

    def __init__(self, spec, params: Any):
        self.spec = spec
        self.params = params
        given = sorted(set(spec.model_fields_set) & set(self.foreign_keys))
        if given:
            raise WorldError(
                f"world.{given[0]}: not a setting of the {self.name} world (world.kind = {spec.kind!r}); "
                f"its settings are the floor, walls, areas, obstacles, clutter and ceiling"
            )

    def geometry(self) -> FieldGeometry:
        raise NotImplementedError

    # --- obstacles: given, then scattered ----------------------------------------------------------------
    def obstacles(self, floor: FieldGeometry) -> tuple[Obstacle, ...]:
        """The obstacles of ``world.obstacles`` and those ``world.clutter`` scatters on ``floor``."""
        given = [given_obstacle(o, k) for k, o in enumerate(self.spec.obstacles)]
        names = [o.name for o in given]
        if len(set(names)) != len(names):
            raise WorldError(f"world.obstacles: two obstacles are named {_first_repeat(names)!r}")
        for k, ob in enumerate(given):
            if not _inside(floor, ob, 0.0):
                raise WorldError(f"world.obstacles[{k}]: {ob.name} does not stand on the floor inside the walls")
        clutter = self.spec.clutter
        if clutter is None or clutter.boxes + clutter.cylinders == 0:
            return tuple(given)
        return tuple(given) + tuple(scatter(clutter, floor, given))


def given_obstacle(o, k: int) -> Obstacle:
    name = o.name or f"obstacle_{k + 1}"
    if o.shape == "cylinder":
        return Obstacle(name, "cylinder", o.x, o.y, o.height, radius=o.radius)
    return Obstacle(name, "box", o.x, o.y, o.height, half_x=o.size[0] / 2, half_y=o.size[1] / 2, yaw=o.yaw)


def _first_repeat(names: list[str]) -> str:
    seen = set()
    for n in names:
        if n in seen:
            return n
        seen.add(n)
    return ""


def _inside(floor: FieldGeometry, ob: Obstacle, margin: float) -> bool:
    """The obstacle's outline lies ``margin`` or more inside the walls."""
    if ob.shape == "cylinder":
        ext_x = ext_y = ob.radius
    else:
        c, s = abs(math.cos(ob.yaw)), abs(math.sin(ob.yaw))
        ext_x, ext_y = c * ob.half_x + s * ob.half_y, s * ob.half_x + c * ob.half_y
    return abs(ob.x) + ext_x <= floor.reach_x - margin and abs(ob.y) + ext_y <= floor.reach_y - margin


def _clear_of_rect(ob: Obstacle, rect: tuple[float, float, float, float], gap: float) -> bool:
    """The obstacle stays ``gap`` or more away from an axis-aligned rectangle (x0, y0, x1, y1)."""
    x0, y0, x1, y1 = rect
    r = ob.bounding_radius + gap
    dx = max(x0 - ob.x, 0.0, ob.x - x1)
    dy = max(y0 - ob.y, 0.0, ob.y - y1)
    return math.hypot(dx, dy) >= r


def scatter(clutter, floor: FieldGeometry, placed: list[Obstacle]) -> list[Obstacle]:
    """``clutter.boxes`` boxes and ``clutter.cylinders`` cylinders at random free places of its region.

    Sizes, heights, places and a box's turn are drawn from ``clutter.seed``. Each obstacle keeps
    ``clutter.gap`` of free floor between its bounding circle and every other obstacle's, the walls, every
    zone of ``world.areas`` and every ``keep_clear`` rectangle, so that robots can pass between them."""
    rng = np.random.default_rng([clutter.seed, 0xC1077E5])
    gap = clutter.gap
    region = clutter.region or (-floor.reach_x, -floor.reach_y, floor.reach_x, floor.reach_y)
    lo, hi = clutter.size
    h_lo, h_hi = clutter.height
    kinds = ["box"] * clutter.boxes + ["cylinder"] * clutter.cylinders
    order = rng.permutation(len(kinds))
    counts = {"box": 0, "cylinder": 0}
    out: list[Obstacle] = []
    keep_out = [(a.x0, a.y0, a.x1, a.y1) for a in floor.areas] + [tuple(r) for r in clutter.keep_clear]
    for k in order:
        shape = kinds[int(k)]
        counts[shape] += 1
        name = f"{shape}_{counts[shape]}"
        for _ in range(_TRIES):
            a, b = rng.uniform(lo, hi), rng.uniform(lo, hi)
            height = rng.uniform(h_lo, h_hi)
            yaw = rng.uniform(-math.pi / 2, math.pi / 2)
            x, y = rng.uniform(region[0], region[2]), rng.uniform(region[1], region[3])
            if shape == "cylinder":
                ob = Obstacle(name, "cylinder", float(x), float(y), float(height), radius=float(a / 2))
            else:
                ob = Obstacle(
                    name,
                    "box",
                    float(x),
                    float(y),
                    float(height),
                    half_x=float(a / 2),
                    half_y=float(b / 2),
                    yaw=float(yaw),
                )
            if (
                _inside(floor, ob, gap)
                and all(
                    math.hypot(ob.x - o.x, ob.y - o.y) >= ob.bounding_radius + o.bounding_radius + gap
                    for o in placed + out
                )
                and all(_clear_of_rect(ob, rect, gap) for rect in keep_out)
            ):
                out.append(ob)
                break
        else:
            raise WorldError(
                f"world.clutter: no room for {len(kinds)} obstacles {gap:g} m apart in the region "
                f"{list(region)} (placed {len(out)}); fewer obstacles, a smaller gap or a larger region"
            )
    return out


def zones(spec) -> tuple[Area, ...]:
    return tuple(Area(**a.model_dump()) for a in spec.areas)
