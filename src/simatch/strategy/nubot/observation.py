"""What one robot knows at one control tick, distilled from its WorldModel into plain floats.

Everything comes from the robot's own topics: its perception (ball, obstacles, its team), its team's
fused StrategyInfo (teammates' roles and passes) and the game command. Opponents are the obstacles that
are not one of the team's robots.
"""

from __future__ import annotations

import math
import struct
from itertools import chain

import numpy as np

from ... import msgs
from ...compiled import kernel
from ..worldmodel import WorldModel

#: an obstacle this close to a teammate is that teammate [m]
_SAME_ROBOT = 0.1
#: a team-mate's row of its team's table written in place (eight float64, native), through a memoryview of
#: the table (taken once per table)
_pack_row = struct.Struct("8d").pack_into


class Mate:
    """One robot of my team (me included), team frame."""

    __slots__ = (
        "id",
        "x",
        "y",
        "yaw",
        "vx",
        "vy",
        "w",
        "holding",
        "valid",
        "stuck",
        "role",
        "action",
        "pass_info",
        "is_goalie",
        "attacking",
        "role_time",
        "row",
    )

    def __init__(
        self,
        id,
        x,
        y,
        yaw,
        vx,
        vy,
        w,
        holding,
        valid,
        stuck,
        role,
        action,
        pass_info,
        is_goalie,
        attacking,
        role_time,
        row,
    ):
        # (the slots' values in slot order, as `TeamView.get` finds them in the robot's RobotInfo and its
        # StrategyInfo; ``role``: as the robot announced it last, -1 if unknown; ``attacking``: whether its
        # team picture said "we attack" last tick (1/0), -1 if unknown; ``role_time``: how long it has had its
        # announced role [s]; ``row``: its row in its TeamView's table)
        self.id = id
        self.x, self.y, self.yaw = x, y, yaw
        self.vx, self.vy, self.w = vx, vy, w
        self.holding, self.valid, self.stuck = holding, valid, stuck
        self.role, self.action, self.pass_info = role, action, pass_info
        self.is_goalie, self.attacking, self.role_time, self.row = is_goalie, attacking, role_time, row

    def key(self) -> tuple:
        return (self.id, self.x, self.y, self.yaw, self.vx, self.vy, self.holding, self.valid, self.role)


#: `Mate` of its slots' values in slot order: the C helper's maker where it is built (one call, no Python
#: ``__init__`` frame), else the class itself
_make_mate = msgs.slot_maker(Mate, Mate.__slots__)


class TeamView:
    """The part of an observation that every robot of the team shares (its team's RobotInfo list and
    StrategyInfo messages): built once per tick by the first robot of the team in this process, reused by
    the others when they hold the very same messages."""

    __slots__ = (
        "tick",
        "robots",
        "team_strategy",
        "mates",
        "by_id",
        "array",
        "holder",
        "opp_tick",
        "opp_array",
        "opps",
        "opp_table",
        "opp_bx",
        "opp_by",
        "opp_near",
    )

    def __init__(self):
        self.tick = -1
        self.robots = None
        self.team_strategy = None
        self.mates: list[Mate] = []
        self.by_id: dict[int, Mate] = {}
        # (K, 8): x, y, vx, vy, id, yaw, announced role, role time of every team-mate, for kernels (they
        # read the columns they need)
        self.array = np.zeros((0, 8))
        self.holder: Mate | None = None  # the first team-mate holding the ball, if any
        # the opponents' array and rows an observation of tick ``opp_tick`` found last: a team-mate seeing
        # the very same opponents at that tick shares them (read only, as the team picture is shared)
        self.opp_tick = -1
        self.opp_array: np.ndarray | None = None
        self.opps: list | None = None
        # and the table and ball position it found them with: the team-mate nearest to the ball, its distance
        # and the nearest opponent's distance it found (`_opponents`), the same for a team-mate seeing the ball
        # at the same place (and the same opponents)
        self.opp_table: np.ndarray | None = None
        self.opp_bx = self.opp_by = math.nan
        self.opp_near: tuple = (-1, math.inf, math.inf)

    def get(self, world: WorldModel) -> tuple[list[Mate], dict[int, Mate], np.ndarray]:
        robots = world.vision.robots
        team = world.team_strategy
        if self.tick == world.tick and self.robots is robots and self.team_strategy is team:
            return self.mates, self.by_id, self.array
        gk = world.goalkeeper
        told = world.strategies.get
        # one pass over the team: the records, the kernels' numbers (each one's row of the table, in place), the
        # look-up by id and the first holder
        mates = []
        self.array = arr = np.empty((len(robots), 8))
        rows = memoryview(arr)
        by_id = {}
        holder = None
        row = 0
        append = mates.append
        for r in robots:
            rid = r.id
            s = told(rid)
            x = r.x  # (one by one: a tuple of five would be built and taken apart)
            y = r.y
            yaw = r.yaw
            vx = r.vx
            vy = r.vy
            holding = r.holding_ball
            if s is None:
                m = _make_mate(
                    rid, x, y, yaw, vx, vy, r.w, holding, r.valid, r.stuck, -1, -1, None, rid == gk, -1, 1e9, row
                )
                role, role_time = -1, 1e9
            else:
                user = s.user.tolist()
                if len(user) >= 2:
                    attacking, role_time = int(user[0]), user[1]
                else:
                    attacking, role_time = -1, 1e9
                role = s.role
                pass_cmd = s.pass_cmd
                m = _make_mate(
                    rid,
                    x,
                    y,
                    yaw,
                    vx,
                    vy,
                    r.w,
                    holding,
                    r.valid,
                    r.stuck,
                    role,
                    s.action,
                    pass_cmd if pass_cmd.is_valid else None,
                    rid == gk,
                    attacking,
                    role_time,
                    row,
                )
            _pack_row(rows, 64 * row, x, y, vx, vy, rid, yaw, role, role_time)  # (the table's row, in place)
            row += 1
            append(m)
            by_id[rid] = m
            if holder is None and holding:
                holder = m
        self.tick, self.robots, self.team_strategy = world.tick, robots, team
        self.mates, self.by_id, self.holder = mates, by_id, holder
        rows.release()
        return self.mates, self.by_id, self.array


