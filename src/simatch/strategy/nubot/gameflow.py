"""The robot's reading of the game flow from the game commands and what it sees.

The scene interface says only the current command (MatchMode) and the last set piece (MatchType). The
rules a team must respect after a restart depend on more: whether the ball is in play yet (it moved
0.5 m), who took the restart (the taker may not touch the ball again before another robot did), whether
a goal would count (no direct goal from a set piece: a team-mate must take the ball first). Every robot
keeps this reading from its own observations, so that the team agrees without talking.
"""

from __future__ import annotations

import enum
import math

from ...msgs.game_commands import MatchMode, is_ours
from ..roles import members
from .observation import Observation

#: `MatchMode` and `Phase` members as plain attributes (`roles.members`), for every module of the team
MODES = members(MatchMode)

IN_PLAY_DISTANCE = 0.65  # the ball is in play once it moved 0.5 m from its restart spot (with a margin) [m]
#: our restart's ball moved this far (beyond perception noise; opponents keep 3 m away): our taker touched
#: it, and may not touch it again, even if it is not in play yet (a bump, a kick that fizzled) [m]
TAKEN_DISTANCE = 0.2
TOUCH_DISTANCE = 0.48  # an opponent's centre this close to the ball's touches it [m]
TAKER_BLOCK_LIMIT = 10.0  # the taker's double-touch block lapses after this long anyway [s]
ON_BALL = 0.42  # a team-mate's centre this close to the ball's is on it [m]
REGAIN_ROLL = 1.3  # a pass into the opponents' half rolls at least 1 m (MSL RC-10.1.2; margin) [m]
HALF_MARGIN = 0.3  # a pass is received past the half-way line by this much, to be sure [m]


class Phase(enum.IntEnum):
    STOP = 0
    SETUP = 1  # positioning for a set piece (the command is a set piece)
    OUR_RESTART = 2  # START given, our set piece not taken yet
    OPP_RESTART = 3  # START given, the opponents' set piece not taken yet
    PLAY = 4
    PARK = 5
    TEST = 6


PHASES = members(Phase)
# (what `update` compares at every tick as plain ints and the very members: an IntEnum compares slowly)
_STOPROBOT, _PARKINGROBOT, _TEST = int(MODES.STOPROBOT), int(MODES.PARKINGROBOT), int(MODES.TEST)
_PLAY, _OUR_RESTART, _OPP_RESTART = PHASES.PLAY, PHASES.OUR_RESTART, PHASES.OPP_RESTART


