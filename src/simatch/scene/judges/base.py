"""Judges: the part of the scene subsystem that watches a run, decides, and says how it ended.

A judge is a node of phase JUDGE. It observes the world through the simulation interface (model states
and the simulator's events on the bus) and may act on it through the Gazebo-like calls of the
`WorldControl` it is given (placing the ball for a restart, parking a sent-off robot, freezing a captured
target, turning a team's frame when the teams change ends). It publishes game commands (CoachInfo) and
events, and it decides when the run is over.
"""

from __future__ import annotations

from typing import Any, ClassVar, Protocol

from pydantic import BaseModel, ConfigDict

from ...bus import Node, Phase
from ...config.loader import LoadedScene


class WorldControl(Protocol):
    """The privileged part of the simulation interface a judge may use (the simulator implements it)."""

    def model_states(self) -> dict: ...  # name -> the model's state now (x, y, yaw, twist), world frame
    def set_model_state(self, name: str, **state: float) -> None: ...
    def apply_wrench(self, name: str, force=(0, 0, 0), torque=(0, 0, 0), duration: float = 0.0) -> None: ...
    def set_enabled(self, name: str, enabled: bool) -> None: ...
    def set_frozen(self, name: str, frozen: bool) -> None: ...
    def set_team_sign(self, team: str, sign: int) -> None: ...  # the team's frame from now on (ends changed)


class NoParams(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Judge(Node):
    phase = Phase.JUDGE
    Params: ClassVar[type[BaseModel]] = NoParams
    name = "judge"
    #: the judge sends the game commands itself (a referee); otherwise each team gets a Coach
    gives_commands: ClassVar[bool] = False

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
