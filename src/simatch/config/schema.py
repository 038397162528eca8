"""What a scene file may contain: every section, key, type, range and default.

A scene is one TOML file. Everything the paper lists as modifiable is here, so that a new world, team
size, robot model, strategy, judge or realism setting needs no code change. Plug-ins (robot models,
strategies, judges) check their own parameters with their own models (see ``simatch.scene.plugins``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, field_validator, model_validator

from ..field import FieldGeometry
from ..worlds import make_world


class Strict(BaseModel):
    """Unknown keys are mistakes, not extensions."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)


Pose = tuple[float, float, float]


class PhysicsSpec(Strict):
    timestep: float = Field(0.005, gt=0.0, le=0.02, description="physics step [s] (paper: 0.005, 200 Hz)")
    gravity: float = Field(9.8, ge=0.0, le=100.0, description="[m/s^2]")
    solver_iterations: int = Field(50, ge=1, le=1000)
    solver_tolerance: float = Field(
        1e-6,
        gt=0.0,
        le=1e-2,
        description="constraint solver tolerance (MuJoCo's default is 1e-8; 1e-6 "
        "gives the same physics within the chaos of a scrum, faster)",
    )


class AreaSpec(Strict):
    name: str = Field(min_length=1)
    x0: float
    y0: float
    x1: float
    y1: float

    @model_validator(mode="after")
    def _ordered(self):
        if not (self.x0 < self.x1 and self.y0 < self.y1):
            raise ValueError("expected x0 < x1 and y0 < y1")
        return self


class ObstacleSpec(Strict):
    """A static obstacle standing on the floor: a box (``size``, turned by ``yaw``) or a cylinder (``radius``)."""

    shape: Literal["box", "cylinder"]
    x: float = Field(description="centre, world frame [m]")
    y: float
    size: tuple[float, float] | None = Field(None, description="a box's length along its own x and y [m]")
    radius: float | None = Field(None, gt=0.0, le=50.0, description="a cylinder's [m]")
    yaw: float = Field(0.0, description="a box's turn about z [rad]")
    height: float = Field(1.0, gt=0.0, le=100.0, description="[m]")
    name: str | None = Field(None, min_length=1, description="default obstacle_<k>")

    @model_validator(mode="after")
    def _shape(self):
        if self.shape == "box":
            if self.size is None or min(self.size) <= 0.0:
                raise ValueError("a box needs size = [length, width], both positive")
            if self.radius is not None:
                raise ValueError("a box has a size, not a radius")
        else:
            if self.radius is None:
                raise ValueError("a cylinder needs a radius")
            if self.size is not None or self.yaw != 0.0:
                raise ValueError("a cylinder has a radius, not a size or a yaw")
        return self


Rect = tuple[float, float, float, float]


class ClutterSpec(Strict):
    """Obstacles scattered at random free places, drawn from ``seed`` (the scene's, not the run's: every
    process and viewer of a run computes the same world)."""

    seed: int = Field(0, ge=0, description="draws sizes, places and turns")
    boxes: int = Field(0, ge=0, le=200)
    cylinders: int = Field(0, ge=0, le=200)
    size: tuple[float, float] = Field((0.6, 1.6), description="range of a box's sides and a cylinder's diameter [m]")
    height: tuple[float, float] = Field((0.5, 1.5), description="range of the heights [m]")
    region: Rect | None = Field(None, description="x0, y0, x1, y1: where centres may fall; default the whole floor")
    gap: float = Field(1.0, ge=0.0, le=20.0, description="least free floor around each obstacle [m]")
    keep_clear: list[Rect] = Field(
        default_factory=list, description="rectangles x0, y0, x1, y1 kept free (e.g. where robots start)"
    )

    @model_validator(mode="after")
    def _ranges(self):
        for what, (lo, hi) in (("size", self.size), ("height", self.height)):
            if not 0.0 < lo <= hi:
                raise ValueError(f"{what}: expected 0 < low <= high, got {[lo, hi]}")
        for what, rect in [("region", self.region)] + [(f"keep_clear[{k}]", r) for k, r in enumerate(self.keep_clear)]:
            if rect is not None and not (rect[0] < rect[2] and rect[1] < rect[3]):
                raise ValueError(f"{what}: expected x0 < x1 and y0 < y1")
        return self


