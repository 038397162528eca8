"""The original's names on ROS: robots ``<prefix><id>`` (``NuBot3``, ``rival2``), teams by their prefix,
the ball ``football``, and the topics of the original interface (simatch-original.md 2.3)."""

from __future__ import annotations

from dataclasses import dataclass

from ..config.schema import Scene

#: the original's default prefixes (its global_config.yaml); any other team is named after itself
DEFAULT_PREFIX = {"cyan": "NuBot", "magenta": "rival"}
#: the ball's model name in the original's Gazebo world
BALL = "football"
SIMATCH_BALL = "ball"

# per robot <r>
OMNIVISION = "omnivision/OmniVisionInfo"
BALL_IS_HOLDING = "ballisholding/BallIsHolding"
VELCMD = "nubotcontrol/velcmd"
ACTIONCMD = "nubotcontrol/actioncmd"
STRATEGY = "nubotcontrol/strategy"  # StrategyInfo per robot; simulation_strategy per team <p>
# per team <p>
COACH = "receive_from_coach"
REDCARD = "redcard/chatter"
# the world
MODEL_STATES = "/gazebo/model_states"
SET_MODEL_STATE = "/gazebo/set_model_state"
CLOCK = "/clock"


def prefix_of(spec: Scene, team: str) -> str:
    """The team's prefix on ROS: the scene's ``teams.<team>.ros_prefix``, else the original's default."""
    return spec.teams[team].ros_prefix or DEFAULT_PREFIX.get(team, team)


@dataclass(frozen=True)
class Robot:
    team: str
    rid: int
    prefix: str
    index: int  # in the scene's order (both teams)

    @property
    def name(self) -> str:
        """The simatch name, ``cyan/3``."""
        return f"{self.team}/{self.rid}"

    @property
    def ros(self) -> str:
        """The ROS name, ``NuBot3``."""
        return f"{self.prefix}{self.rid}"

    def topic(self, leaf: str) -> str:
        return f"/{self.ros}/{leaf}"


class Names:
    """Every robot of a scene under both its names."""

    def __init__(self, spec: Scene):
        self.prefixes = {team: prefix_of(spec, team) for team in spec.teams}
        if len(set(self.prefixes.values())) != len(self.prefixes):
            raise ValueError(f"two teams have the same ROS prefix: {self.prefixes} (set teams.<team>.ros_prefix)")
        self.robots: list[Robot] = []
        for team, tspec in spec.teams.items():
            for rid in tspec.robot_ids():
                self.robots.append(Robot(team, rid, self.prefixes[team], len(self.robots)))
        self.by_name = {r.name: r for r in self.robots}
        self.by_ros = {r.ros: r for r in self.robots}
        if len(self.by_ros) != len(self.robots):
            raise ValueError("two robots have the same ROS name: give the teams distinct ros_prefix settings")
        self.teams = list(spec.teams)

    def team_robots(self, team: str) -> list[Robot]:
        return [r for r in self.robots if r.team == team]

    def team_topic(self, team: str, leaf: str) -> str:
        return f"/{self.prefixes[team]}/{leaf}"

    def model_to_ros(self, name: str) -> str:
        if name == SIMATCH_BALL:
            return BALL
        robot = self.by_name.get(name)
        return robot.ros if robot is not None else name

    def model_from_ros(self, name: str) -> str | None:
        """The simatch model of a ROS model name (``football`` -> ``ball``; ``NuBot3`` -> ``cyan/3``), None
        if there is none."""
        if name in (BALL, SIMATCH_BALL):
            return SIMATCH_BALL
        robot = self.by_ros.get(name)
        if robot is not None:
            return robot.name
        return name if name in self.by_name else None
