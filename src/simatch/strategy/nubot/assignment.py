"""Giving the robots their places: which robot takes which role's point.

`assign` gives robots distinct slots, minimising the total distance (with hysteresis for the roles the
robots announced); `open_slots` makes open play's positional slots (the roles' points kept inside the
field and apart) and assigns them; `assist_spots` chooses the assistants' receiving spots. The team
picture (picture.py) calls them at every tick.
"""

from __future__ import annotations

import math

import numpy as np

from ...compiled import Array, Bool, Float, Matrix, Vector, kernel
from ..roles import ROLES
from .positions import PitchType, _score_spots, inside_field
from .setpieces import SLOT_GAP, spread_point

#: a robot that took its role less than MIN_ROLE_TIME ago keeps it unless another way saves NEW_ROLE_HOLD more
MIN_ROLE_TIME = 0.6
NEW_ROLE_HOLD = 3.0
#: the points of positional roles stay this far inside the lines [m]
SLOT_INSIDE = 0.5
#: the positional roles as the numbers the kernels take
ASSISTANT, PASSIVE, MIDFIELD = int(ROLES.ASSISTANT), int(ROLES.PASSIVE), int(ROLES.MIDFIELD)


def assign(
    robots: list, slots: list[tuple], hysteresis: float, around: tuple[float, float, float] | None = None
) -> dict[int, int]:
    """Robot id -> slot index, minimising the total distance, each robot's announced role earning
    ``hysteresis`` metres when it keeps it. Slots beyond the number of robots stay empty (they are listed
    by priority). ``around`` = (x, y, r): a circle robots must go round (a set piece's ball), whose detour
    counts too."""
    n = len(robots)
    if n == 0:
        return {}
    slots = slots[:n] if len(slots) >= n else slots
    if not slots:
        return {}
    # a robot that took its role only a moment ago holds on to it harder (roles last a while); the robots'
    # rows (x, y, announced role, hysteresis) and the slots' (x, y, role) in one array, for one kernel call
    flat = []
    for m in robots:
        flat += (m.x, m.y, m.role, hysteresis + (NEW_ROLE_HOLD if m.role_time < MIN_ROLE_TIME else 0.0))
    for sl in slots:
        flat += (sl[1], sl[2], sl[0])
    cx, cy, cr = around if around is not None else (0.0, 0.0, -1.0)
    best = _assign_flat(np.array(flat, dtype=float), n, len(slots), cx, cy, cr).tolist()
    return {robots[i].id: best[i] for i in range(min(n, len(slots)))}


@kernel
def _assign_flat(flat, n, m, cx, cy, cr):
    """`_assign` of the robots' (n, 4) and the slots' (m, 3) rows, given one after the other in ``flat``."""
    return _assign(flat[: 4 * n].reshape((n, 4)), flat[4 * n : 4 * n + 3 * m].reshape((m, 3)), cx, cy, cr)


@kernel
def _assign(robots, slots, cx, cy, cr):
    """The assignment of `assign`, compiled: every way of giving k = min(robots, slots) robots distinct
    slots, in lexicographic order (the first best one wins, so the result is the same everywhere)."""
    n, m = robots.shape[0], slots.shape[0]
    k = min(n, m)
    cost = np.empty((n, m))
    for i in range(n):
        for j in range(m):
            dx, dy = slots[j, 0] - robots[i, 0], slots[j, 1] - robots[i, 1]
            d = math.sqrt(dx * dx + dy * dy)
            if cr > 0.0:
                ll = dx * dx + dy * dy
                t = 0.0
                if ll > 1e-12:
                    t = min(max(((cx - robots[i, 0]) * dx + (cy - robots[i, 1]) * dy) / ll, 0.0), 1.0)
                gap = math.sqrt((robots[i, 0] + t * dx - cx) ** 2 + (robots[i, 1] + t * dy - cy) ** 2)
                d += 2.0 * max(0.0, cr - gap)
            if robots[i, 2] == slots[j, 2]:
                d -= robots[i, 3]  # the robot's hysteresis for keeping its role
            cost[i, j] = d
    best = np.zeros(k, dtype=np.int64)
    perm = np.zeros(k, dtype=np.int64)
    used = np.zeros(m, dtype=np.bool_)
    best_c = 1e18
    # depth-first over the slots in increasing order: permutations come in lexicographic order
    depth = 0
    perm[0] = -1
    acc = np.zeros(k + 1)
    while depth >= 0:
        j = perm[depth] + 1
        if perm[depth] >= 0:
            used[perm[depth]] = False
        while j < m and used[j]:
            j += 1
        if j >= m:
            perm[depth] = -1
            depth -= 1
            continue
        perm[depth] = j
        used[j] = True
        acc[depth + 1] = acc[depth] + cost[depth, j]
        if depth == k - 1:
            if acc[k] < best_c - 1e-9:
                best_c = acc[k]
                best[:] = perm
        else:
            depth += 1
            perm[depth] = -1
    return best


