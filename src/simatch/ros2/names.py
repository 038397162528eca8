"""The bridge's names on the ROS 2 graph: topics, frames and the node's name (one place, as `bus.topics`).

Per robot, namespaced ``/<team>/robot<id>/`` (as a robot's own stack would be namespaced on a real team), per
team ``/<team>/``, and the world at the root (``/clock``, ``/tf``) or under ``/simatch/``. Frames follow REP 105:
``map`` is the world frame of the field (origin at the centre, +x towards magenta's goal, z up), each robot's
body ``<team>/robot<id>/base_link`` (x forward = the kicker, y left), the ball ``ball``; each team's own frame
(the world turned by pi for a team attacking -x) is ``<team>/field``.
"""

from __future__ import annotations

import re

MAP = "map"
BALL = "ball"

CLOCK = "/clock"
TF = "/tf"
TF_STATIC = "/tf_static"
MARKERS = "/simatch/markers"
MODEL_STATES = "/simatch/model_states"
GAME_STATE = "/simatch/game_state"
EVENTS = "/simatch/events"
SET_MODEL_STATE = "/simatch/set_model_state"

# per robot (relative to /<team>/robot<id>/)
CMD_VEL = "cmd_vel"
DRIBBLE = "dribble"
KICK = "kick"
LOB = "lob"
ACTION_CMD = "action_cmd"
ODOM = "odom"
GROUND_TRUTH = "ground_truth"
BALL_SEEN = "ball"
OBSTACLES = "obstacles"
TEAMMATES = "teammates"
HOLDING_BALL = "holding_ball"
OMNI_VISION = "omni_vision"

# per team (relative to /<team>/)
COACH = "coach"
MATCH_MODE = "match_mode"
MATCH_TYPE = "match_type"

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


def check_team(team: str) -> str:
    """A team name usable as a ROS namespace (letters, digits, '_', starting with a letter)."""
    if not _NAME.match(team):
        raise ValueError(f"team name {team!r} cannot be a ROS 2 namespace (letters, digits and '_' only)")
    return team


def robot_ns(team: str, rid: int) -> str:
    return f"/{team}/robot{int(rid)}"


def robot_topic(team: str, rid: int, leaf: str) -> str:
    return f"{robot_ns(team, rid)}/{leaf}"


def team_topic(team: str, leaf: str) -> str:
    return f"/{team}/{leaf}"


def base_link(team: str, rid: int) -> str:
    return f"{team}/robot{int(rid)}/base_link"


def team_frame(team: str) -> str:
    return f"{team}/field"


#: the bridge's second node, which takes the cmd_vel messages (`graph.RosGraph`): its name is the bridge's and this
COMMANDS_SUFFIX = "_commands"


def node_name(what: str) -> str:
    """The bridge node's name: ``simatch_bridge`` plus what it serves (``cyan``, ``cyan_2``, ``observer``)."""
    return "simatch_bridge_" + re.sub(r"[^A-Za-z0-9_]", "_", what)
