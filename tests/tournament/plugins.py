"""Teams that misbehave, for the tournament's failure tests (named as ``tests.tournament.plugins:Class``)."""

from __future__ import annotations

import os
import time

from simatch.strategy import Command, RobotStrategy


class Crashing(RobotStrategy):
    """Cannot even be built: the match fails before its first step."""

    def __init__(self, ctx):
        raise RuntimeError("this team does not build")


class Hanging(RobotStrategy):
    """Plays one second, then loops for ever inside decide (pure Python: the match's time limit stops it)."""

    def decide(self, world) -> Command:
        if world.time > 1.0:
            while True:
                pass
        return Command()


class Stubborn(RobotStrategy):
    """Loops for ever and swallows every interruption: only ending its process stops it."""

    def decide(self, world) -> Command:
        while True:
            try:
                time.sleep(3600)
            except BaseException:
                pass


class Exiting(RobotStrategy):
    """Ends the process playing the match (as a crash in compiled code would)."""

    def decide(self, world) -> Command:
        if world.time > 0.5:
            os._exit(3)
        return Command()


class Raising(RobotStrategy):
    """Raises in every decision: the strategies' guard keeps the match going with this team standing still."""

    def decide(self, world) -> Command:
        raise ValueError("a bug in decide")
