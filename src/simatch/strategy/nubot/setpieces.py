"""Positions for every game command (the set-piece planner), keeping the MSL distances.

For a restart of ours: a taker behind the ball, lined up with its pass; a receiver at a free spot within
passing range and at least 2 m (``mate_distance``) from the ball; the others in their defensive shape, also
2 m away. The taker passes first: no goal may come straight from a set piece. At a kick-off everybody stays
in our half (the taker too, until it touches the ball), so the pass cannot go backwards: the taker plays
the ball gently sideways, to stop in front of the receiver, nearer to it than to any opponent.

For a restart of theirs: nobody within 3 m (``opponent_distance``) of the ball; a wall between the ball
and our goal, and markers on the opponents nearest to the ball. At a dropped ball everybody keeps 1 m
(``dropball_distance``), our active robot on the goal side of the ball.

A slot is (role, x, y, face_x, face_y): where to stand and the point to face.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ...compiled import Float, Matrix, bind, kernel
from ..roles import ROLES
from . import positions
from .gameflow import MODES
from .geometry import clamp, unit
from .params import NubotParams
from .positions import Areas, as_called, score_spots

SLOT_GAP = 1.3  # robots' slots at least this far apart [m]
TAKER_GAP = 0.6  # taker's centre behind the ball's centre while waiting [m]
KICKOFF_LEAD = (0.3, 1.95)  # where the kick-off pass stops (team frame, y to the receiver's side; x > 0
#                               keeps the taker, behind the ball on the kick line, clear of the half-way line) [m]
#: headings round the ball tried by `_settle` when the pushes undo each other (every 7.5 degrees)
_ROUND = tuple((math.cos(k * math.pi / 24), math.sin(k * math.pi / 24)) for k in range(48))


@lru_cache(maxsize=16)
def _round(r: float) -> tuple[np.ndarray, np.ndarray]:
    """The offsets (x, y) from the ball of the points `_settle` tries for distance ``r``: rings at r + 0.05
    ... r + 3 on each heading of _ROUND, in the order it scans them."""
    offsets = [(rr * c, rr * s) for c, s in _ROUND for rr in (r + 0.05, r + 0.6, r + 1.2, r + 2.0, r + 3.0)]
    ox, oy = np.array(offsets).T.copy()
    ox.flags.writeable = oy.flags.writeable = False
    return ox, oy


def push_from(x: float, y: float, bx: float, by: float, r: float) -> tuple[float, float]:
    """The point moved radially away from the ball to at least ``r``."""
    dx, dy = x - bx, y - by
    d = math.hypot(dx, dy)
    if d >= r:
        return x, y
    if d < 1e-6:
        dx, dy, d = -1.0, 0.0, 1.0
    return bx + dx / d * r, by + dy / d * r


def restart_spot(
    areas: Areas,
    bx: float,
    by: float,
    opps: list,
    spots: tuple[np.ndarray, np.ndarray],
    p: NubotParams,
    near: tuple[float, float] | None,
) -> tuple[float, float]:
    """The receiver's spot for a restart of ours: free, in range, 2 m+ from the ball, inside the lines."""
    cx, cy = spots
    ox = np.array([o[0] for o in opps])
    oy = np.array([o[1] for o in opps])
    dmin = p.mate_distance + 0.5
    score = score_spots(cx, cy, bx, by, ox, oy, areas.L2, dmin, 6.5, near)
    dball = np.hypot(cx - bx, cy - by)
    score[dball < p.mate_distance + 0.2] -= 100.0
    k = int(np.argmax(score))
    return float(cx[k]), float(cy[k])


def kickoff_side(opps: list) -> float:
    """+1 or -1: the side (y) of the kick-off pass, away from the opponents' weight."""
    s = sum(o[1] for o in opps if abs(o[0]) < 6.0)
    return -1.0 if s > 0.0 else 1.0