class WorldSpec(Strict):
    kind: str = Field(
        "msl_field", min_length=1, description="the world plug-in: msl_field, arena, or package.module:Class"
    )
    length: float = Field(22.0, gt=1.0, le=200.0, description="between the goal lines [m]")
    width: float = Field(14.0, gt=1.0, le=200.0, description="between the side lines [m]")
    margin: float = Field(1.5, ge=0.0, le=20.0, description="floor beyond the lines [m]")
    line_width: float = Field(0.125, gt=0.0, le=1.0)
    markings: Literal["msl", "none"] = "msl"
    center_circle_radius: float = Field(2.0, ge=0.0)
    goal_area_depth: float = Field(0.75, ge=0.0)
    goal_area_width: float = Field(3.9, ge=0.0)
    penalty_area_depth: float = Field(2.25, ge=0.0)
    penalty_area_width: float = Field(6.9, ge=0.0)
    penalty_spot_distance: float = Field(3.0, ge=0.0)
    corner_arc_radius: float = Field(0.75, ge=0.0)
    goals: bool = True
    goal_width: float = Field(2.4, gt=0.0, le=20.0, description="inner mouth between the posts [m]")
    goal_height: float = Field(1.0, gt=0.0, le=5.0, description="lower edge of the crossbar [m]")
    goal_depth: float = Field(0.6, gt=0.0, le=5.0)
    goal_post_size: float = Field(0.125, gt=0.0, le=1.0)
    walls: bool = True
    wall_height: float = Field(0.5, gt=0.0, le=5.0)
    areas: list[AreaSpec] = Field(default_factory=list, description="named zones (a prison, a base), world frame")
    obstacles: list[ObstacleSpec] = Field(default_factory=list, description="static obstacles at given poses")
    clutter: ClutterSpec | None = Field(None, description="static obstacles scattered from a seed")
    ceiling: float | None = Field(None, gt=0.5, le=100.0, description="height of a ceiling [m]; none: open sky")
    params: dict[str, Any] = Field(default_factory=dict, description="a world plug-in's own settings")
    _geometry: tuple[str, FieldGeometry] | None = PrivateAttr(None)

    @model_validator(mode="after")
    def _fits(self):
        if self.kind != "msl_field":
            return self  # the soccer sizes are the MSL field's (another kind refuses or ignores them)
        if self.goals and self.goal_width >= self.width:
            raise ValueError("goal_width must be smaller than the field width")
        if self.penalty_area_depth > self.length / 2 or self.penalty_area_width > self.width:
            raise ValueError("the penalty area must fit in a half of the field")
        return self

    def geometry(self) -> FieldGeometry:
        """The world's description (`FieldGeometry`), made by the world plug-in of ``kind``; computed once
        per setting (a scattered clutter is drawn once). Raises `WorldError` or `PluginError` for a world
        that cannot be made (the loader checks every scene for that first, `check_world`)."""
        key = self.model_dump_json()
        if self._geometry is None or self._geometry[0] != key:
            self._geometry = (key, make_world(self).geometry())
        return self._geometry[1]


class BallSpec(Strict):
    radius: float = Field(0.11, gt=0.01, le=1.0, description="[m]")
    mass: float = Field(0.43, gt=0.01, le=10.0, description="[kg]")
    rolling_deceleration: float = Field(
        0.5, ge=0.0, le=20.0, description="deceleration of a freely rolling ball [m/s^2]"
    )
    restitution: float = Field(0.6, ge=0.0, le=0.95, description="bounce on the floor: rebound/impact speed")
    friction: float = Field(0.6, ge=0.0, le=2.0, description="sliding friction against floor and robots")
    position: tuple[float, float] = (0.0, 0.0)


class SquadSpec(Strict):
    """More robots of a team, of another model (drones beside wheeled robots): one team, one strategy, one
    picture of the game, robots of several kinds."""

    model: str = Field(min_length=1, description="robot model: a shipped name or package.module:Class")
    model_params: dict[str, Any] = Field(default_factory=dict)
    ids: list[int] | None = Field(None, description="robot ids; default: after the team's ids before them")
    start: list[Pose] = Field(
        min_length=1, max_length=32, description="one start pose [x, y, yaw] per robot, world frame [m, rad]"
    )

    @model_validator(mode="after")
    def _ids(self):
        if self.ids is not None and len(self.ids) != len(self.start):
            raise ValueError(f"ids has {len(self.ids)} entries but start has {len(self.start)}")
        return self


