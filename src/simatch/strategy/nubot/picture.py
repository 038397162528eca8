"""The team picture: what every robot of the team concludes from the same facts at one control tick.

Who has the ball or will get it first (interception times of every robot, ours and theirs, on the ball's
predicted path), whether we attack or defend, and the roles: the active robot is the one that reaches the
ball first (the one holding it, or the receiver of a pass under way), the others take the remaining roles
(passive, assistant, midfield, or a set-piece slot) by the assignment that minimises the total distance to
the roles' points. Both choices have hysteresis against the roles the robots announced last tick, so roles
do not flicker when two robots are nearly equal.

Each robot computes the picture from its own WorldModel; the result depends only on its inputs, so robots
that see the same facts agree, and a team whose robots run in one process may share one computation per
tick (see `TeamMemo`) without any robot deciding on anything but its own observations.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ...compiled import Array, Bool, Float, Matrix, Vector, bind, kernel
from ...exactmath import hypot
from ..roles import ROLES
from . import positions
from .ballpath import BallPath, _team_intercepts
from .gameflow import PHASES, GameFlow
from .observation import Observation
from .observation import _array as _rows
from .params import NubotParams
from .positions import Areas, PitchType, _score_spots, as_called, inside_field
from .setpieces import SLOT_GAP, formation, kickoff_side, spread_point

BALL_RADIUS = 0.11
#: an opponent whose centre is this close to the ball controls it [m]
OPP_CONTROL = 0.45
#: a robot that has just become the active one stays so at least this long (unless another holds the ball) [s]
MIN_ACTIVE_TIME = 0.6
#: a robot that took its role less than MIN_ROLE_TIME ago keeps it unless another way saves NEW_ROLE_HOLD more
MIN_ROLE_TIME = 0.6
NEW_ROLE_HOLD = 3.0
#: the points of positional roles stay this far inside the lines [m]
SLOT_INSIDE = 0.5
#: we keep attacking (defending) until the opponents (we) reach the ball this much sooner [s]
ATTACK_HYSTERESIS = 0.4
#: set-piece slots change hands easily while robots run to them, and never once START is given [m]
SETUP_HYSTERESIS = 0.5
RESTART_HYSTERESIS = 50.0
#: a pass under way counts while the ball heads for the catch point within acos(PASS_HEADING), or within
#: acos(PASS_KEPT) once the receiver took the catching role
PASS_HEADING = 0.6
PASS_KEPT = 0.3


# the positional roles as numbers, for the compiled slots (and back: the Role members by value)
_ASSISTANT, _PASSIVE, _MIDFIELD = int(ROLES.ASSISTANT), int(ROLES.PASSIVE), int(ROLES.MIDFIELD)
_ASSISTANT_ROLE, _ACTIVE_ROLE, _GOALIE = ROLES.ASSISTANT, ROLES.ACTIVE, ROLES.GOALIE
_SETUP, _OUR_RESTART = PHASES.SETUP, PHASES.OUR_RESTART
_ROLE_OF = {int(r): r for r in (ROLES.ASSISTANT, ROLES.PASSIVE, ROLES.MIDFIELD)}
#: the phases of a set piece (set up or not taken yet), as one tuple made once
_SET_PIECE_PHASES = (PHASES.SETUP, PHASES.OUR_RESTART, PHASES.OPP_RESTART)
#: the set pieces whose formation depends on the ball's place alone (their kick-off, the penalties, the
#: dropped ball); our kick-off's also on the side of the pass (`kickoff_side` of the opponents)
_OUR_KICKOFF = 1
_BALL_ONLY_FORMATIONS = frozenset((2, 5, 6, 13))
_copysign = math.copysign


def _formation_key(kind: int, bx: float, by: float, opps: list) -> tuple | None:
    """What `formation` of set piece ``kind`` depends on besides the fixed field and parameters, when that is
    few numbers (the ball's place, with the signs of its zeros, and our kick-off's side); None when the
    formation reads the opponents or the assistant's place (the other restarts: computed at every picture)."""
    if kind == _OUR_KICKOFF:
        side = kickoff_side(opps)
    elif kind in _BALL_ONLY_FORMATIONS:
        side = 0.0
    else:
        return None
    return (kind, bx, by, _copysign(1.0, bx), _copysign(1.0, by), side)


