"""What a rule is: a small object that looks at the match and makes calls.

One rule per file, in the style of the ER-Force autoref: each rule names the phases in which it judges,
keeps its own memory (timers, who it has flagged), and returns `Call`s — what it saw, measured against
its limit, and the restart that follows. The referee (`referee.py`) logs every call and enforces it;
rules never touch the world or the game state themselves.

Hooks (all optional):

* ``check()`` — at the control period, in the rule's ``phases``;
* ``ready()`` — while robots prepare a restart: are the positions this rule cares about legal?
* ``at_start()`` — when START is given: calls for robots still out of position (logged; play goes on);
* ``on_restart()`` — the ball was placed for a new restart: forget what belonged to the last one.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

from ..state import LIVE, Phase

if TYPE_CHECKING:
    from ..match import Match
    from ..restarts import Restart


@dataclass
class Call:
    """A decision: ``type`` is the event type (the rule's name or a finer one)."""

    type: str
    team: str = ""  # the team concerned (the offender for a foul)
    robot: int = -1  # robot index, -1 if none
    x: float = 0.0  # where (world frame)
    y: float = 0.0
    value: float = 0.0  # the measured value ...
    limit: float = 0.0  # ... and the limit it was judged against
    detail: str = ""
    restart: Restart | None = None  # the restart that follows; None: play goes on
    card: str | None = None  # "yellow" or "red" for the robot
    goal_for: str = ""  # a goal that counts, for this team
    in_play: bool = False  # the call puts the ball in play (restart timeout)
    scorer: int = -1  # a goal's scorer (robot index; of the other team for an own goal)


class Rule:
    name: ClassVar[str] = "rule"
    phases: ClassVar[frozenset[Phase]] = frozenset()

    def __init__(self, match: Match):
        self.m = match
        self.p = match.params

    def on_restart(self) -> None:
        pass

    def ready(self) -> bool:
        return True

    def at_start(self) -> list[Call]:
        return []

    def check(self) -> Call | None:
        return None

    # --- helpers ---------------------------------------------------------------------------------------
    def robot_name(self, i: int) -> str:
        return self.m.obs.names[i]

    def call(self, type: str, i: int, value: float, limit: float, detail: str, **kw) -> Call:
        """A call about robot ``i`` (its team, its id, where it stands)."""
        obs = self.m.obs
        return Call(
            type=type,
            team=obs.team_of[i],
            robot=i,
            x=obs.X[i],
            y=obs.Y[i],
            value=float(value),
            limit=float(limit),
            detail=detail,
            **kw,
        )

    def free_kick_against(self, i: int) -> Restart:
        """A free kick for the opponents of robot ``i``, where the ball is."""
        obs = self.m.obs
        return self.m.spots.at_ball("free_kick", obs.other(obs.team_of[i]), obs.bx, obs.by)

    def foul_restart(self, i: int) -> tuple[Restart | None, str]:
        """(restart, what it is) after a foul by robot ``i`` against an opponent: a free kick for the opponents
        where the ball is, or a penalty kick when ``i`` is a defender in its own penalty area (and
        ``penalty_for_fouls_in_area``). While the ball is not in play the restart stands (None)."""
        m, p = self.m, self.p
        if m.game.phase not in LIVE:
            return None, "the ball is not in play: the restart stands"
        obs = m.obs
        other = obs.other(obs.team_of[i])
        if p.penalty_for_fouls_in_area and obs.penalty_area[i] == obs.own_side[i]:
            return m.spots.penalty(other, obs.own_side[i]), f"penalty kick for {other}"
        return self.free_kick_against(i), f"free kick for {other}"