def formation(
    kind: int,
    areas: Areas,
    bx: float,
    by: float,
    opps: list,
    p: NubotParams,
    spots: tuple[np.ndarray, np.ndarray],
    receiver_near: tuple[float, float] | None,
) -> list[tuple]:
    """The four field-robot slots for set piece ``kind`` with the ball at (bx, by)."""
    M = MODES
    slots: list[tuple] = []
    if kind == M.OUR_KICKOFF:
        side = kickoff_side(opps)
        lx, ly = KICKOFF_LEAD[0], side * KICKOFF_LEAD[1]
        ux, uy = unit(lx - bx, ly - by)
        slots.append((ROLES.ACTIVE, bx - TAKER_GAP * ux, by - TAKER_GAP * uy, lx, ly))
        rx, ry = push_from(-0.45, side * 2.35, bx, by, p.mate_distance + 0.15)
        slots.append((ROLES.ASSISTANT, rx, ry, bx, by))
        slots.append((ROLES.PASSIVE, -4.5, -side * 1.0, bx, by))
        slots.append((ROLES.MIDFIELD, -2.2, -side * 2.6, bx, by))
    elif kind == M.OPP_KICKOFF:
        # a block in front of the ball and two robots on the half-way line, near the receivers
        r = p.opponent_distance + 0.1
        slots.append((ROLES.ACTIVE, -r, 0.0, bx, by))
        slots.append((ROLES.MIDFIELD, -0.6, r + 0.3, bx, by))
        slots.append((ROLES.ASSISTANT, -0.6, -r - 0.3, bx, by))
        slots.append((ROLES.PASSIVE, -6.0, 0.0, bx, by))
    elif kind == M.OUR_PENALTY:
        gx = areas.L2
        ux, uy = unit(gx - bx, -by)
        slots.append((ROLES.ACTIVE, bx - TAKER_GAP * ux, by - TAKER_GAP * uy, gx, 0.0))
        x = min(bx - p.opponent_distance - 0.1, areas.opp_pa[0] - 0.3)
        slots.append((ROLES.ASSISTANT, x, 2.0, bx, by))
        slots.append((ROLES.MIDFIELD, x, -2.0, bx, by))
        slots.append((ROLES.PASSIVE, -2.0, 0.0, bx, by))
    elif kind == M.OPP_PENALTY:
        x = max(bx + p.opponent_distance + 0.1, areas.own_pa[1] + 0.3)
        slots.append((ROLES.ACTIVE, x, 1.3, bx, by))
        slots.append((ROLES.PASSIVE, x, -1.3, bx, by))
        slots.append((ROLES.MIDFIELD, x, 4.0, bx, by))
        slots.append((ROLES.ASSISTANT, x, -4.0, bx, by))
    elif kind == M.DROPBALL:
        slots = _dropball(areas, bx, by, p)
    elif kind % 2 == 1:  # our throw-in, goal kick, corner, free kick
        rx, ry = restart_spot(areas, bx, by, opps, spots, p, receiver_near)
        ux, uy = unit(rx - bx, ry - by)
        slots.append((ROLES.ACTIVE, bx - TAKER_GAP * ux, by - TAKER_GAP * uy, rx, ry))
        slots.append((ROLES.ASSISTANT, rx, ry, bx, by))
        px, py = as_called(positions.passive_point)(areas.pitch, bx, by, bx > 0.0)
        slots.append((ROLES.PASSIVE, px, py, bx, by))
        mx, my = clamp(bx - 3.5, -areas.L2 + 4.0, areas.L2 - 4.5), (by - 3.0 if by > 0 else by + 3.0)
        slots.append((ROLES.MIDFIELD, mx, my, bx, by))
    else:  # their throw-in, goal kick, corner, free kick
        slots = _their_restart(areas, bx, by, opps, p)
    return _made_legal(kind, slots, areas, bx, by, p)