class Observation:
    __slots__ = (
        "t",
        "tick",
        "me",
        "mates",
        "by_id",
        "mate_array",
        "bx",
        "by",
        "bz",
        "bvx",
        "bvy",
        "bvz",
        "ball_seen",
        "ball_age",
        "opps",
        "opp_array",
        "mode",
        "mtype",
        "coach",
        "goalie_id",
        "holder",
        "near_mate",
        "near_mate_d",
        "opp_ball_d",
    )

    def __init__(self, world: WorldModel, view: TeamView | None = None):
        made = observe(world, view if view is not None else TeamView())
        for name in Observation.__slots__:
            setattr(self, name, getattr(made, name))

    @property
    def ball_speed(self) -> float:
        return math.hypot(self.bvx, self.bvy)

    def field_mates(self) -> list[Mate]:
        """Valid team-mates that are not the goalkeeper, me included."""
        return [m for m in self.mates if m.valid and not m.is_goalie]


#: `Observation` of its slots' values, in slot order (the C helper's one call)
_make_observation = msgs.slot_maker(Observation, Observation.__slots__)


def observe(world: WorldModel, view: TeamView) -> Observation:
    """``Observation(world, view)``: the same record, its numbers found in locals and its slots filled by one
    call (no class call with a Python ``__init__``, no attribute writes one by one: a robot observes at
    almost every tick)."""
    v = world.vision
    tick = world.tick
    robots = v.robots
    # (`TeamView.get`'s test of a view still valid, here: a team-mate's observation makes no call for it)
    if view.tick == tick and view.robots is robots and view.team_strategy is world.team_strategy:
        mates, by_id, table = view.mates, view.by_id, view.array
    else:
        mates, by_id, table = view.get(world)
    me = by_id.get(world.id)
    if me is None:
        raise LookupError(f"robot {world.id} is missing from its own perception")
    # (the WorldModel's own record, found here: `WorldModel.me` then needs no search, e.g. for what the robot
    # tells its team)
    world._me = robots[me.row]
    b = v.ball
    if b.pos_known:
        bx = b.x  # (one by one: a tuple of six would be built and taken apart)
        by = b.y
        bz = b.z
        bvx = b.vx
        bvy = b.vy
        bvz = b.vz
        seen = True
        age = 0.0
    else:
        b = world.ball
        seen = False
        if b is None:
            bx = by = bvx = bvy = bvz = 0.0
            bz = 0.11
            age = math.inf
        else:
            bx, by, bz, bvx, bvy, bvz = b.x, b.y, b.z, b.vx, b.vy, b.vz
            age = b.age
    arr, rows, near, near_d, opp_d = _opponents_seen(v.obstacles, table, bx, by, view, tick)
    c = world.coach
    if c is None:
        mode = mtype = 0
    else:
        mode, mtype = c.match_mode, c.match_type
    # (in Observation.__slots__' order)
    return _make_observation(
        world.time,
        tick,
        me,
        mates,
        by_id,
        table,
        bx,
        by,
        bz,
        bvx,
        bvy,
        bvz,
        seen,
        age,
        rows,
        arr,
        mode,
        mtype,
        c,
        world.goalkeeper,
        view.holder,  # the first team-mate holding the ball (None: none does)
        near,
        near_d,
        opp_d,
    )