class Picture:
    __slots__ = (
        "path",
        "phase",
        "holder",
        "goalie_plays",
        "opp_holds",
        "attacking",
        "catch",
        "their_t",
        "their_xy",
        "roles",
        "slots",
        "receiver",
        "pass_info",
        "active",
    )

    def __init__(self):
        self.holder = 0  # our robot holding the ball (0: none)
        self.goalie_plays = False  # the ball is our goalkeeper's to play
        self.opp_holds = False
        self.attacking = False
        self.catch: dict[int, tuple[float, float, float]] = {}  # id -> (time, x, y) interception
        self.their_t = math.inf
        self.their_xy = (0.0, 0.0)
        self.roles: dict[int, int] = {}
        self.slots: dict[int, tuple[float, float, float, float]] = {}  # id -> (x, y, face x, face y)
        self.receiver = 0  # robot a pass is (to be) played to
        self.pass_info = None
        self.active = 0


class TeamMemo:
    """The last picture computed in this process for a team, with every input it depends on: robots of
    the team that see exactly the same facts at the same tick reuse it instead of recomputing it. (The
    team-mates' part of an observation is the very same object then, see observation.TeamView.)"""

    def __init__(self):
        self.tick = -1
        self.mates = None
        self.rest: tuple = ()
        self.picture = None
        self._asked: tuple = ()  # the key of the last `get` that found nothing, for the `put` after it

    def get(self, obs: Observation, flow: GameFlow) -> Picture | None:
        rest = _rest_key(obs, flow)
        if self.tick == obs.tick and self.mates is obs.mates and self.rest == rest:
            return self.picture
        self._asked = rest
        return None

    def put(self, obs: Observation, flow: GameFlow, picture: Picture) -> None:
        rest = self._asked
        self._asked = ()
        if not rest:
            rest = _rest_key(obs, flow)
        self.tick, self.mates, self.rest, self.picture = obs.tick, obs.mates, rest, picture


def _rest_key(obs: Observation, flow: GameFlow) -> tuple:
    # (GameFlow.key()'s numbers inline, the phase as its member: the members are distinct, so equal members
    # are equal phases, compared by identity first)
    return (
        obs.bx,
        obs.by,
        obs.bz,
        obs.bvx,
        obs.bvy,
        obs.bvz,
        obs.mode,
        obs.mtype,
        obs.opps,
        flow.phase,
        flow.kind,
        flow.ball0,
        flow.taker,
    )


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


@numba.njit(cache=True)
def _assign_flat(flat, n, m, cx, cy, cr):
    """`_assign` of the robots' (n, 4) and the slots' (m, 3) rows, given one after the other in ``flat``."""
    return _assign(flat[: 4 * n].reshape((n, 4)), flat[4 * n : 4 * n + 3 * m].reshape((m, 3)), cx, cy, cr)


@numba.njit(cache=True)
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
            if not hypot(x - out[j, 0], y - out[j, 1]) > 3.0:
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
        order[0], order[1], order[2], order[3] = _ASSISTANT, _ASSISTANT, _PASSIVE, _MIDFIELD
    elif attacking:
        order[0], order[1], order[2] = _ASSISTANT, _PASSIVE, _MIDFIELD
    else:
        order[0], order[1], order[2] = _PASSIVE, _MIDFIELD, _ASSISTANT
    m = min(4 if n >= 4 else 3, n)
    slots = np.empty((m, 3))  # x, y, role (the rows `_assign` takes), spread as they come
    used = 0
    for s in range(m):
        role = order[s]
        if role == _ASSISTANT:
            a = min(used, assist.shape[0] - 1)
            x, y = assist[a, 0], assist[a, 1]
            used += 1
        elif role == _PASSIVE:
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


