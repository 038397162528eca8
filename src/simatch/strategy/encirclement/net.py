"""The chasers' net: where n chasers stand to fence every free target in with the prison.

The net is a level set of the distance to the prison rectangle: every point at distance ``r`` from the
prison (a rounded rectangle), cut by the arena's walls. Everything between the net and the prison is
inside; a target inside flees from the chasers standing on the net, that is towards the prison. Shrinking
``r`` sweeps the arena and tightens the ring around the prison. Where the prison touches a wall the net is
a U whose ends rest on that wall; where ``r`` is large the net is one or more arcs between walls (the
walls close the fence); in the open it is a closed ring.

The curve is handled exactly (four sides and four quarter circles, by arc length). Pure geometry, in any
frame (the strategies use their team frame).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ...field import Area, FieldGeometry

HALF_PI = 0.5 * math.pi
_EPS = 1e-9


@dataclass(frozen=True)
class Arena:
    """The floor a robot's centre can reach: |x| <= half_x, |y| <= half_y (walls minus a clearance)."""

    half_x: float
    half_y: float

    @classmethod
    def of(cls, field: FieldGeometry, clearance: float) -> Arena:
        """The reach of a robot's centre inside the walls at the edge of the field's margin."""
        return cls(field.half_length + field.margin - clearance, field.half_width + field.margin - clearance)

    def clamp(self, x: float, y: float) -> tuple[float, float]:
        return (min(max(x, -self.half_x), self.half_x), min(max(y, -self.half_y), self.half_y))


def prison_distance(prison: Area, x: float, y: float) -> float:
    """Distance of a point to the prison rectangle (0 inside)."""
    return math.hypot(max(prison.x0 - x, 0.0, x - prison.x1), max(prison.y0 - y, 0.0, y - prison.y1))


