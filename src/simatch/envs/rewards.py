"""Reward terms: what a scene's ``[learning.rewards]`` table names, each with its weight.

A term is computed per agent after every environment step from what happened in it: the events the run
published (the referee's goals and fouls, the encirclement's captures, ...) and the world's true state
before and after (the ball, the robots, who holds the ball). An agent's reward is the sum of its weighted
terms; ``infos[agent]["rewards"]`` reports each weighted term, so a user sees what the agent was paid for.

```toml
[learning.rewards]
goal = 1.0                                  # a shipped term and its weight
conceded = -1.0
ball_progress = { weight = 0.1 }            # the same, as a table
"mypackage.terms:Dribble" = { weight = 0.5, radius = 2.0 }   # your own `RewardTerm` with settings
```

Shipped terms (`SHIPPED`): ``goal`` (+1 per goal of the agent's team: a ``goal`` event for it), ``conceded``
(+1 per goal against it: give it a negative weight), ``ball_progress`` (metres the ball came closer to the goal
the agent's team attacks), ``ball_approach`` (metres the agent came closer to the ball), ``possession``
(seconds the agent's team held the ball with its dribbler), ``foul`` (+1 per foul of the agent's team,
referee's `FOUL_TYPES`: give it a negative weight), ``capture`` (+1 per robot of the other team captured,
encirclement), ``captured`` (+1 per robot of the agent's team captured), ``time`` (seconds passed: a cost
with a negative weight), ``event`` (+1 per event of the given ``type``, of the agent's team, the other or any).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

from pydantic import BaseModel, ConfigDict, Field

from ..config.loader import SceneError, validate_params
from ..plugins import PluginError, load
from ..scene.referee.log import FOUL_TYPES


@dataclass
class Snapshot:
    """The world's true state at an instant (world frame): what the terms compare before and after a step."""

    ball: tuple[float, float, float]
    robots: dict[str, tuple[float, float]]
    holder_team: str  # team of the robot whose dribbler holds the ball, "" if none
    attacks: dict[str, int]  # team -> +1 if it attacks +x now, -1 if -x (teams change ends at half time)


@dataclass
class Step:
    """One environment step as the terms read it."""

    before: Snapshot
    after: Snapshot
    events: list  # GameEvent messages published during the step, in order
    seconds: float  # simulated time the step lasted


@dataclass
class Agent:
    """Who a reward is for."""

    name: str  # "cyan/2"
    team: str
    half_length: float  # of the field: the goals' centres are at x = +-half_length (world)


class TermParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    weight: float = Field(1.0, description="the term's weight in the reward")


class RewardTerm:
    """One term. Subclasses set ``Params`` (a `TermParams` subclass) and override `value`."""

    Params: ClassVar[type[TermParams]] = TermParams

    def __init__(self, params: TermParams):
        self.params = params

    def value(self, step: Step, agent: Agent) -> float:
        raise NotImplementedError


def _count(events: list, types: frozenset | set | tuple, team: str | None = None, other_than: str | None = None):
    n = 0
    for ev in events:
        if ev.type in types and (team is None or ev.team == team) and (other_than is None or ev.team != other_than):
            n += 1
    return n


class Goal(RewardTerm):
    def value(self, step: Step, agent: Agent) -> float:
        return float(_count(step.events, ("goal",), team=agent.team))


class Conceded(RewardTerm):
    def value(self, step: Step, agent: Agent) -> float:
        return float(_count(step.events, ("goal",), other_than=agent.team))


class BallProgress(RewardTerm):
    def value(self, step: Step, agent: Agent) -> float:
        goal_x = step.after.attacks[agent.team] * agent.half_length  # the goal it attacks now

        def to_goal(ball: tuple[float, float, float]) -> float:
            return math.hypot(ball[0] - goal_x, ball[1])

        return to_goal(step.before.ball) - to_goal(step.after.ball)


class BallApproach(RewardTerm):
    def value(self, step: Step, agent: Agent) -> float:
        def gap(s: Snapshot) -> float:
            x, y = s.robots[agent.name]
            return math.hypot(s.ball[0] - x, s.ball[1] - y)

        return gap(step.before) - gap(step.after)


class Possession(RewardTerm):
    def value(self, step: Step, agent: Agent) -> float:
        return step.seconds if step.after.holder_team == agent.team else 0.0


class Foul(RewardTerm):
    def value(self, step: Step, agent: Agent) -> float:
        return float(_count(step.events, FOUL_TYPES, team=agent.team))


class Capture(RewardTerm):
    def value(self, step: Step, agent: Agent) -> float:
        return float(_count(step.events, ("capture",), other_than=agent.team))


class Captured(RewardTerm):
    def value(self, step: Step, agent: Agent) -> float:
        return float(_count(step.events, ("capture",), team=agent.team))


class Time(RewardTerm):
    def value(self, step: Step, agent: Agent) -> float:
        return step.seconds


class EventParams(TermParams):
    type: str = Field(min_length=1, description="the event type counted, e.g. ball_out")
    team: Literal["own", "other", "any"] = Field("own", description="whose events count: the agent's team's, ...")


class Event(RewardTerm):
    Params = EventParams

    def value(self, step: Step, agent: Agent) -> float:
        p = self.params
        team = agent.team if p.team == "own" else None
        other = agent.team if p.team == "other" else None
        return float(_count(step.events, (p.type,), team=team, other_than=other))


SHIPPED: dict[str, str] = {
    "goal": "simatch.envs.rewards:Goal",
    "conceded": "simatch.envs.rewards:Conceded",
    "ball_progress": "simatch.envs.rewards:BallProgress",
    "ball_approach": "simatch.envs.rewards:BallApproach",
    "possession": "simatch.envs.rewards:Possession",
    "foul": "simatch.envs.rewards:Foul",
    "capture": "simatch.envs.rewards:Capture",
    "captured": "simatch.envs.rewards:Captured",
    "time": "simatch.envs.rewards:Time",
    "event": "simatch.envs.rewards:Event",
}


def make_terms(table: dict[str, Any], source: str) -> dict[str, RewardTerm]:
    """The terms of a ``[learning.rewards]`` table, checked: an unknown term or a wrong setting is a
    SceneError naming the file and the key."""
    terms: dict[str, RewardTerm] = {}
    for name, raw in table.items():
        key = f"learning.rewards.{name}"
        try:
            cls = load(name, SHIPPED, "reward term")
        except PluginError as exc:
            raise SceneError(f"{source}: {key}: {exc}") from None
        if not (isinstance(cls, type) and issubclass(cls, RewardTerm)):
            raise SceneError(f"{source}: {key}: {name!r} is not a simatch.envs.rewards.RewardTerm subclass")
        settings = {"weight": raw} if isinstance(raw, int | float) else dict(raw)
        terms[name] = cls(validate_params(cls.Params, settings, source, key))
    return terms


def reward(terms: dict[str, RewardTerm], step: Step, agent: Agent) -> tuple[float, dict[str, float]]:
    """The agent's reward for the step, and each weighted term."""
    parts = {name: term.params.weight * term.value(step, agent) for name, term in terms.items()}
    return float(sum(parts.values())), parts
