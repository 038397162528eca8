"""The strategy plug-in API: what a team writes to play in simatch.

A strategy is named in the scene as ``teams.<team>.strategy = "package.module:Class"`` (or a shipped
name). ``Class`` is either

* a `RobotStrategy` subclass: one instance per robot (the robot's Control), all of the same class; or
* a `TeamStrategy` subclass: one instance per team, which makes each robot's `RobotStrategy`
  (e.g. a different class for the goalkeeper).

Every control period, each robot's `RobotStrategy.decide` gets the robot's `WorldModel` and returns a
`Command`: a body-frame velocity, or a target pose for the robot's low-level controller, plus the
dribbler, the kicker and what the robot tells its team (role, action, pass). A strategy sees the world
only through its robot's topics, so the same class runs embedded or in its own process over Zenoh.

Parameters: a class may declare ``Params`` (a pydantic model); ``teams.<team>.strategy_params`` is
checked against it and handed over as ``ctx.params``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from pydantic import BaseModel

from ..field import FieldGeometry
from ..robots import model_class
from .roles import Action, Role
from .worldmodel import WorldModel

_new = object.__new__


@dataclass
class PassIntent:
    catch_id: int
    pass_x: float
    pass_y: float
    catch_x: float
    catch_y: float
    kicked: bool = False
    dynamic: bool = True
    static: bool = False


@dataclass
class Command:
    """One robot's decision for one control period.

    Motion: if ``target`` is None the robot drives at the body-frame velocity (vx, vy, w); otherwise its
    low-level controller drives it to ``target`` (team frame) and turns it to ``target_ori`` (if given),
    within ``max_vel`` and ``max_w``. An aerial robot also climbs at ``vz`` (upward, m/s), or, if
    ``altitude`` is given, its low-level controller takes it to that height within ``max_vz``; ground
    robots ignore both.
    """

    vx: float = 0.0
    vy: float = 0.0
    w: float = 0.0
    target: tuple[float, float] | None = None
    target_ori: float | None = None
    target_vel: tuple[float, float] = (0.0, 0.0)
    max_vel: float = 3.0
    max_w: float = 6.0
    dribble: bool = False
    kick_speed: float = 0.0
    lob: bool = False
    # what the robot tells its team (StrategyInfo)
    role: int = Role.NOROLE  # a robot says which role it plays; none said is none (0 would be the goalie)
    action: int = Action.NO_ACTION  # likewise: none said is none (0 would be STUCKED)
    intent: tuple[float, float] | None = None
    pass_intent: PassIntent | None = None
    target_num: tuple[int, ...] = ()
    user: tuple[float, ...] = ()
    # aerial robots (appended: positional constructions of the fields above keep their meaning)
    vz: float = 0.0
    altitude: float | None = None
    max_vz: float = 1.0

    # (every field has a plain default: the dataclass keeps it as a class attribute, which `move` relies on)

    @classmethod
    def stop(cls, **info: Any) -> Command:
        return cls(**info)

    @classmethod
    def move(
        cls,
        vx: float,
        vy: float,
        w: float,
        role: int,
        action: int,
        intent: tuple[float, float] | None,
        user: tuple = (),
    ) -> Command:
        """``Command(vx=vx, vy=vy, w=w, role=role, action=action, intent=intent, user=user)``: a body-frame
        velocity with what the robot tells its team, every other field at its default. Made without the
        dataclass's ``__init__`` (which writes every field), for strategies that move every robot at every
        control tick."""
        move = _new(cls)
        move.vx, move.vy, move.w = vx, vy, w
        move.role, move.action, move.intent, move.user = role, action, intent, user
        return move


@dataclass
class RobotContext:
    """What a robot's strategy is given when it is created."""

    team: str
    id: int
    goalkeeper: int | None
    ids: list[int]  # every robot id of the team
    field: FieldGeometry  # in the team frame
    start: tuple[float, float, float]  # start pose, team frame
    control_period: float  # [s]
    params: Any  # validated strategy_params (a pydantic model or a dict)
    rng: np.random.Generator = field(repr=False, default_factory=np.random.default_rng)
    model: str = "omni4"  # the robot's model (teams.<team>.model, or its squad's)
    models: dict[int, str] = field(default_factory=dict)  # every robot of the team: id -> model

    @property
    def is_goalkeeper(self) -> bool:
        return self.goalkeeper is not None and self.id == self.goalkeeper

    @property
    def aerial(self) -> bool:
        """The robot flies (its model's locomotion is aerial)."""
        return is_aerial(self.model)


@dataclass
class TeamContext:
    team: str
    ids: list[int]
    goalkeeper: int | None
    field: FieldGeometry
    starts: dict[int, tuple[float, float, float]]
    control_period: float
    params: Any
    models: dict[int, str] = field(default_factory=dict)  # id -> robot model (teams with squads mix models)


def is_aerial(model: str) -> bool:
    """Whether robots of ``model`` (a robot model's name or plug-in path) fly."""
    return model_class(model).locomotion == "aerial"


class RobotStrategy:
    """The Control of one robot. Override `decide`."""

    Params: ClassVar[type[BaseModel] | None] = None

    def __init__(self, ctx: RobotContext):
        self.ctx = ctx

    def decide(self, world: WorldModel) -> Command:
        raise NotImplementedError

    @classmethod
    def warm_up(cls) -> None:
        """Load or compile now what the strategy would otherwise first meet in the middle of a match (e.g.
        compiled kernels that only open play or a set piece reaches). A team or robot process calls it
        before it joins a distributed run on a machine where its kernels were not compiled yet, after a
        short rehearsal of the scene has met the common paths: a lockstep tick does not wait for a
        compiler. Default: nothing."""


class TeamStrategy:
    """A team: makes its robots' strategies. Override `make_robot` or set ``robot_class``."""

    Params: ClassVar[type[BaseModel] | None] = None
    robot_class: ClassVar[type[RobotStrategy] | None] = None

    def __init__(self, ctx: TeamContext):
        self.ctx = ctx

    @classmethod
    def warm_up(cls) -> None:
        """As `RobotStrategy.warm_up`; by default, the ``robot_class``'s."""
        if cls.robot_class is not None:
            cls.robot_class.warm_up()

    def make_robot(self, ctx: RobotContext) -> RobotStrategy:
        if self.robot_class is None:
            raise NotImplementedError(f"{type(self).__name__} must set robot_class or override make_robot")
        return self.robot_class(ctx)
