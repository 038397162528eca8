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
NEUTRAL = frozenset({MatchMode.STOPROBOT, MatchMode.DROPBALL, MatchMode.STARTROBOT, MatchMode.PARKINGROBOT,
                     MatchMode.TEST})


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
