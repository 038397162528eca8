"""Game commands: the scene interface's vocabulary (paper section VI-B, original numbering).

A command is always expressed from one team's point of view: a kick-off for cyan is OUR_KICKOFF to cyan
and OPP_KICKOFF to magenta. `for_team` turns a command given for one team into what another team hears.
"""

from __future__ import annotations

import enum


class MatchMode(enum.IntEnum):
    STOPROBOT = 0
    OUR_KICKOFF = 1
    OPP_KICKOFF = 2
    OUR_THROWIN = 3
    OPP_THROWIN = 4
    OUR_PENALTY = 5
    OPP_PENALTY = 6
    OUR_GOALKICK = 7
    OPP_GOALKICK = 8
    OUR_CORNERKICK = 9
    OPP_CORNERKICK = 10
    OUR_FREEKICK = 11
    OPP_FREEKICK = 12
    DROPBALL = 13
    STARTROBOT = 15
    PARKINGROBOT = 25
    TEST = 27


class TestMode(enum.IntEnum):
    """CoachInfo.test_mode when match_mode is TEST (the original coach's test tab)."""

    TEST_STOP = 0
    PASS_BALL = 2
    CATCH_BALL = 3
    SHOOT_BALL = 4
    LOCATION_TEST = 5
    CIRCLE_TEST = 6
    MOVE_NOBALL_NOAVOID = 10
    MOVE_NOBALL_AVOID = 11
    MOVE_BALL_NOAVOID = 12
    MOVE_BALL_AVOID = 13


#: set pieces: OUR_x and OPP_x pairs (and the dropped ball, which belongs to nobody)
SET_PIECES = frozenset(range(1, 14))
NEUTRAL = frozenset(
    {MatchMode.STOPROBOT, MatchMode.DROPBALL, MatchMode.STARTROBOT, MatchMode.PARKINGROBOT, MatchMode.TEST}
)


def is_ours(cmd: int) -> bool:
    """An OUR_x set piece (odd numbers 1..11)."""
    return 1 <= cmd <= 12 and cmd % 2 == 1


def mirror(cmd: int) -> MatchMode:
    """The same command heard by the other team: OUR_x <-> OPP_x; neutral commands unchanged."""
    cmd = MatchMode(cmd)
    if 1 <= cmd <= 12:
        return MatchMode(cmd + 1 if cmd % 2 == 1 else cmd - 1)
    return cmd


def for_team(cmd: int, given_to: str, team: str) -> MatchMode:
    """Command ``cmd`` given from ``given_to``'s point of view, as ``team`` hears it."""
    return MatchMode(cmd) if team == given_to else mirror(cmd)


def name(cmd: int) -> str:
    try:
        return MatchMode(cmd).name
    except ValueError:
        return f"UNKNOWN_{cmd}"


#: set pieces by restart kind: the OUR_x command of the team that takes it (the dropped ball is neutral)
RESTART_COMMANDS = {
    "kickoff": MatchMode.OUR_KICKOFF,
    "throw_in": MatchMode.OUR_THROWIN,
    "penalty": MatchMode.OUR_PENALTY,
    "goal_kick": MatchMode.OUR_GOALKICK,
    "corner_kick": MatchMode.OUR_CORNERKICK,
    "free_kick": MatchMode.OUR_FREEKICK,
    "dropped_ball": MatchMode.DROPBALL,
}
RESTART_OF_COMMAND = {int(cmd): kind for kind, cmd in RESTART_COMMANDS.items()}

#: words a person may type for a command (the CLI coach, the operator console), besides the enum names
ALIASES = {
    "stop": MatchMode.STOPROBOT,
    "start": MatchMode.STARTROBOT,
    "park": MatchMode.PARKINGROBOT,
    "parking": MatchMode.PARKINGROBOT,
    "test": MatchMode.TEST,
    "dropball": MatchMode.DROPBALL,
    "drop": MatchMode.DROPBALL,
    "dropped_ball": MatchMode.DROPBALL,
    "kickoff": MatchMode.OUR_KICKOFF,
    "throwin": MatchMode.OUR_THROWIN,
    "throw_in": MatchMode.OUR_THROWIN,
    "penalty": MatchMode.OUR_PENALTY,
    "goalkick": MatchMode.OUR_GOALKICK,
    "goal_kick": MatchMode.OUR_GOALKICK,
    "corner": MatchMode.OUR_CORNERKICK,
    "cornerkick": MatchMode.OUR_CORNERKICK,
    "corner_kick": MatchMode.OUR_CORNERKICK,
    "freekick": MatchMode.OUR_FREEKICK,
    "free_kick": MatchMode.OUR_FREEKICK,
}


def restart_kind(cmd: int) -> str | None:
    """``"free_kick"`` for OUR_FREEKICK and OPP_FREEKICK, ``"dropped_ball"`` for DROPBALL, None otherwise."""
    cmd = int(cmd)
    if 1 <= cmd <= 12:
        return RESTART_OF_COMMAND[cmd if cmd % 2 == 1 else cmd - 1]
    return RESTART_OF_COMMAND.get(cmd)


def parse(words: str | list[str]) -> MatchMode:
    """A command from what a person types: a number (``11``), an enum name (``OUR_FREEKICK``), or an alias
    with an optional ``opp``/``our`` (``freekick``, ``opp corner``, ``corner opp``). ValueError if unknown."""
    parts = words.split() if isinstance(words, str) else list(words)
    low = [p.lower() for p in parts]
    side = "our"
    for s in ("opp", "our"):
        if s in low:
            side = s
            low.remove(s)
    if len(low) != 1:
        raise ValueError(f"expected one command, got {' '.join(parts)!r}")
    word = low[0]
    if word.isdigit():
        try:
            cmd = MatchMode(int(word))
        except ValueError:
            raise ValueError(f"no game command numbered {word}") from None
    elif word.upper() in MatchMode.__members__:
        cmd = MatchMode[word.upper()]
    elif word in ALIASES:
        cmd = ALIASES[word]
    else:
        known = ", ".join(sorted(ALIASES))
        raise ValueError(f"unknown game command {word!r} (a number, a name like OUR_FREEKICK, or one of: {known})")
    if side == "opp":
        if not 1 <= cmd <= 12:
            raise ValueError(f"{cmd.name} belongs to no team: 'opp' does not apply")
        if is_ours(cmd):
            cmd = mirror(cmd)
    return cmd