@dataclass(frozen=True)
class Member:
    """One robot of a team as the scene gives it: its id, model and start pose."""

    id: int
    model: str
    model_params: dict
    start: Pose
    squad: int  # -1: the team's own robots (teams.<team>.start), else its index in teams.<team>.squads


class TeamSpec(Strict):
    color: str | None = Field(None, description="display colour; defaults to the team's name")
    attacks: Literal["+x", "-x"] | None = Field(
        None, description="direction of this team's team frame +x; default +x, except magenta -x"
    )
    model: str = Field("omni4", min_length=1, description="robot model: a shipped name or package.module:Class")
    model_params: dict[str, Any] = Field(default_factory=dict)
    strategy: str = Field(
        "none", min_length=1, description="a shipped strategy name, package.module:Class, or 'external'"
    )
    strategy_params: dict[str, Any] = Field(default_factory=dict)
    goalkeeper: int | None = Field(1, ge=1, description="id of the goalkeeper, if any")
    ids: list[int] | None = Field(None, description="robot ids; default 1..n in the order of start")
    ros_prefix: str | None = Field(
        None,
        pattern=r"^[A-Za-z][A-Za-z0-9_]*$",
        description="its robots' names on ROS are <ros_prefix><id>; default NuBot for cyan, rival for "
        "magenta (the original's), else the team's name",
    )
    learners: list[int] = Field(
        default_factory=list,
        description="ids of the robots handed to learning (they play what a learning environment decides, "
        "see docs/learning.md); the others play `strategy`. strategy = 'learner' hands over the whole team",
    )
    start: list[Pose] = Field(
        min_length=1, max_length=32, description="one start pose [x, y, yaw] per robot, world frame [m, rad]"
    )
    squads: list[SquadSpec] = Field(
        default_factory=list, max_length=8, description="more robots of other models (e.g. drones), same team"
    )

    @model_validator(mode="after")
    def _ids(self):
        if self.ids is not None and len(self.ids) != len(self.start):
            raise ValueError(f"ids has {len(self.ids)} entries but start has {len(self.start)}")
        ids = [m.id for m in self.members()]
        if len(set(ids)) != len(ids) or min(ids) < 1:
            raise ValueError("ids must be distinct positive integers (over the team and its squads)")
        if len(ids) > 64:
            raise ValueError(f"a team has at most 64 robots, this one {len(ids)}")
        unknown = sorted(set(self.learners) - set(ids))
        if unknown:
            raise ValueError(f"learners: the team has no robot(s) {unknown}; its robots are {ids}")
        if self.learners and self.strategy == "external":
            raise ValueError("learners: an 'external' team plays in its own process; its robots cannot learn here")
        return self

    def learner_ids(self) -> list[int]:
        """The robots of this team handed to learning, in the team's order."""
        every = self.strategy == "learner"
        return [rid for rid in self.robot_ids() if every or rid in self.learners]

    def members(self) -> list[Member]:
        """Every robot of the team, its own robots first, then each squad's, in the scene's order."""
        ids = list(self.ids) if self.ids is not None else list(range(1, len(self.start) + 1))
        out = [Member(rid, self.model, self.model_params, tuple(p), -1) for rid, p in zip(ids, self.start)]
        for k, squad in enumerate(self.squads):
            after = max((m.id for m in out), default=0)
            sids = list(squad.ids) if squad.ids is not None else list(range(after + 1, after + 1 + len(squad.start)))
            out += [Member(rid, squad.model, squad.model_params, tuple(p), k) for rid, p in zip(sids, squad.start)]
        return out

    def robot_ids(self) -> list[int]:
        return [m.id for m in self.members()]

    def starts(self) -> list[Pose]:
        """Every robot's start pose, in the order of `robot_ids`."""
        return [m.start for m in self.members()]


class ControlSpec(Strict):
    period: float = Field(0.025, gt=0.0, le=1.0, description="robot control period [s]")
    command_timeout: float = Field(
        0.1, gt=0.0, le=10.0, description="a robot with no fresh command for this long is stopped [s]"
    )
    strategy_pub_period: float | None = Field(
        None, gt=0.0, le=1.0, description="StrategyPub period [s]; default: the control period"
    )
    strategy_stale_after: float = Field(
        0.1, gt=0.0, le=10.0, description="StrategyPub drops entries older than this [s]"
    )