class Analyst:
    """Computes team pictures for one team (field, parameters and the receiving-spot grid are fixed)."""

    def __init__(self, params: NubotParams, areas: Areas, spots: tuple[np.ndarray, np.ndarray]):
        self.p = params
        self.areas = areas
        self.spots = spots
        self.xlim = areas.L2 + 1.3
        self.ylim = areas.W2 + 1.3
        self.pitch = areas.pitch
        # the last set-piece formation computed, with `_formation_key` of its inputs: while a kick-off, a
        # penalty or a dropped ball is set up and taken, the ball stays put and the formation is the same
        self._formation_key: tuple | None = None
        self._formation: list[tuple] = []
        self._intercepts = bind(_team_intercepts)
        self._assist = bind(assist_spots)
        self._slots = bind(open_slots)

    def analyse(self, obs: Observation, flow: GameFlow) -> Picture:
        p = self.p
        pic = Picture()
        pic.phase = flow.phase
        pic.path = path = BallPath(
            obs.bx, obs.by, obs.bz, obs.bvx, obs.bvy, obs.bvz, p.ball_deceleration, BALL_RADIUS, self.xlim, self.ylim
        )
        # a robot off the field beyond the margin (it followed the ball) still plays; one not valid within
        # the margin has been taken off (sent off: parked and disabled beside the field)
        xl, yl = self.areas.L2 + 1.0, self.areas.W2 + 1.0
        mates = obs.mates  # (as nearly always: every team-mate plays; the list is only read)
        for m in mates:
            if not (m.valid or abs(m.x) > xl or abs(m.y) > yl):
                mates = [m for m in obs.mates if m.valid or abs(m.x) > xl or abs(m.y) > yl]
                break
        for m in mates:
            if m.holding:
                pic.holder = m.id
        opps = obs.opps
        if pic.holder == 0 and obs.opp_ball_d < OPP_CONTROL:  # (the nearest opponent's distance to the ball)
            pic.opp_holds = True
        self._passes(obs, pic)
        if flow.phase in _SET_PIECE_PHASES:
            self._set_piece(obs, flow, pic, mates)  # (nobody plays the ball: no interceptions needed)
            return pic
        # interception of every robot, ours (with the time to face the ball) and theirs, in one go
        n_us = len(mates)
        if mates or opps:
            # (the team view's table when every team-mate plays, as nearly always)
            if n_us == len(obs.mates):
                us = obs.mate_array
            else:
                us = _rows([(m.x, m.y, m.vx, m.vy, m.id, m.yaw) for m in mates], 6)
            # (ballpath.team_intercepts, by its kernel's compiled entry)
            out = np.empty((us.shape[0] + obs.opp_array.shape[0], 3))
            turn = 0.7 / p.max_turn
            self._intercepts(
                path.x,
                path.y,
                path.speed,
                path.ux,
                path.uy,
                path.land_t,
                path.stop_t,
                path.decel,
                path.xlim,
                path.ylim,
                us,
                obs.opp_array,
                obs.bx,
                obs.by,
                turn,
                p.max_speed,
                p.acceleration,
                out,
            )
            res = out.tolist()
            for k, m in enumerate(mates):
                pic.catch[m.id] = (0.0, obs.bx, obs.by) if m.holding else tuple(res[k])
            if opps:
                t, x, y = min(res[n_us:])
                pic.their_t, pic.their_xy = (0.0 if pic.opp_holds else t), (x, y)
        self._play(obs, flow, pic, mates)
        return pic

    # --- passes announced by team-mates ---------------------------------------------------------------
    def _passes(self, obs: Observation, pic: Picture) -> None:
        for m in obs.mates:
            info = m.pass_info
            if info is None or info.catch_id == m.id or info.catch_id not in obs.by_id:
                continue
            if info.is_passout:
                # under way while the ball is loose (no opponent on it either: a kick into a duel is no
                # pass) and still moving towards the catch point
                if pic.holder or pic.opp_holds or obs.ball_speed < 0.25:
                    continue
                dx, dy = info.catch_x - obs.bx, info.catch_y - obs.by
                d = math.hypot(dx, dy)
                # hysteresis on what the receiver tells the team: a pass slightly off does not swap the
                # roles back and forth
                on_it = obs.by_id[info.catch_id].role == ROLES.CATCHOFPASS
                heading = PASS_KEPT if on_it else PASS_HEADING
                if d > 1.5 and (obs.bvx * dx + obs.bvy * dy) < heading * d * obs.ball_speed:
                    continue
            elif pic.holder != m.id and not info.is_static_pass:
                continue  # announced by a robot that does not have the ball (any more)
            pic.receiver, pic.pass_info = info.catch_id, info
            return

    # --- open play --------------------------------------------------------------------------------------
    def _play(self, obs: Observation, flow: GameFlow, pic: Picture, mates: list) -> None:
        p, areas = self.p, self.areas
        # (plain loops: a generator or a comprehension makes a function object at every call)
        field = []
        goalie = None
        for m in mates:
            if not m.is_goalie:
                field.append(m)
            elif goalie is None:
                goalie = m
        holder = obs.by_id.get(pic.holder) if pic.holder else None
        if goalie is not None:
            pic.roles[goalie.id] = ROLES.GOALIE
            if holder is goalie:
                pic.goalie_plays = True
            elif holder is None:
                gt, gx, gy = pic.catch[goalie.id]
                pic.goalie_plays = areas.near_own_penalty_area(gx, gy, -0.1) and areas.near_own_penalty_area(
                    obs.bx, obs.by, 0.6
                )
        active = None
        if holder is not None and not holder.is_goalie:
            active = holder
        elif (
            pic.receiver
            and pic.pass_info.is_passout
            and pic.receiver in obs.by_id
            and not obs.by_id[pic.receiver].is_goalie
            and obs.by_id[pic.receiver].valid
        ):
            active = obs.by_id[pic.receiver]
        elif holder is None:
            best = math.inf
            taker = flow.taker
            active_role = ROLES.ACTIVE
            for m in field:
                if m.role == active_role and m.role_time < MIN_ACTIVE_TIME and m.id != taker:
                    best, active = -math.inf, m  # a robot that just took the ball on keeps it a moment
                    break
            catch = pic.catch
            hysteresis = p.active_hysteresis
            for m in field:
                if m.id == taker:
                    continue
                score = catch[m.id][0] - (hysteresis if m.role == active_role else 0.0)
                if score < best:
                    best, active = score, m
        if active is not None:
            pic.active = active.id
            pic.roles[active.id] = ROLES.ACTIVE if pic.receiver != active.id else ROLES.CATCHOFPASS
        # (min of the catch times as min() takes it: the first, then any smaller one)
        our_t = math.inf
        n_said = n_yes = 0
        for k, m in enumerate(mates):
            t = pic.catch[m.id][0]
            if k == 0 or t < our_t:
                our_t = t
            said = m.attacking
            if said >= 0:
                n_said += 1
                n_yes += said
        # attacking, with hysteresis on what the team said last tick (so formations do not swap back and forth)
        before = 2 * n_yes > n_said if n_said else False
        margin = -ATTACK_HYSTERESIS if before else ATTACK_HYSTERESIS
        pic.attacking = holder is not None or (not pic.opp_holds and our_t < pic.their_t - margin)
        rest = []
        for m in field:
            if m is not active:
                rest.append(m)
        if not rest:
            return
        bx, by = pic.path.at(0.4)
        receiver = None
        if pic.receiver and pic.receiver != pic.active and pic.pass_info is not None:
            for m in rest:
                if m.id == pic.receiver:
                    receiver = m
                    break
        # the roles' points, each looked up in `positions` now (a replacement there is the one followed)
        pitch, attacking = self.pitch, pic.attacking
        if attacking:
            assist = self._assist_array(obs, 2 if len(rest) >= 4 else 1)
        else:
            assist = np.array((as_called(positions.outlet_point)(pitch, bx, by),))
        passive_x, passive_y = as_called(positions.passive_point)(pitch, bx, by, attacking)
        midfield_x, midfield_y = as_called(positions.midfield_point)(pitch, bx, by, attacking, obs.opp_array)
        out = np.empty((len(rest), 4))
        k = self._slots(
            obs.mate_array,
            np.array([m.row for m in rest], dtype=np.int64),
            attacking,
            assist,
            passive_x,
            passive_y,
            midfield_x,
            midfield_y,
            bx,
            by,
            pitch,
            p.role_hysteresis,
            out,
        )
        res = out.tolist()
        for i in range(k):
            _, role, x, y = res[i]
            rid = rest[i].id
            pic.roles[rid] = _ROLE_OF[int(role)]
            pic.slots[rid] = (x, y, bx, by)
        if receiver is not None and receiver.id in pic.slots:
            # the announced receiver keeps its role and waits at the catch point, facing the passer
            info = pic.pass_info
            pic.slots[receiver.id] = (info.catch_x, info.catch_y, obs.bx, obs.by)

    def _assist_array(self, obs: Observation, n: int) -> np.ndarray:
        """Up to ``n`` receiving spots for the assistants (`assist_spots`), as a (k, 2) array, near where the
        first assistant stands."""
        cx, cy = self.spots
        nx = ny = math.nan  # (the first assistant's place)
        for m in obs.mates:
            if m.role == _ASSISTANT_ROLE:
                nx, ny = m.x, m.y
                break
        out = np.empty((n, 2))
        k = self._assist(cx, cy, obs.bx, obs.by, obs.opp_array, self.areas.L2, 3.0, 8.5, nx, ny, out)
        return out[:k]

    # --- set pieces ---------------------------------------------------------------------------------------
    def _set_piece(self, obs: Observation, flow: GameFlow, pic: Picture, mates: list) -> None:
        # (one plain loop; the phases compared by identity: the flow's phase is always one of PHASES' members)
        field = []
        for m in mates:
            if m.is_goalie:
                pic.roles[m.id] = _GOALIE
            else:
                field.append(m)
        phase = flow.phase
        bx, by = (obs.bx, obs.by) if phase is _SETUP else flow.ball0
        key = _formation_key(flow.kind, bx, by, obs.opps)
        if key is not None and key == self._formation_key:
            slots = self._formation  # (never written: `assign` and the loop below only read it)
        else:
            prev = next(((m.x, m.y) for m in obs.mates if m.role == ROLES.ASSISTANT), None)
            slots = formation(flow.kind, self.areas, bx, by, obs.opps, self.p, self.spots, prev)
            if key is not None:
                self._formation_key, self._formation = key, slots
        hyst = SETUP_HYSTERESIS if phase is _SETUP else RESTART_HYSTERESIS
        keep = (
            self.p.dropball_distance
            if flow.kind == 13
            else (self.p.mate_distance if flow.kind % 2 == 1 else self.p.opponent_distance)
        )
        chosen = assign(field, slots, hyst, around=(bx, by, keep))
        for rid, i in chosen.items():
            role, x, y, fx, fy = slots[i]
            pic.roles[rid] = role
            pic.slots[rid] = (x, y, fx, fy)
            if role == _ACTIVE_ROLE:
                pic.active = rid
        if phase is _OUR_RESTART and pic.receiver in pic.slots and pic.pass_info is not None and flow.kind != 1:
            # the taker aims at the receiver: it waits for the ball where it is announced, facing it
            info = pic.pass_info
            pic.slots[pic.receiver] = (info.catch_x, info.catch_y, bx, by)
        pic.attacking = flow.kind % 2 == 1 and flow.kind != 13
