"""What a robot of an aerial team tells its team-mates it sees, and what it knows from them.

Each robot's StrategyInfo carries, in ``user``, a head of a few numbers (a chaser: the net's radius and
slack, as the ``encircle`` chasers share them; a drone: NaN) then the opponents it perceives this tick:
``[head..., n, x1, y1, ..., xn, yn]`` (team frame). A robot's `Sightings` joins what it sees itself, what its
team-mates reported (their StrategyInfo of the last tick, through the team picture) and what was seen
lately and is hidden now (remembered ``memory`` seconds, its last known place): drones that see the whole
arena from above make every chaser know every target, and a target that slips behind an obstacle is not
forgotten at once.

`team_opponents` tells team-mates from opponents among the robots a robot sees: with exact perception a
team-mate is seen exactly where it says it is (whether or not every team-mate is in sight); with noise, each
team-mate claims the obstacle nearest to it at about its height (a target under a drone is no drone).
"""

from __future__ import annotations

import math

from ..encirclement.view import SAME_ROBOT


def encode(head: tuple[float, ...], seen: list[tuple[float, float]]) -> tuple[float, ...]:
    return (*head, float(len(seen)), *(v for p in seen for v in p))


def decode(user, head: int) -> list[tuple[float, float]]:
    """The sightings of a ``user`` field with a head of ``head`` numbers (nothing if malformed)."""
    if len(user) <= head:
        return []
    n = user[head]
    if not math.isfinite(n) or n < 0 or head + 1 + 2 * int(n) > len(user):
        return []
    flat = user[head + 1 : head + 1 + 2 * int(n)]
    flat = flat.tolist() if hasattr(flat, "tolist") else [float(v) for v in flat]
    return [p for p in zip(flat[0::2], flat[1::2]) if math.isfinite(p[0] + p[1])]


def by_cell(points: list[tuple[float, float]], cell: float) -> list[tuple[float, float]]:
    """One point per ``cell``-sized square (the last of those in it): many reports of one robot become one."""
    return list({(round(x / cell), round(y / cell)): (x, y) for x, y in points}.values())


class TeamKnowledge:
    """What a team knows of its opponents (team frame), brought up to date with each team picture: every
    place its robots reported in the picture (everybody's StrategyInfo of the last tick), merged per
    half-metre cell, and what it saw lately and sees no more: a place of the previous picture near which
    (within a metre) nothing is seen now is remembered for ``memory`` seconds, or until something is seen
    near it again.

    The team's robots share one (the team strategy makes it), so in one process a picture is worked out once
    for all of them; a robot in a process of its own works the same pictures out alike. Bringing it up to
    date twice with the same picture changes nothing. A robot reported twice (by two robots, or on a cell's
    edge) counts twice, which changes nothing for whoever asks for the outermost one."""

    CELL = 0.5
    NEAR = 1.0  # [m]

    def __init__(self, memory: float, head: int = 2):
        self.memory = memory
        self.head = head
        self.infos: tuple = ()  # the picture last worked out (its messages, kept: compared by identity)
        self.last: list[tuple[float, float]] = []
        self.lost: list[tuple[float, float, float]] = []  # place, time last seen
        self.known: list[tuple[float, float]] = []

    def update(self, now: float, world) -> list[tuple[float, float]]:
        infos = tuple(world.strategies.values())
        if len(infos) == len(self.infos) and all(a is b for a, b in zip(infos, self.infos)):
            return self.known
        here = by_cell([p for info in infos for p in decode(info.user, self.head)], self.CELL)
        if self.memory > 0.0:
            r, old = self.NEAR, now - self.memory

            def seen_near(x: float, y: float) -> bool:
                return any(abs(x - a) <= r and abs(y - b) <= r for a, b in here)

            lost = [(x, y, t) for x, y, t in self.lost if t >= old and not seen_near(x, y)]
            self.lost = lost + [(x, y, now) for x, y in self.last if not seen_near(x, y)]
        self.infos, self.last = infos, here
        self.known = here + [(x, y) for x, y, _ in self.lost]
        return self.known


class Sightings:
    """The opponents one robot knows of (team frame): what it sees now, and what its team knows."""

    def __init__(self, team: TeamKnowledge):
        self.team = team

    def update(self, now: float, own: list[tuple[float, float]], world) -> list[tuple[float, float]]:
        return own + self.team.update(now, world)


def team_opponents(world) -> list[tuple[float, float]]:
    """Positions (team frame) of the robots I see that are not my team-mates, heights considered."""
    vision = world.vision
    o = vision.obstacles
    xs, ys = o.x.tolist(), o.y.tolist()
    mates = [(r.x, r.y, r.z) for r in vision.robots if r.id != world.id]
    exact = {(x, y) for x, y, _ in mates}
    rest = [(x, y) for x, y in zip(xs, ys) if (x, y) not in exact]
    if len(rest) < len(xs) or not mates:
        return rest  # exact perception: a team-mate is exactly where it says
    out = []
    for x, y, z in zip(xs, ys, o.z.tolist()):
        if not any(abs(x - mx) < SAME_ROBOT and abs(y - my) < SAME_ROBOT and abs(z - mz) < 0.5 for mx, my, mz in mates):
            out.append((x, y))
    return out
