"""The robots a scene hands to learning (``teams.<team>.learners = [ids]``, or ``strategy = "learner"`` for a
whole team).

A `Learner` is an ordinary robot Control on the bus, with the same WorldModel, topics and timing as every
other robot: it only does not decide. Each control period it plays the `Command` its learning environment
(`simatch.envs`) set for this tick with `act`; with no environment driving it (a plain ``simatch run``), it
stands still.
"""

from __future__ import annotations

from .base import Command, RobotStrategy


class Learner(RobotStrategy):
    def __init__(self, ctx):
        super().__init__(ctx)
        self.command = Command()

    def act(self, command: Command) -> None:
        """The command to play from the next decision on (until another one is set)."""
        self.command = command

    def decide(self, world) -> Command:
        return self.command