@kernel(
    cx=Vector,
    cy=Vector,
    bx=Float,
    by=Float,
    opps=Matrix,
    L2=Float,
    dmin=Float,
    dmax=Float,
    nx=Float,
    ny=Float,
    out=Matrix,
)
def assist_spots(cx, cy, bx, by, opps, L2, dmin, dmax, nx, ny, out):
    """Up to ``len(out)`` receiving spots for the assistants: the best scored of the candidates (cx, cy)
    (`score_spots` from ``dmin`` to ``dmax`` of the ball at (bx, by), near (nx, ny), the assistant's place,
    NaN: none), at least 3 m apart, taken among the twelve best (of equal scores, the first candidate).
    ``opps``: the opponents' (M, 4) rows. Writes the spots into the first rows of ``out`` and returns how
    many."""
    m = cx.shape[0]
    score = np.empty(m)
    _score_spots(
        cx,
        cy,
        bx,
        by,
        np.ascontiguousarray(opps[:, 0]),
        np.ascontiguousarray(opps[:, 1]),
        L2,
        dmin,
        dmax,
        nx,
        ny,
        score,
    )
    n = out.shape[0]
    k = 0
    taken = np.zeros(m, np.bool_)
    for _ in range(min(12, m)):
        # the best candidate not looked at yet (a NaN score only when nothing else is left)
        best = -1
        for j in range(m):
            if not taken[j] and (best < 0 or score[j] > score[best]):
                best = j
        taken[best] = True
        x, y = cx[best], cy[best]
        free = True
        for j in range(k):
            if not math.hypot(x - out[j, 0], y - out[j, 1]) > 3.0:
                free = False
                break
        if free:
            out[k, 0] = x
            out[k, 1] = y
            k += 1
            if k == n:
                break
    return k


@kernel(
    table=Matrix,
    rest=Array(np.int64, 1),
    attacking=Bool,
    assist=Matrix,
    passive_x=Float,
    passive_y=Float,
    midfield_x=Float,
    midfield_y=Float,
    bx=Float,
    by=Float,
    pitch=PitchType,
    hysteresis=Float,
    out=Matrix,
)
def open_slots(
    table, rest, attacking, assist, passive_x, passive_y, midfield_x, midfield_y, bx, by, pitch, hysteresis, out
):
    """Open play's positional roles of the robots at rows ``rest`` of the team view's table ((K, 8): x, y,
    vx, vy, id, yaw, announced role, role time), neither the active one nor the goalkeeper, the ball
    expected at (bx, by). The roles' points: the assistants' at ``assist`` ((k, 2): the receiving spots, or
    the outlet point when we defend), the passive defender's and the midfielder's as given; kept inside the
    field, spread apart, and given to the robots by `_assign`. Writes, for the i-th robot of ``rest`` that
    gets a slot, the slot's index, role, x and y into ``out[i]``; returns how many got one."""
    n = rest.shape[0]
    robots = np.empty((n, 4))
    for i in range(n):
        j = rest[i]
        robots[i, 0], robots[i, 1], robots[i, 2] = table[j, 0], table[j, 1], table[j, 6]
        robots[i, 3] = hysteresis + (NEW_ROLE_HOLD if table[j, 7] < MIN_ROLE_TIME else 0.0)
    order = np.empty(4, np.int64)
    if n >= 4:  # two assistants
        order[0], order[1], order[2], order[3] = ASSISTANT, ASSISTANT, PASSIVE, MIDFIELD
    elif attacking:
        order[0], order[1], order[2] = ASSISTANT, PASSIVE, MIDFIELD
    else:
        order[0], order[1], order[2] = PASSIVE, MIDFIELD, ASSISTANT
    m = min(4 if n >= 4 else 3, n)
    slots = np.empty((m, 3))  # x, y, role (the rows `_assign` takes), spread as they come
    used = 0
    for s in range(m):
        role = order[s]
        if role == ASSISTANT:
            a = min(used, assist.shape[0] - 1)
            x, y = assist[a, 0], assist[a, 1]
            used += 1
        elif role == PASSIVE:
            x, y = passive_x, passive_y
        else:
            x, y = midfield_x, midfield_y
        x, y = inside_field(pitch, x, y, SLOT_INSIDE)
        x, y = spread_point(slots[:s], x, y, bx, by, SLOT_GAP)
        slots[s, 0], slots[s, 1], slots[s, 2] = x, y, role
    best = _assign(robots, slots, 0.0, 0.0, -1.0)
    k = min(n, m)
    for i in range(k):
        j = best[i]
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = j, slots[j, 2], slots[j, 0], slots[j, 1]
    return k
