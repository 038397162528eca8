"""The referee's explicit state machine: the stage of the match and the phase of play within it.

Stages follow the scene's ``[match]``: first half, half time, second half (up to four halves), an optional
penalty shoot-out, then ended. Within a stage, play goes through phases::

    stopped ──(stop_time, ball placed)──► prepare ──(positions legal, or time up: START)──► taking
       ▲                                     │ dropped ball: START puts the ball in play       │
       │                                     ▼                                                 │ ball moved
       └───────── a decision (goal, ball out, foul, no progress) ◄────── play ◄────────────────┘ 0.5 m or 7 s

``paused`` is the operator's halt (the clock stops; resume returns to where play was); ``ended`` is final.
Every change goes through `Game.go`, which refuses a change the table below does not allow.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from ...msgs.game_commands import MatchMode
from .restarts import Restart


class Phase(str, enum.Enum):
    STOPPED = "stopped"  # dead ball: robots hold STOP (or PARKING) while the referee places the ball
    PREPARE = "prepare"  # a restart is called: robots take their positions
    TAKING = "taking"  # START given; the set piece is being taken, the ball is not in play yet
    PLAY = "play"  # the ball is in play
    PAUSED = "paused"  # an operator halted the game; the clock stands still
    ENDED = "ended"


TRANSITIONS: dict[Phase, frozenset[Phase]] = {
    Phase.STOPPED: frozenset({Phase.STOPPED, Phase.PREPARE, Phase.PLAY, Phase.PAUSED, Phase.ENDED}),
    Phase.PREPARE: frozenset({Phase.STOPPED, Phase.PREPARE, Phase.TAKING, Phase.PLAY, Phase.PAUSED, Phase.ENDED}),
    Phase.TAKING: frozenset({Phase.STOPPED, Phase.PREPARE, Phase.PLAY, Phase.PAUSED, Phase.ENDED}),
    Phase.PLAY: frozenset({Phase.STOPPED, Phase.PREPARE, Phase.PAUSED, Phase.ENDED}),
    Phase.PAUSED: frozenset({Phase.STOPPED, Phase.PREPARE, Phase.TAKING, Phase.PLAY, Phase.ENDED}),
    Phase.ENDED: frozenset(),
}

#: phases in which the ball can leave the field or enter a goal with consequences
LIVE = frozenset({Phase.TAKING, Phase.PLAY})

HALF_NAMES = ("first_half", "second_half", "third_half", "fourth_half")


@dataclass(frozen=True)
class Stage:
    name: str
    kind: str  # "half", "break", "shootout", "ended"
    duration: float | None  # seconds of clock, None: until decided
    half: int = 0  # 1-based half number for halves


def schedule(match) -> list[Stage]:
    """The stages of a match from the scene's ``[match]`` settings."""
    out: list[Stage] = []
    for h in range(match.halves):
        if h > 0 and match.half_time > 0:
            out.append(Stage("half_time", "break", match.half_time))
        out.append(Stage(HALF_NAMES[h], "half", match.half_duration, h + 1))
    if match.penalty_shootout:
        out.append(Stage("penalty_shootout", "shootout", None))
    out.append(Stage("ended", "ended", None))
    return out


class TransitionError(RuntimeError):
    """A phase change the state machine does not allow (a bug in the referee, never a team's doing)."""


@dataclass
class Game:
    """The state of the match as the referee holds it."""

    teams: list[str]
    stages: list[Stage]
    dt: float
    stage_index: int = 0
    stage_steps: int = 0  # clock of the current stage, in physics steps
    phase: Phase = Phase.STOPPED
    phase_steps: int = 0  # time in the current phase (not counting pauses)
    paused_phase: Phase | None = None
    command: MatchMode = MatchMode.STOPROBOT  # current command as given (from `command_team`'s view)
    command_team: str = ""
    match_type: dict[str, MatchMode] = field(default_factory=dict)  # last set piece, per team's view
    restart: Restart | None = None  # the restart being prepared or taken (or last taken)
    next_restart: Restart | None = None  # the restart that follows the current stoppage
    hold: bool = False  # stopped until an operator acts (operator STOP, PARKING)
    auto: bool = True  # the referee enforces its decisions (False: manual mode)
    reason: str = ""  # why the current command was given
    score: dict[str, int] = field(default_factory=dict)
    kickoff_team: str = ""  # team that kicked off the current half
    version: int = 0  # bumped on every change worth publishing

    def __post_init__(self):
        self.score = {t: 0 for t in self.teams}
        self.match_type = {t: MatchMode.STOPROBOT for t in self.teams}

    # --- stage -----------------------------------------------------------------------------------------
    @property
    def stage(self) -> Stage:
        return self.stages[self.stage_index]

    @property
    def clock(self) -> float:
        """Seconds of the current stage played (the clock stops while paused)."""
        return self.stage_steps * self.dt

    @property
    def time_left(self) -> float:
        d = self.stage.duration
        return -1.0 if d is None else max(0.0, d - self.clock)

    def next_stage(self) -> Stage:
        self.stage_index = min(self.stage_index + 1, len(self.stages) - 1)
        self.stage_steps = 0
        self.version += 1
        return self.stage

    # --- phase -----------------------------------------------------------------------------------------
    @property
    def phase_time(self) -> float:
        return self.phase_steps * self.dt

    def go(self, phase: Phase) -> None:
        if phase not in TRANSITIONS[self.phase]:
            raise TransitionError(f"the referee cannot go from {self.phase.value} to {phase.value}")
        self.phase = phase
        self.phase_steps = 0
        self.version += 1

    @property
    def ball_in_play(self) -> bool:
        return self.phase == Phase.PLAY

    @property
    def ended(self) -> bool:
        return self.phase == Phase.ENDED
