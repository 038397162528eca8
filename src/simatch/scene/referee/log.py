"""The referee's append-only event log: every decision, with the rule, the team, the robot, where, and the
measured value against its limit.

Each entry is a GameEvent, published on the run's ``events`` topic as it is made (so the run's event
list, recordings and viewers get it) and kept here in order. Nothing is ever removed or edited: a
decision that is revised (a disallowed goal, an operator's correction) is a new entry.
"""

from __future__ import annotations

from collections.abc import Callable

from ... import msgs

#: event types that are fouls (counted per team in the result); the rules' own types
FOUL_TYPES = frozenset(
    {
        "dribble_too_far",
        "dribble_backward_too_far",
        "goal_area",
        "penalty_area_crowded",
        "penalty_area_time",
        "set_piece_distance",
        "kickoff_half",
        "dropped_ball_distance",
        "double_touch",
        "charging",
        "lob",
        "ball_holding",
        "ball_rotation",
        "pushing",
        "goalkeeper_contact",
    }
)


class EventLog:
    def __init__(self, publish: Callable[[object], None] | None = None):
        self._entries: list = []
        self._publish = publish
        self.fouls: dict[str, int] = {}

    def add(
        self,
        stamp: float,
        type: str,
        team: str = "",
        robot: int = 0,
        x: float = 0.0,
        y: float = 0.0,
        value: float = 0.0,
        limit: float = 0.0,
        detail: str = "",
    ):
        ev = msgs.GameEvent(
            stamp=float(stamp),
            type=type,
            team=team,
            robot=int(robot),
            x=float(x),
            y=float(y),
            value=float(value),
            limit=float(limit),
            detail=detail,
        )
        self._entries.append(ev)
        if type in FOUL_TYPES and team:
            self.fouls[team] = self.fouls.get(team, 0) + 1
        if self._publish is not None:
            self._publish(ev)
        return ev

    def __len__(self) -> int:
        return len(self._entries)

    def __iter__(self):
        return iter(tuple(self._entries))

    def of_type(self, *types: str) -> list:
        return [e for e in self._entries if e.type in types]

    @property
    def last(self):
        return self._entries[-1] if self._entries else None