class DribblerSpec(Strict):
    distance: float = Field(0.40, gt=0.0, le=2.0, description="max robot-centre to ball-centre distance [m]")
    angle: float = Field(10.0, gt=0.0, le=90.0, description="max bearing of the ball off the kicker axis [deg]")
    grip_force: float = Field(
        15.0, gt=0.0, le=1000.0, description="largest force the dribbler can exert on the ball before losing it [N]"
    )
    pull_speed: float = Field(1.0, gt=0.0, le=10.0, description="speed at which the rollers draw the ball in [m/s]")
    catch_speed: float = Field(
        3.5, gt=0.0, le=30.0, description="fastest ball (relative to the mouth) the rollers can take [m/s]"
    )
    settle_time: float = Field(
        0.1, ge=0.0, le=2.0, description="after taking the ball, time before the grip limit applies [s]"
    )
    roller_torque: float = Field(
        1.0,
        ge=0.0,
        le=100.0,
        description="largest torque the rollers put on a held ball to keep it turning [N m] (0: no rollers, "
        "the ball turns only as the floor makes it)",
    )
    roller_spin: float = Field(
        1.0,
        ge=-2.0,
        le=2.0,
        description="the spin the rollers keep a held ball at, as a fraction of rolling with its motion over the "
        "floor: 1 turns it as a free ball rolls (its natural rotation, MSL RC-12.3.1), 0 clamps it without "
        "turning (against its rotation: a foul), below 0 turns it against its motion",
    )


class KickerSpec(Strict):
    max_speed: float = Field(10.0, gt=0.0, le=30.0, description="ground kick speed limit [m/s]")
    max_lob_speed: float = Field(10.0, gt=0.0, le=30.0, description="lob launch speed limit [m/s]")
    lob_angle: float = Field(37.0, gt=0.0, lt=90.0, description="lob launch angle above the floor [deg]")
    recharge: float = Field(0.5, ge=0.0, le=10.0, description="time before the kicker can fire again [s]")


class PerceptionSpec(Strict):
    position_noise: float = Field(0.0, ge=0.0, le=5.0, description="std of Gaussian position noise [m]")
    velocity_noise: float = Field(0.0, ge=0.0, le=10.0, description="std of Gaussian velocity noise [m/s]")
    heading_noise: float = Field(0.0, ge=0.0, le=3.2, description="std of Gaussian heading noise [rad]")
    ball_dropout: float = Field(0.0, ge=0.0, le=1.0, description="probability that the ball is not seen")
    obstacle_dropout: float = Field(0.0, ge=0.0, le=1.0, description="probability that an obstacle is missed")
    latency: float = Field(0.0, ge=0.0, le=2.0, description="delay of every observation [s]")
    line_of_sight: bool = Field(
        False, description="ground robots see only what no obstacle hides (3D sight line from the top of the robot)"
    )
    camera_footprint: bool = Field(
        False, description="aerial robots see only what lies within their downward camera's cone below them"
    )
    ground_range: float | None = Field(
        None, gt=0.0, le=1000.0, description="ground robots see nothing farther than this [m]; none: no limit"
    )


class JudgeSpec(BaseModel):
    """``kind`` picks the judge; its other keys are the judge's own settings, checked by the judge."""

    model_config = ConfigDict(extra="allow")
    kind: str = Field("none", min_length=1)


class MatchSpec(Strict):
    halves: int = Field(2, ge=1, le=4)
    half_duration: float = Field(900.0, gt=0.0, le=86400.0, description="[s] (MSL: 15 min)")
    half_time: float = Field(10.0, ge=0.0, le=3600.0, description="break between halves [s]")
    kickoff: str = Field("cyan", description="team that kicks off the first half")
    penalty_shootout: bool = Field(False, description="a shoot-out decides a draw")
    change_ends: bool = Field(
        True,
        description="the teams change ends at half time, and again before extra time and a shoot-out "
        "(every team frame, start pose and side the referee judges follows)",
    )
    start: Literal[
        "kickoff", "play", "throw_in", "goal_kick", "corner_kick", "free_kick", "penalty", "dropped_ball"
    ] = Field(
        "kickoff",
        description="how the referee begins the match: the kick-off, the ball in play at once, or a restart "
        "(to look at a situation again: scripts/referee_audit.py writes such scenes)",
    )
    start_team: str | None = Field(None, description="the team whose restart `start` is (default: kickoff)")
    start_spot: tuple[float, float] | None = Field(
        None, description="the spot of the `start` restart, world frame [m] (default: where the ball starts)"
    )