def _opponents_seen(o, table: np.ndarray, bx: float, by: float, view: TeamView, tick: int) -> tuple:
    """The opponents among the obstacles ``o``: their array and rows, the team-mate nearest to the ball, its
    distance, the nearest opponent's distance (`_opponents`). Shared with a team-mate's observation of the
    same tick when the rows are the same bit for bit (`_same_opponents`), found afresh otherwise."""
    if view.opp_tick == tick:
        # a team-mate's observation of this tick found its opponents: the same rows (bit for bit) are shared
        # (one kernel call that compares instead of filling, no array or rows made)
        arr = view.opp_array
        if view.opp_table is table and bx == view.opp_bx and by == view.opp_by:
            # the ball where that team-mate saw it (the same numbers; a NaN never is): the team-mate nearest to
            # it and the nearest opponent (when the rows are the same) are the ones it found
            k = _same_rows(o.x, o.y, o.vx, o.vy, table, arr)
            near, near_d, opp_d = view.opp_near
        else:
            k, near, near_d, opp_d = _same_opponents(o.x, o.y, o.vx, o.vy, table, arr, bx, by)
        if k >= 0:
            return arr, view.opps, near, near_d, opp_d
    return _own_opponents(o, table, bx, by, view, tick)


def _own_opponents(o, table: np.ndarray, bx: float, by: float, view: TeamView, tick: int) -> tuple:
    """The opponents among the obstacles ``o`` (of a robot whose team's table is ``table``, the ball at ``bx``,
    ``by``), found afresh and kept in ``view`` for team-mates: their array and rows, the team-mate nearest to
    the ball, its distance, the nearest opponent's distance (`_opponents`)."""
    ox = o.x
    # (the kernel fills an array made here, room for every obstacle, and says how many rows it wrote)
    buf = np.empty((len(ox), 4))
    k, near, near_d, opp_d = _opponents(ox, o.y, o.vx, o.vy, table, buf, bx, by)
    arr = buf[:k]
    rows = arr.tolist()
    view.opp_tick, view.opp_array, view.opps = tick, arr, rows
    view.opp_table, view.opp_bx, view.opp_by, view.opp_near = table, bx, by, (near, near_d, opp_d)
    return arr, rows, near, near_d, opp_d


def _array(rows: list[tuple], width: int) -> np.ndarray:
    """(len(rows), width) float array of equal-length tuples of numbers: the values of
    ``np.array(rows, dtype=float)``. (Shared between the robots of a
    team in one process: read it, never write it.)"""
    return np.fromiter(chain.from_iterable(rows), float, width * len(rows)).reshape(-1, width)


# _GIL_NOTE: the kernels a robot calls from Python at every tick keep the GIL (no ``nogil``, as every kernel of
# simatch, docs/performance.md's rules): they run for about a microsecond, in single-threaded runs.
@kernel  # (called from Python: holding the GIL, see _GIL_NOTE)
def _opponents(ox, oy, ovx, ovy, mates, out, bx, by):
    """Writes x, y, vx, vy (float64) of the obstacles (float32 arrays of an ObstaclesInfo) that are not
    team-mates (``mates``, the TeamView's array: x, y in its first columns) into the first rows of ``out``
    (at least as many rows as obstacles). With exact perception a team-mate's obstacle is exactly where
    the team list puts it; otherwise (noise) anything within _SAME_ROBOT of one.

    Returns how many, with what the game flow and the team picture ask of the ball at (bx, by) every
    tick: the row of the team-mate nearest to it (the first of equals; -1 without team-mates) and its
    distance, and the distance of the nearest opponent (inf without opponents)."""
    noisy = _noisy(ox, oy, mates)
    r = 0
    opp_d = math.inf
    for k in range(ox.shape[0]):
        if _opponent(np.float64(ox[k]), np.float64(oy[k]), mates, noisy):
            out[r, 0] = ox[k]
            out[r, 1] = oy[k]
            out[r, 2] = ovx[k]
            out[r, 3] = ovy[k]
            d = math.hypot(out[r, 0] - bx, out[r, 1] - by)
            if d < opp_d:
                opp_d = d
            r += 1
    near, near_d = _nearest_mate(mates, bx, by)
    return r, near, near_d, opp_d