class GameFlow:
    def __init__(self, restart_wait: float):
        self.restart_wait = restart_wait
        self.phase = PHASES.STOP
        self.kind = 0  # the set piece being set up or taken (MatchMode value)
        self.t0 = 0.0  # when START came for the restart
        self.ball0 = (0.0, 0.0)  # where the ball was then
        self.taker = 0  # our robot that took the last restart (blocked), 0 if none
        self.taker_since = 0.0
        self.pass_pending = False  # a goal would not count yet: a second team-mate must take the ball
        self.first_holder = 0
        # MSL RC-10.1.2: a ball won in our own half counts for a goal only after a team-mate received it
        # in the opponents' half after a free roll of 1 m
        self.need_pass = False
        self._ours = 0  # our robot last on the ball, 0 if the opponents (or nobody) were
        self._left_at = (0.0, 0.0)  # where the ball was when our robot last had it
        self._last_mode = -1

    def key(self) -> tuple:
        return (int(self.phase), self.kind, self.ball0, self.taker)

    def update(self, obs: Observation) -> None:
        mode = obs.mode
        last = self._last_mode
        self._last_mode = mode
        if mode == _STOPROBOT:
            self.phase = PHASES.STOP
            return
        if mode == _PARKINGROBOT:
            self.phase = PHASES.PARK
            return
        if mode == _TEST:
            self.phase = PHASES.TEST
            return
        if 1 <= mode <= 13:
            self.phase = PHASES.SETUP
            self.kind = mode
            self.taker = 0
            return
        # START (or anything else that means play)
        if mode != last:
            if 1 <= last <= 13:
                self._restart(obs, obs.mtype if 1 <= obs.mtype <= 13 else last)
            else:
                self.phase = PHASES.PLAY
        self._follow(obs)

    def _restart(self, obs: Observation, kind: int) -> None:
        self.kind = kind
        self.t0 = obs.t
        self.ball0 = (obs.bx, obs.by)
        self.taker = 0
        self.first_holder = 0
        self._ours = 0
        if kind == MODES.DROPBALL:
            self.phase = PHASES.PLAY
            self.pass_pending = True
        elif is_ours(kind):
            self.phase = PHASES.OUR_RESTART
            self.pass_pending = kind != MODES.OUR_PENALTY
        else:
            self.phase = PHASES.OPP_RESTART
            self.pass_pending = False

    def _follow(self, obs: Observation) -> None:
        holder = obs.holder
        touched = self._regain(obs, holder)
        phase = self.phase  # (always one of PHASES' members: compared by identity)
        if phase is _OUR_RESTART:
            shift = math.hypot(obs.bx - self.ball0[0], obs.by - self.ball0[1])
            if shift >= TAKEN_DISTANCE and not self.taker:
                # from its first touch on, the taker may not touch the ball again before another robot did;
                # the others keep their distance until the ball is in play (or the restart times out)
                bx, by = self.ball0
                taker = min(obs.field_mates() or obs.mates, key=lambda m: math.hypot(m.x - bx, m.y - by))
                self.taker, self.taker_since = taker.id, obs.t
                self.first_holder = taker.id
            if shift >= IN_PLAY_DISTANCE or obs.t - self.t0 > self.restart_wait:
                self.phase = PHASES.PLAY
        elif phase is _OPP_RESTART:
            shift = math.hypot(obs.bx - self.ball0[0], obs.by - self.ball0[1])
            if shift >= IN_PLAY_DISTANCE or obs.t - self.t0 > self.restart_wait:
                self.phase = PHASES.PLAY
        if self.phase is not _PLAY or not (self.taker or self.pass_pending):
            return
        if touched is None:
            touched = _opponent_touching(obs)
        if self.taker:
            if (
                touched
                or (holder is not None and holder.id != self.taker)
                or obs.t - self.taker_since > TAKER_BLOCK_LIMIT
            ):
                self.taker = 0
        if self.pass_pending:
            # no direct goal: a second robot of ours must have had the ball (at a dropped ball, any
            # second robot, an opponent too)
            if holder is not None and self.first_holder == 0:
                self.first_holder = holder.id
            elif (holder is not None and holder.id != self.first_holder) or (touched and self.kind == MODES.DROPBALL):
                self.pass_pending = False

    def _regain(self, obs: Observation, holder) -> bool | None:
        """Follow who is on the ball for RC-10.1.2 (as the referee reads it from the touches, with margins).
        ``holder``: the team-mate holding the ball (`Observation.holder`). Returns whether an opponent touches the ball,
        if it had to find out (else None)."""
        bx, by = obs.bx, obs.by
        on = holder
        if on is None and obs.near_mate >= 0 and not obs.near_mate_d > ON_BALL:
            # the team-mate nearest to the ball (the first of equals), if it is on it
            on = obs.mates[obs.near_mate]
        if on is None:
            touched = obs.opp_ball_d < TOUCH_DISTANCE  # (_opponent_touching, inline)
            if touched:
                self._ours = 0
            return touched
        if not self._ours:
            self.need_pass = bx < 0.0  # won in our half (the line itself is not)
        elif (
            on.id != self._ours
            and self.need_pass
            and bx > HALF_MARGIN
            and math.hypot(bx - self._left_at[0], by - self._left_at[1]) >= REGAIN_ROLL
        ):
            self.need_pass = False  # a team-mate received a pass in their half
        self._ours = on.id
        self._left_at = (bx, by)
        return None


def _opponent_touching(obs: Observation) -> bool:
    """An opponent is close enough to the ball to be touching it."""
    return obs.opp_ball_d < TOUCH_DISTANCE