def _dropball(areas: Areas, bx: float, by: float, p: NubotParams) -> list[tuple]:
    """A dropped ball: our active robot on the goal side of the ball, the others at their defensive points,
    everyone ``dropball_distance`` (and the others 0.6 m more) away."""
    slots: list[tuple] = []
    d = p.dropball_distance
    gx, gy = as_called(positions.guard_point)(areas.pitch, bx, by, 1.0, 0.0, d)
    if math.hypot(gx - bx, gy - by) < d - 1e-6 or math.hypot(gx - bx, gy - by) > d + 0.5:
        ux, uy = unit(-areas.L2 - bx, -by)
        gx, gy = bx + d * ux, by + d * uy
    slots.append((ROLES.ACTIVE, gx, gy, bx, by))
    px, py = as_called(positions.passive_point)(areas.pitch, bx, by, False)
    slots.append((ROLES.PASSIVE, *push_from(px, py, bx, by, d + 0.6), bx, by))
    ax, ay = as_called(positions.outlet_point)(areas.pitch, bx, by)
    slots.append((ROLES.ASSISTANT, *push_from(ax, ay, bx, by, d + 0.6), bx, by))
    mx, my = clamp(bx - 3.0, -areas.L2 + 4.0, areas.L2 - 4.0), by - 2.5 if by > 0 else by + 2.5
    slots.append((ROLES.MIDFIELD, *push_from(mx, my, bx, by, d + 0.6), bx, by))
    return slots


def _their_restart(areas: Areas, bx: float, by: float, opps: list, p: NubotParams) -> list[tuple]:
    """Their throw-in, goal kick, corner or free kick: a wall between the ball and our goal, the passive
    defender, and markers on the opponents most likely to receive (or zones, without them)."""
    slots: list[tuple] = []
    r = p.opponent_distance + 0.1
    wx, wy = as_called(positions.guard_point)(areas.pitch, bx, by, 1.0, 0.0, r)
    slots.append((ROLES.ACTIVE, wx, wy, bx, by))
    px, py = as_called(positions.passive_point)(areas.pitch, bx, by, False)
    slots.append((ROLES.PASSIVE, px, py, bx, by))
    # markers on the opponents most likely to receive: away from the ball, nearest to our goal
    free = [o for o in opps if math.hypot(o[0] - bx, o[1] - by) > r and o[0] < areas.L2 - 1.0]
    free.sort(key=lambda o: math.hypot(o[0] + areas.L2, o[1]))
    zones = [
        (clamp(bx - 4.5, -areas.L2 + 4.0, areas.L2 - 3.0), -2.5 if by > 0 else 2.5),
        as_called(positions.outlet_point)(areas.pitch, bx, by),
    ]
    for k, role in enumerate((ROLES.MIDFIELD, ROLES.ASSISTANT)):
        if k < len(free):
            o = free[k]
            ux, uy = unit(-areas.L2 - o[0], -o[1])
            vx, vy = unit(bx - o[0], by - o[1])
            wx, wy = unit(ux + vx, uy + vy)
            ox, oy = o[0] + 0.9 * wx, o[1] + 0.9 * wy
        else:
            ox, oy = zones[k]
        slots.append((role, ox, oy, bx, by))
    return slots


def _made_legal(kind: int, slots: list[tuple], areas: Areas, bx: float, by: float, p: NubotParams) -> list[tuple]:
    """The slots made to respect the distances and areas of set piece ``kind`` and spread apart (a slot
    spread moved, or that clashes with one before it, made legal again keeping clear of those)."""
    slots = [_legal(kind, s, areas, bx, by, p) for s in slots]
    out: list[tuple] = []
    for s, moved in zip(spread(slots, bx, by), slots):
        taken = [(o[1], o[2]) for o in out]
        if s is not moved or any(math.hypot(s[1] - x, s[2] - y) < SLOT_GAP - 1e-6 for x, y in taken):
            s = _legal(kind, s, areas, bx, by, p, taken=taken)  # spread moved it, or it clashes
        out.append(s)
    return out


def spread(slots: list[tuple], bx: float, by: float, gap: float = SLOT_GAP) -> list[tuple]:
    """Slots (listed by priority) moved apart so that no two robots are sent to the same place
    (`spread_point`); a slot not moved is the same object (callers can tell)."""
    out: list[tuple] = []
    placed = np.empty((len(slots), 2))
    for i, slot in enumerate(slots):
        role, x, y, fx, fy = slot
        sx, sy = _spread_point(placed[:i], x, y, bx, by, gap)
        out.append(slot if (sx == x and sy == y) else (role, sx, sy, fx, fy))
        placed[i, 0], placed[i, 1] = sx, sy
    return out