class LevelSet:
    """The closed curve at distance ``r`` > 0 from the prison, counter-clockwise, by arc length ``s``.

    Pieces, in order: bottom side, corner (x1, y0), right side, corner (x1, y1), top side, corner (x0, y1),
    left side, corner (x0, y0); a corner is a quarter circle of radius r about that corner of the prison."""

    def __init__(self, prison: Area, r: float):
        self.prison, self.r = prison, r
        w, h, arc = prison.x1 - prison.x0, prison.y1 - prison.y0, HALF_PI * r
        self.lengths = (w, arc, h, arc, w, arc, h, arc)
        self.starts = tuple(sum(self.lengths[:k]) for k in range(8))
        self.perimeter = sum(self.lengths)

    def point(self, s: float) -> tuple[float, float]:
        """The point at arc length ``s`` (taken modulo the perimeter)."""
        s %= self.perimeter
        k = 7
        while k > 0 and s < self.starts[k]:
            k -= 1
        u = min(s - self.starts[k], self.lengths[k])
        p, r = self.prison, self.r
        if k == 0:
            return (p.x0 + u, p.y0 - r)
        if k == 2:
            return (p.x1 + r, p.y0 + u)
        if k == 4:
            return (p.x1 - u, p.y1 + r)
        if k == 6:
            return (p.x0 - r, p.y1 - u)
        cx, cy, a0 = ((p.x1, p.y0, -HALF_PI), (p.x1, p.y1, 0.0), (p.x0, p.y1, HALF_PI), (p.x0, p.y0, math.pi))[k // 2]
        a = a0 + u / r
        return (cx + r * math.cos(a), cy + r * math.sin(a))

    def param(self, x: float, y: float) -> float:
        """Arc length of the point of the curve nearest to (x, y) (along the prison's outward normal)."""
        p, r = self.prison, self.r
        S = self.starts
        left, right, below, above = x < p.x0, x > p.x1, y < p.y0, y > p.y1
        if right and below:
            return S[1] + r * (math.atan2(y - p.y0, x - p.x1) + HALF_PI)
        if right and above:
            return S[3] + r * math.atan2(y - p.y1, x - p.x1)
        if left and above:
            return S[5] + r * (math.atan2(y - p.y1, x - p.x0) - HALF_PI)
        if left and below:
            a = math.atan2(y - p.y0, x - p.x0)
            return S[7] + r * ((a + 2 * math.pi if a < 0 else a) - math.pi)
        if not (left or right or below or above):  # inside: the nearest side's outward normal
            gaps = (y - p.y0, p.x1 - x, p.y1 - y, x - p.x0)
            side = gaps.index(min(gaps))
            below, right, above, left = (side == 0, side == 1, side == 2, side == 3)
        if below:
            return S[0] + (x - p.x0)
        if right:
            return S[2] + (y - p.y0)
        if above:
            return S[4] + (p.x1 - x)
        return S[6] + (p.y1 - y)

    def inside(self, arena: Arena) -> list[tuple[float, float]]:
        """The stretches [s0, s1] of the curve that lie in the arena, in order of s, merged across pieces."""
        spans = [iv for k in range(8) if (iv := self._piece_inside(k, arena)) is not None]
        merged: list[list[float]] = []
        for a, b in spans:
            if merged and a - merged[-1][1] <= 1e-7:
                merged[-1][1] = b
            else:
                merged.append([a, b])
        if len(merged) > 1 and merged[0][0] <= 1e-7 and self.perimeter - merged[-1][1] <= 1e-7:
            last = merged.pop()  # the stretch through s = 0
            merged[0] = [last[0] - self.perimeter, merged[0][1]]
        return [(a, b) for a, b in merged]

    def _piece_inside(self, k: int, arena: Arena) -> tuple[float, float] | None:
        p, r, X, Y = self.prison, self.r, arena.half_x, arena.half_y
        L, s0 = self.lengths[k], self.starts[k]
        if k % 2 == 0:
            # a side: one coordinate fixed, the other linear in u (direction +1 or -1)
            fixed, lim, start, sign, lim_var = (
                (p.y0 - r, Y, p.x0, 1.0, X),
                (p.x1 + r, X, p.y0, 1.0, Y),
                (p.y1 + r, Y, p.x1, -1.0, X),
                (p.x0 - r, X, p.y1, -1.0, Y),
            )[k // 2]
            if abs(fixed) > lim + _EPS:
                return None
            lo, hi = sorted(((-lim_var - start) * sign, (lim_var - start) * sign))
            lo, hi = max(lo, 0.0), min(hi, L)
        else:
            # a quarter circle: angle t in [0, pi/2] from the piece's start; x and y are each the corner
            # plus +-r sin t or +-r cos t, monotone in t, so each wall bound is one interval of t
            j = k // 2
            cx, cy = ((p.x1, p.y0), (p.x1, p.y1), (p.x0, p.y1), (p.x0, p.y0))[j]
            fx, fy = _ARC_XY[j]
            lo, hi = 0.0, HALF_PI
            for (fn, sign), c, lim in ((fx, cx, X), (fy, cy, Y)):
                a, b = (-lim - c) / r, (lim - c) / r  # bound on sign * f(t)
                a, b = (a, b) if sign > 0 else (-b, -a)  # bound on f(t)
                t0, t1 = _monotone_interval(fn, a, b)
                lo, hi = max(lo, t0), min(hi, t1)
            lo, hi = lo * r, hi * r
        if hi - lo < -_EPS or hi < 0.0 or lo > L:
            return None
        return (s0 + lo, s0 + max(hi, lo))


#: per corner piece: x and y as (function of t, sign) of cos(a0 + t) and sin(a0 + t), a0 = -90, 0, 90, 180 deg
_ARC_XY = (
    (("sin", 1.0), ("cos", -1.0)),
    (("cos", 1.0), ("sin", 1.0)),
    (("sin", -1.0), ("cos", 1.0)),
    (("cos", -1.0), ("sin", -1.0)),
)


def _monotone_interval(fn: str, a: float, b: float) -> tuple[float, float]:
    """{t in [0, pi/2] : a <= fn(t) <= b} for fn = sin (rising) or cos (falling); empty as (1, 0)."""
    if b < 0.0 or a > 1.0 or a > b:
        return (1.0, 0.0)
    a, b = max(a, 0.0), min(b, 1.0)
    if fn == "sin":
        return (math.asin(a), math.asin(b))
    return (math.acos(b), math.acos(a))


@dataclass
class Net:
    """The net at one radius: the chasers' stations, in order along the curve."""

    curve: LevelSet
    stations: np.ndarray  # (n, 2) where the chasers stand, in order along the net
    cut: float  # arc length where the order starts (a point outside the arena, if any)
    closed: bool  # the whole ring lies in the arena (no wall closes it)
    _last: tuple = (None, None)  # (chaser positions, their stations): the latest assignment

    def station(self, chasers: tuple[tuple[float, float], ...], i: int) -> tuple[float, float]:
        """Where chaser ``i`` of ``chasers`` (positions) stands; remembered for the same positions, which
        every chaser of a team sees alike."""
        key, stations = self._last
        if key != chasers:
            stations = self.assign(np.array(chasers))
            self._last = (chasers, stations)
        x, y = self.stations[stations[i]]
        return (float(x), float(y))

    def order(self, chasers: np.ndarray) -> np.ndarray:
        """Chaser indices in the order of their nearest points along the net."""
        P, cut = self.curve.perimeter, self.cut
        keys = [(self.curve.param(float(x), float(y)) - cut) % P for x, y in chasers]
        return np.argsort(np.array(keys), kind="stable")

    def assign(self, chasers: np.ndarray) -> np.ndarray:
        """(n,) the station of each chaser: stations are given in order along the net, so that no two
        chasers cross on the way; on a closed ring the rotation that moves them least is taken."""
        n = len(chasers)
        order = self.order(chasers)
        out = np.empty(n, dtype=int)
        if not self.closed:
            out[order] = np.arange(n)
            return out
        ordered = chasers[order]
        shifts = (np.arange(n)[None, :] + np.arange(n)[:, None]) % n  # (shift, rank)
        cost = ((ordered[None, :, :] - self.stations[shifts]) ** 2).sum(axis=(1, 2))
        out[order] = shifts[int(cost.argmin())]
        return out


@lru_cache(maxsize=64)
def make_net(prison: Area, arena: Arena, r: float, n: int) -> Net | None:
    """The net of ``n`` stations at distance ``r`` from the prison, or None if no part of it is in the arena.

    Stretches cut by walls get stations in proportion to their lengths, with their end stations on the
    walls (no gap for a target to slip through); a closed ring gets evenly spaced stations.

    A pure function of its arguments, remembered: chasers that agree on the radius (they share it) compute
    the net once per tick between them when they run in one process."""
    curve = LevelSet(prison, max(r, 1e-3))
    spans = curve.inside(arena)
    if not spans or n <= 0:
        return None
    P = curve.perimeter
    if len(spans) == 1 and spans[0][1] - spans[0][0] >= P - 1e-7:
        at = [spans[0][0] + i * P / n for i in range(n)]
        return Net(curve, _points(curve, arena, at), spans[0][0], True)
    cut = spans[-1][1] + 0.5 * ((spans[0][0] + P) - spans[-1][1])  # middle of a gap
    spans.sort(key=lambda ab: (ab[0] - cut) % P)
    counts = _apportion([b - a for a, b in spans], n)
    at: list[float] = []
    for (a, b), k in zip(spans, counts):
        if k == 1:
            at.append(0.5 * (a + b))
        elif k > 1:
            at.extend(a + i * (b - a) / (k - 1) for i in range(k))
    return Net(curve, _points(curve, arena, at), cut % P, False)


def _points(curve: LevelSet, arena: Arena, at: list[float]) -> np.ndarray:
    out = np.array([arena.clamp(*curve.point(s)) for s in at])
    out.setflags(write=False)  # shared by every caller of the remembered net
    return out


def _apportion(lengths: list[float], n: int) -> list[int]:
    """n stations shared among stretches in proportion to their lengths (largest remainders), every
    stretch getting at least one while there are enough."""
    k = len(lengths)
    base = [1 if n >= k else 0] * k
    rest = n - sum(base)
    total = sum(lengths)
    share = [(length / total * rest) if total > 0 else rest / k for length in lengths]
    counts = [b + int(math.floor(s)) for b, s in zip(base, share)]
    left = n - sum(counts)
    for i in sorted(range(k), key=lambda i: -(share[i] - math.floor(share[i])))[:left]:
        counts[i] += 1
    return counts
