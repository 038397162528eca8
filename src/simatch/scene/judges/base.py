"""Judges: the part of the scene subsystem that watches a run, decides, and says how it ended.

A judge is a node of phase JUDGE. It observes the world through the simulation interface (model states
and the simulator's events on the bus) and may act on it through the Gazebo-like calls of the
`WorldControl` it is given (placing the ball for a restart, parking a sent-off robot, freezing a captured
target, turning a team's frame when the teams change ends). It publishes game commands (CoachInfo) and
events, and it decides when the run is over.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar, Protocol

from pydantic import BaseModel, ConfigDict

from ... import msgs
from ...bus import Node, NodeContext, Phase, topics
from ...config.loader import LoadedScene
from ...msgs.game_commands import MatchMode


class WorldControl(Protocol):
    """The privileged part of the simulation interface a judge may use (the simulator implements it)."""

    def model_states(self) -> dict: ...  # name -> the model's state now (x, y, yaw, twist), world frame
    def ball_array(self): ...  # (6,): x y z vx vy vz of the ball now, world frame (no other model read)
    def set_model_state(self, name: str, **state: float) -> None: ...
    def apply_wrench(self, name: str, force=(0, 0, 0), torque=(0, 0, 0), duration: float = 0.0) -> None: ...
    def set_enabled(self, name: str, enabled: bool) -> None: ...
    def set_frozen(self, name: str, frozen: bool) -> None: ...
    def set_team_sign(self, team: str, sign: int) -> None: ...  # the team's frame from now on (ends changed)
    def set_rotor(self, name: str, rotor: int, working: bool = True) -> None: ...  # aerial robots


def require_team(scene: LoadedScene, key: str, team: str) -> None:
    """SceneError naming the file and ``judge.<key>`` if the scene has no team ``team``."""
    from ...config.loader import SceneError

    if team not in scene.spec.teams:
        raise SceneError(
            f"{scene.source}: judge.{key}: the scene has no team {team!r} (teams: {', '.join(scene.spec.teams)})"
        )


class NoParams(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Judge(Node):
    phase = Phase.JUDGE
    Params: ClassVar[type[BaseModel]] = NoParams
    name = "judge"
    #: the judge sends the game commands itself (a referee); otherwise each team gets a Coach
    gives_commands: ClassVar[bool] = False
    #: the game has soccer's set pieces and restarts (kick-offs, throw-ins, ..., dropped balls) and the test
    #: modes: the coach pages and the referee console offer them only then
    set_pieces: ClassVar[bool] = False

    def __init__(self, scene: LoadedScene, params: Any, world: WorldControl):
        self.scene = scene
        self.params = params
        self.world = world
        self.done = False

    @property
    def duration(self) -> float | None:
        """How long the run lasts if nothing ends it earlier [s]; None: until the judge says done."""
        return self.scene.spec.duration

    def result(self) -> dict:
        """The judge's summary (the ``result`` of ``simatch run --json``)."""
        return {}

    def game(self) -> dict | None:
        """The game as the judge sees it (score, stage, clock, commands), if it judges a game."""
        return None


class NoJudge(Judge):
    """No judging: the run lasts the scene's (or the command line's) duration."""

    name = "none"
    set_pieces = True  # coaches give any command by hand, as in a friendly match without a referee


#: CoachInfo built positionally (every team, every control period)
_CoachInfo = msgs.positional(
    msgs.CoachInfo,
    "stamp match_mode match_type test_mode point_a_x point_a_y point_b_x point_b_y angle_a angle_b id_a id_b "
    "kick_force max_vel max_w ball_x ball_y",
)


class PlayJudge(Judge):
    """A judge of a game without set pieces, which gives the commands itself: STARTROBOT to every team from the
    first instant, STOPROBOT once it is done, re-sent every period; its `GameState` on every change (`changed`)
    and at least every ``game_state_period`` seconds. Subclasses judge in `tick` (calling `publish` at its
    end) and say what the game looks like in `game_state`."""

    gives_commands = True
    game_state_period: ClassVar[float] = 1.0

    def __init__(self, scene: LoadedScene, params: Any, world: WorldControl):
        super().__init__(scene, params, world)
        self.teams = list(scene.spec.teams)
        self._published = -math.inf
        self._dirty = True

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        bus = ctx.bus
        self.pub_coach = {
            t: bus.publisher(topics.team_topic(t, topics.RECEIVE_FROM_COACH), msgs.CoachInfo) for t in self.teams
        }
        self.pub_game = bus.publisher(topics.GAME_STATE, msgs.GameState)
        self.pub_events = bus.publisher(topics.EVENTS, msgs.GameEvent)

    def command(self) -> MatchMode:
        return MatchMode.STOPROBOT if self.done else MatchMode.STARTROBOT

    def changed(self) -> None:
        """The game changed: publish the GameState at the next `publish`."""
        self._dirty = True

    def event(self, now: float, kind: str, detail: str, team: str = "", robot: int = 0, **numbers: float) -> None:
        """Log a decision on the run's event log (``numbers``: x, y, value, limit)."""
        self.pub_events.put(
            msgs.GameEvent(
                stamp=now,
                type=kind,
                team=team,
                robot=robot,
                x=numbers.get("x", 0.0),
                y=numbers.get("y", 0.0),
                value=numbers.get("value", 0.0),
                limit=numbers.get("limit", 0.0),
                detail=detail,
            )
        )
        self._dirty = True

    def publish(self, now: float) -> None:
        """Every team's command, and the GameState when due."""
        cmd = int(self.command())
        for pub in self.pub_coach.values():
            pub.put(_CoachInfo(now, cmd, cmd, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0, 0, 0.0, 0.0, 0.0, 0.0, 0.0))
        if self._dirty or now - self._published >= self.game_state_period - 1e-9:
            if self.pub_game.active:
                self.pub_game.put(self.game_state(now))
            self._published = now
            self._dirty = False

    def game_state(self, now: float):
        """The GameState message of the game now."""
        raise NotImplementedError