@kernel(placed=Matrix, x=Float, y=Float, bx=Float, by=Float, gap=Float)
def spread_point(placed, x, y, bx, by, gap):
    """(x, y) moved away from the points ``placed`` ((k, 2+) rows, x and y first) it is nearer than ``gap``
    to: it slides sideways, across the direction of the ball at (bx, by), to ``gap`` from the first point it
    is too close to, at most three times."""
    for _ in range(3):
        clash = -1
        for e in range(placed.shape[0]):
            if math.hypot(x - placed[e, 0], y - placed[e, 1]) < gap:
                clash = e
                break
        if clash < 0:
            break
        cx, cy = placed[clash, 0], placed[clash, 1]
        dx, dy = x - bx, y - by
        d = math.hypot(dx, dy)
        ux, uy = (1.0, 0.0) if d < 1e-12 else (dx / d, dy / d)
        nx, ny = -uy, ux  # across the line to the ball
        if (x - cx) * nx + (y - cy) * ny < 0.0:
            nx, ny = -nx, -ny
        if abs(y + ny * gap) > 6.0:  # do not slide off the field
            nx, ny = -nx, -ny
        x, y = cx + nx * gap, cy + ny * gap
    return x, y


_spread_point = bind(spread_point)


def _legal(
    kind: int, slot: tuple, areas: Areas, bx: float, by: float, p: NubotParams, taken: list[tuple[float, float]] = ()
) -> tuple:
    """Make a slot respect the distances and areas of set piece ``kind`` (and keep ``SLOT_GAP`` from the
    points already ``taken``)."""
    role, x, y, fx, fy = slot
    M = MODES
    taker = role == ROLES.ACTIVE and kind % 2 == 1 and kind != M.DROPBALL
    if kind == M.DROPBALL:
        r = p.dropball_distance
    elif kind % 2 == 1:
        r = 0.0 if taker else p.mate_distance
    else:
        r = p.opponent_distance
    x, y = areas.inside_field(x, y, -0.6 if taker else 0.5)
    if kind in (M.OUR_KICKOFF, M.OPP_KICKOFF):
        x = min(x, -0.35)
    x, y = _settle(kind, areas, x, y, bx, by, r, taker, taken)
    return (role, x, y, fx, fy)


def _settle(
    kind: int,
    areas: Areas,
    x: float,
    y: float,
    bx: float,
    by: float,
    r: float,
    taker: bool,
    taken: list[tuple[float, float]] = (),
) -> tuple[float, float]:
    """The point moved out of the areas, to ``r`` from the ball and (at a kick-off) into our half; where
    those pushes undo each other (near a box), or the point is taken by another slot, the nearest point
    round the ball that satisfies all of them."""
    kickoff = kind in (MODES.OUR_KICKOFF, MODES.OPP_KICKOFF)

    def legal(px: float, py: float) -> bool:
        if kickoff and px > -0.35 + 1e-6:
            return False
        if r > 0.0 and math.hypot(px - bx, py - by) < r - 1e-6:
            return False
        for tx, ty in taken:
            if math.hypot(px - tx, py - ty) < SLOT_GAP - 1e-6:
                return False
        return areas.keep_out(px, py, True, not taker) == (px, py)

    for _ in range(3):
        x, y = areas.keep_out(x, y, True, not taker)
        if r > 0.0:
            x, y = push_from(x, y, bx, by, r)
        if kickoff:
            x = min(x, -0.35)
        if legal(x, y):
            return x, y
    # the points round the ball, nearest to (x, y) first (ties in the order of the scan), the first legal one
    # (the same float operations as a scan in Python, done for all candidates at once)
    ox, oy = _round(r)
    px, py = bx + ox, by + oy
    on = (np.abs(px) <= areas.L2 + 0.5) & (np.abs(py) <= areas.W2 - 0.3)
    px, py = px[on], py[on]
    d = list(map(math.hypot, (px - x).tolist(), (py - y).tolist()))
    pxs, pys = px.tolist(), py.tolist()
    for k in sorted(range(len(d)), key=d.__getitem__):
        if d[k] < math.inf and legal(pxs[k], pys[k]):
            return pxs[k], pys[k]
    return x, y
