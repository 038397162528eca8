"""Topic names, in one place (names from the paper and the original system).

A topic is relative to a run; a transport turns it into a key expression ``simatch/<run>/<topic>``, e.g.
``simatch/match1/cyan/2/VelCmd``. Robots are ``<team>/<id>``.
"""

from __future__ import annotations

PREFIX = "simatch"

# per robot
VEL_CMD = "VelCmd"
ACTION_CMD = "ActionCmd"
OMNI_VISION = "OmniVisionInfo"
STRATEGY_INFO = "StrategyInfo"

# per team
TEAM_STRATEGY = "TeamStrategy"
RECEIVE_FROM_COACH = "receive_from_coach"

# world
CLOCK = "clock"
MODEL_STATES = "model_states"
STATE_FINGERPRINT = "state_fingerprint"  # the exact states' identity at every control tick (when listened to)
COMPONENT_FINGERPRINTS = "component_fingerprints"  # each step's per-component fingerprints (when listened to)
LINK_STATES = "link_states"
SET_MODEL_STATE = "set_model_state"
SET_LINK_STATE = "set_link_state"
APPLY_WRENCH = "apply_wrench"
BALL_CONTACTS = "ball_contacts"
WORLD_INPUTS = "world_inputs"  # WorldInputs: what entered the world from outside the simulator (when listened to)

# scene
GAME_STATE = "game_state"
EVENTS = "events"
OPERATOR = "operator"  # OperatorCommand: interventions from outside the run's nodes (API, operators)
REFEREE_COMMAND = "referee_command"


def robot_name(team: str, rid: int) -> str:
    return f"{team}/{rid}"


def split_robot_name(name: str) -> tuple[str, int]:
    """``"cyan/2"`` -> ``("cyan", 2)``; ValueError for anything else."""
    team, sep, rid = name.partition("/")
    if not sep or not team or not rid.isdigit():
        raise ValueError(f"not a robot name: {name!r} (expected TEAM/ID, e.g. cyan/2)")
    return team, int(rid)


def robot_topic(team: str, rid: int, leaf: str) -> str:
    return f"{team}/{rid}/{leaf}"


def team_topic(team: str, leaf: str) -> str:
    return f"{team}/{leaf}"


def key(run: str, topic: str) -> str:
    """The full key expression of a topic in a run."""
    return f"{PREFIX}/{run}/{topic}"


def matches(pattern: str, topic: str) -> bool:
    """Zenoh-style key-expression match: ``*`` is one chunk, ``**`` any number of chunks (also none)."""
    return _match(pattern.split("/"), topic.split("/"))


def _match(p: list[str], t: list[str]) -> bool:
    if not p:
        return not t
    head = p[0]
    if head == "**":
        return any(_match(p[1:], t[i:]) for i in range(len(t) + 1))
    if not t:
        return False
    if head == "*" or head == t[0]:
        return _match(p[1:], t[1:])
    return False