class LearningSpec(Strict):
    """How a scene is used for learning (`simatch.envs`): rewards, what ends an episode, how long one lasts.
    A run that is not a learning environment ignores it."""

    rewards: dict[str, float | dict[str, Any]] = Field(
        default_factory=dict,
        description="reward terms: a shipped term name or package.module:Class -> its weight, or a table "
        "{weight = ..., other settings of the term} (docs/learning.md lists the terms)",
    )
    end_on: list[str] = Field(
        default_factory=list,
        description="event types that end an episode (terminated), besides the judge ending the run, "
        "e.g. ['goal', 'ball_out']",
    )
    episode_time: float | None = Field(
        None, gt=0.0, le=86400.0, description="an episode is cut (truncated) after this long [s]; none: the run's"
    )


class Scene(Strict):
    name: str = Field(min_length=1)
    description: str = ""
    duration: float | None = Field(None, gt=0.0, description="default run length [s] if the judge sets none")
    physics: PhysicsSpec = Field(default_factory=PhysicsSpec)
    world: WorldSpec = Field(default_factory=WorldSpec)
    ball: BallSpec = Field(default_factory=BallSpec)
    teams: dict[str, TeamSpec] = Field(min_length=1)
    control: ControlSpec = Field(default_factory=ControlSpec)
    dribbler: DribblerSpec = Field(default_factory=DribblerSpec)
    kicker: KickerSpec = Field(default_factory=KickerSpec)
    perception: PerceptionSpec = Field(default_factory=PerceptionSpec)
    judge: JudgeSpec = Field(default_factory=JudgeSpec)
    match: MatchSpec = Field(default_factory=MatchSpec)
    learning: LearningSpec = Field(default_factory=LearningSpec)

    @field_validator("teams")
    @classmethod
    def _team_names(cls, teams: dict[str, TeamSpec]):
        for name in teams:
            if not name.isidentifier() or name != name.lower():
                raise ValueError(f"team name {name!r} must be a lower-case identifier (e.g. cyan)")
        return teams

    @model_validator(mode="after")
    def _consistent(self):
        dt = self.physics.timestep
        for what, value in (
            ("control.period", self.control.period),
            ("control.strategy_pub_period", self.control.strategy_pub_period),
        ):
            if value is not None:
                n = round(value / dt)
                if n < 1 or abs(n * dt - value) > 1e-9:
                    raise ValueError(f"{what} ({value} s) must be a whole number of physics steps ({dt} s)")
        if self.control.strategy_pub_period is not None:
            ratio = self.control.strategy_pub_period / self.control.period
            if abs(ratio - round(ratio)) > 1e-9:
                raise ValueError("control.strategy_pub_period must be a multiple of control.period")
        if self.match.kickoff not in self.teams:
            raise ValueError(f"match.kickoff names team {self.match.kickoff!r}, which the scene does not have")
        if self.match.start_team is not None and self.match.start_team not in self.teams:
            raise ValueError(f"match.start_team names team {self.match.start_team!r}, which the scene does not have")
        return self

    # --- derived --------------------------------------------------------------------------------------
    def team_sign(self, team: str) -> int:
        """+1 if the team's frame is the world frame, -1 if it is the world turned by pi (magenta)."""
        spec = self.teams[team]
        attacks = spec.attacks or ("-x" if team == "magenta" else "+x")
        return 1 if attacks == "+x" else -1

    def team_color(self, team: str) -> str:
        return self.teams[team].color or team

    def robot_names(self) -> list[str]:
        return [f"{team}/{rid}" for team, spec in self.teams.items() for rid in spec.robot_ids()]

    def member(self, name: str) -> Member | None:
        """The robot ``team/id`` as the scene gives it (its model and start), or None if there is none."""
        team, _, rid = name.partition("/")
        spec = self.teams.get(team)
        return next((m for m in spec.members() if str(m.id) == rid), None) if spec is not None else None

    def learner_names(self) -> list[str]:
        """The robots handed to learning (``teams.<team>.learners`` or ``strategy = 'learner'``)."""
        return [f"{team}/{rid}" for team, spec in self.teams.items() for rid in spec.learner_ids()]

    @property
    def strategy_pub_period(self) -> float:
        return self.control.strategy_pub_period or self.control.period

    @property
    def lob_angle_rad(self) -> float:
        return math.radians(self.kicker.lob_angle)