@kernel
def _noisy(ox, oy, mates):
    """Whether some team-mates are not exactly where the team list puts them among the obstacles (float32 x,
    y; ``mates``: x, y in the first columns): fewer obstacles are exactly at a team-mate than there are
    team-mates besides the robot itself (noisy perception). Then `_opponent` matches by distance."""
    n = ox.shape[0]
    k_mates = mates.shape[0]
    at_mates = 0
    for k in range(n):
        if _at_mate(np.float64(ox[k]), np.float64(oy[k]), mates):
            at_mates += 1
    return at_mates < k_mates - 1


@kernel
def _at_mate(x, y, mates):
    for j in range(mates.shape[0]):
        if mates[j, 0] == x and mates[j, 1] == y:
            return True
    return False


@kernel
def _opponent(x, y, mates, noisy):
    """Whether the obstacle at (x, y) is an opponent: not exactly at a team-mate, nor, when ``noisy``
    (`_noisy`), within _SAME_ROBOT of one (in both coordinates)."""
    if _at_mate(x, y, mates):
        return False
    if noisy:
        for j in range(mates.shape[0]):
            if not (abs(mates[j, 0] - x) >= _SAME_ROBOT or abs(mates[j, 1] - y) >= _SAME_ROBOT):
                return False
    return True


@kernel
def _nearest_mate(mates, bx, by):
    """The row of the team-mate nearest to (bx, by) (the first of equals; -1 without team-mates) and its
    distance."""
    near, near_d = -1, math.inf
    for j in range(mates.shape[0]):
        d = math.hypot(mates[j, 0] - bx, mates[j, 1] - by)
        if j == 0 or d < near_d:
            near, near_d = j, d
    return near, near_d


@kernel
def _same(a, b):
    """``a`` and ``b`` are the same float64 bit for bit (a NaN never is; -0.0 is not 0.0)."""
    return a == b and (a != 0.0 or math.copysign(1.0, a) == math.copysign(1.0, b))


@kernel  # (called from Python: holding the GIL, see _GIL_NOTE)
def _same_rows(ox, oy, ovx, ovy, mates, prev):
    """The number of rows of ``prev`` (a team-mate's opponents at the same tick) if the opponents among these
    obstacles (`_opponents`' rule) are exactly ``prev``'s rows (bit for bit, in order; nothing written), else
    -1."""
    noisy = _noisy(ox, oy, mates)
    m = prev.shape[0]
    r = 0
    for k in range(ox.shape[0]):
        x, y = np.float64(ox[k]), np.float64(oy[k])
        if _opponent(x, y, mates, noisy):
            if r >= m:
                return -1
            if not (
                _same(prev[r, 0], x)
                and _same(prev[r, 1], y)
                and _same(prev[r, 2], np.float64(ovx[k]))
                and _same(prev[r, 3], np.float64(ovy[k]))
            ):
                return -1
            r += 1
    return r if r == m else -1


@kernel  # (called from Python: holding the GIL, see _GIL_NOTE)
def _same_opponents(ox, oy, ovx, ovy, mates, prev, bx, by):
    """`_opponents` when the rows are expected to be ``prev`` (a team-mate's opponents at the same tick): the
    number of rows if the opponents among these obstacles are exactly ``prev``'s rows (`_same_rows`), else -1;
    then, as `_opponents`, the team-mate nearest to the ball at (bx, by), its distance and (when the rows are
    the same) the nearest opponent's distance (inf without opponents)."""
    r = _same_rows(ox, oy, ovx, ovy, mates, prev)
    opp_d = math.inf
    for j in range(r):
        d = math.hypot(prev[j, 0] - bx, prev[j, 1] - by)
        if d < opp_d:
            opp_d = d
    near, near_d = _nearest_mate(mates, bx, by)
    return r, near, near_d, opp_d
