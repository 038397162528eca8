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

import numpy as np

from ...compiled import bind
from ..roles import ROLES
from . import positions
from .assignment import assign, assist_spots, open_slots
from .ballpath import BallPath, _team_intercepts
from .gameflow import PHASES, GameFlow
from .observation import Observation
from .observation import _array as _rows
from .params import NubotParams
from .positions import Areas, as_called
from .setpieces import formation, kickoff_side

BALL_RADIUS = 0.11
#: an opponent whose centre is this close to the ball controls it [m]
OPP_CONTROL = 0.45
#: a robot that has just become the active one stays so at least this long (unless another holds the ball) [s]
MIN_ACTIVE_TIME = 0.6
#: we keep attacking (defending) until the opponents (we) reach the ball this much sooner [s]
ATTACK_HYSTERESIS = 0.4
#: set-piece slots change hands easily while robots run to them, and never once START is given [m]
SETUP_HYSTERESIS = 0.5
RESTART_HYSTERESIS = 50.0
#: a pass under way counts while the ball heads for the catch point within acos(PASS_HEADING), or within
#: acos(PASS_KEPT) once the receiver took the catching role
PASS_HEADING = 0.6
PASS_KEPT = 0.3


# the positional roles' Role members by their numbers (the slots' kernel gives numbers)
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
    # (GameFlow.key()'s numbers, the phase as its member: the members are distinct, so equal members are
    # equal phases)
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
        field = []
        goalie = None
        for m in mates:
            if not m.is_goalie:
                field.append(m)
            elif goalie is None:
                goalie = m
        holder = obs.by_id.get(pic.holder) if pic.holder else None
        if goalie is not None:
            self._goalie(obs, pic, goalie, holder)
        active = self._active(obs, flow, pic, field, holder)
        if active is not None:
            pic.active = active.id
            pic.roles[active.id] = ROLES.ACTIVE if pic.receiver != active.id else ROLES.CATCHOFPASS
        pic.attacking = self._attacking(pic, mates, holder)
        rest = []
        for m in field:
            if m is not active:
                rest.append(m)
        if rest:
            self._positional_slots(obs, pic, rest)

    def _goalie(self, obs: Observation, pic: Picture, goalie, holder) -> None:
        """The goalkeeper's role, and whether the ball is its to play: it holds it, or it reaches the ball
        near our penalty area with the ball there too."""
        areas = self.areas
        pic.roles[goalie.id] = ROLES.GOALIE
        if holder is goalie:
            pic.goalie_plays = True
        elif holder is None:
            gt, gx, gy = pic.catch[goalie.id]
            pic.goalie_plays = areas.near_own_penalty_area(gx, gy, -0.1) and areas.near_own_penalty_area(
                obs.bx, obs.by, 0.6
            )

    def _active(self, obs: Observation, flow: GameFlow, pic: Picture, field: list, holder):
        """The field robot that plays the ball: the one holding it, the receiver of a pass under way, or
        (nobody holding the ball) the one reaching the ball first, with hysteresis for the robot that plays
        it already, which keeps it a moment after it took it on; never the taker of the restart just played."""
        if holder is not None and not holder.is_goalie:
            return holder
        receiver = obs.by_id.get(pic.receiver) if pic.receiver else None
        if receiver is not None and pic.pass_info.is_passout and not receiver.is_goalie and receiver.valid:
            return receiver
        if holder is not None:  # (our goalkeeper)
            return None
        active = None
        best = math.inf
        taker = flow.taker
        active_role = ROLES.ACTIVE
        for m in field:
            if m.role == active_role and m.role_time < MIN_ACTIVE_TIME and m.id != taker:
                best, active = -math.inf, m
                break
        catch = pic.catch
        hysteresis = self.p.active_hysteresis
        for m in field:
            if m.id == taker:
                continue
            score = catch[m.id][0] - (hysteresis if m.role == active_role else 0.0)
            if score < best:
                best, active = score, m
        return active

    def _attacking(self, pic: Picture, mates: list, holder) -> bool:
        """Whether we attack: we hold the ball, or reach it sooner than the opponents (who do not hold it),
        with hysteresis on what the team said last tick (so formations do not swap back and forth)."""
        our_t = math.inf  # (the first of the smallest catch times)
        n_said = n_yes = 0
        for k, m in enumerate(mates):
            t = pic.catch[m.id][0]
            if k == 0 or t < our_t:
                our_t = t
            said = m.attacking
            if said >= 0:
                n_said += 1
                n_yes += said
        before = 2 * n_yes > n_said if n_said else False
        margin = -ATTACK_HYSTERESIS if before else ATTACK_HYSTERESIS
        return holder is not None or (not pic.opp_holds and our_t < pic.their_t - margin)

    def _positional_slots(self, obs: Observation, pic: Picture, rest: list) -> None:
        """The positional roles and places of the robots ``rest`` (`open_slots`), the ball expected where
        it will be in 0.4 s; an announced receiver waits at the catch point, facing the passer."""
        bx, by = pic.path.at(0.4)
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
            self.p.role_hysteresis,
            out,
        )
        res = out.tolist()
        for i in range(k):
            _, role, x, y = res[i]
            rid = rest[i].id
            pic.roles[rid] = _ROLE_OF[int(role)]
            pic.slots[rid] = (x, y, bx, by)
        info = pic.pass_info
        if pic.receiver and pic.receiver != pic.active and info is not None and pic.receiver in pic.slots:
            pic.slots[pic.receiver] = (info.catch_x, info.catch_y, obs.bx, obs.by)

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
