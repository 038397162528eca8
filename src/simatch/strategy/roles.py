"""Roles and actions a robot announces in its StrategyInfo (``role``, ``action``), with the original
NuBot numbering, so that coaches, viewers and recordings can name what a robot is doing whatever
strategy it runs. A strategy may use its own numbers above the ones listed here."""

from __future__ import annotations

import enum
import types


class Role(enum.IntEnum):
    GOALIE = 0
    ACTIVE = 1  # has the ball or goes for it
    PASSIVE = 2  # defends between the ball and its own goal
    MIDFIELD = 3  # marks an opponent, or supports behind the attack
    ASSISTANT = 4  # offers itself for a pass
    ACIDPASSIVE = 5
    GAZER = 6
    BLOCK = 7
    NOROLE = 8
    CATCHOFPASS = 9  # receives a pass under way
    PASSOFPASS = 10  # has just passed


class Action(enum.IntEnum):
    STUCKED = 0
    PENALTY = 1
    CAN_NOT_SEE_BALL = 2
    SEE_NOT_DRIBBLE_BALL = 3
    TURN_FOR_SHOOT = 4
    TURN_FOR_SHOOT_ROBOT = 5
    AT_SHOOT_SITUATION = 6
    TURN_TO_PASS = 7
    TURN_TO_PASS_ROBOT = 8
    STATIC_PASS = 9
    AVOID_OBS = 10
    CATCH_POSITIONED = 11
    POSITIONED = 12
    POSITIONED_STATIC = 13
    KICK_COOP = 14
    KICK_COOP_TURN = 15
    CATCH_BALL = 16
    CATCH_BALL_SLOW = 17
    CIRCLE_TEST = 18
    MOVE_WITH_BALL = 19
    TELEOP_JOY = 20
    NO_ACTION = 21


def role_name(value: int) -> str:
    try:
        return Role(value).name
    except ValueError:
        return f"ROLE_{value}"


def action_name(value: int) -> str:
    try:
        return Action(value).name
    except ValueError:
        return f"ACTION_{value}"


#: what each role means, in words a coach reads on the page (`role_words`)
ROLE_WORDS = {
    Role.GOALIE: "goalkeeper",
    Role.ACTIVE: "on the ball",
    Role.PASSIVE: "defend",
    Role.MIDFIELD: "midfield",
    Role.ASSISTANT: "offer a pass",
    Role.ACIDPASSIVE: "second defender",
    Role.GAZER: "watch the ball",
    Role.BLOCK: "block",
    Role.NOROLE: "",  # nothing to say: the pages leave the robot unlabelled, the tables show a dash
    Role.CATCHOFPASS: "catch the pass",
    Role.PASSOFPASS: "just passed",
}
#: what each action means, in words (`action_words`)
ACTION_WORDS = {
    Action.STUCKED: "stuck",
    Action.PENALTY: "penalty",
    Action.CAN_NOT_SEE_BALL: "look for the ball",
    Action.SEE_NOT_DRIBBLE_BALL: "sees the ball",
    Action.TURN_FOR_SHOOT: "turn to shoot",
    Action.TURN_FOR_SHOOT_ROBOT: "turn to shoot",
    Action.AT_SHOOT_SITUATION: "shoot",
    Action.TURN_TO_PASS: "turn to pass",
    Action.TURN_TO_PASS_ROBOT: "turn to pass",
    Action.STATIC_PASS: "set-piece pass",
    Action.AVOID_OBS: "avoid an obstacle",
    Action.CATCH_POSITIONED: "wait for the pass",
    Action.POSITIONED: "in position",
    Action.POSITIONED_STATIC: "in set-piece position",
    Action.KICK_COOP: "pass",
    Action.KICK_COOP_TURN: "turn to pass",
    Action.CATCH_BALL: "take the ball",
    Action.CATCH_BALL_SLOW: "take the ball gently",
    Action.CIRCLE_TEST: "circle test",
    Action.MOVE_WITH_BALL: "dribble",
    Action.TELEOP_JOY: "driven by hand",
    Action.NO_ACTION: "",
}


def role_words(value: int) -> str:
    """The role in words ("catch the pass"; "" for none); a strategy's own number as "role 42"."""
    try:
        return ROLE_WORDS[Role(value)]
    except ValueError:
        return f"role {value}"


def action_words(value: int) -> str:
    """The action in words ("take the ball"; "" for none); a strategy's own number as "action 42"."""
    try:
        return ACTION_WORDS[Action(value)]
    except ValueError:
        return f"action {value}"


def members(enum_cls: type[enum.Enum]) -> types.SimpleNamespace:
    """The members of an Enum class as plain attributes (``members(Role).ACTIVE is Role.ACTIVE``), for code
    that runs for every robot and tick (an Enum class's attributes are looked up through its metaclass's
    ``__getattr__``)."""
    return types.SimpleNamespace(**enum_cls.__members__)


#: `Role` and `Action` members as plain attributes (`members`), for the hot paths of strategies
ROLES = members(Role)
ACTIONS = members(Action)
