"""Plug-ins that use randomness nobody seeded (the operating system's): their runs differ every time, so only
the recorded world inputs can reproduce them (tests/record/test_world_inputs.py)."""

from __future__ import annotations

import random

from simatch.scene.judges import Judge
from simatch.strategy import Command, RobotStrategy

_entropy = random.SystemRandom()  # never seeded, never the same twice


class Wanderer(RobotStrategy):
    """Drives towards a new random point, with the dribbler on at random, every control tick."""

    def decide(self, world) -> Command:
        return Command(
            target=(_entropy.uniform(-4.0, 4.0), _entropy.uniform(-3.0, 3.0)),
            target_ori=_entropy.uniform(-3.0, 3.0),
            dribble=_entropy.random() < 0.5,
            kick_speed=_entropy.choice((0.0, 0.0, 0.0, 4.0)),
            max_vel=_entropy.uniform(0.5, 3.0),
        )


class DiceJudge(Judge):
    """Every half second places the ball, and now and then a robot, somewhere random; sends a random robot
    off and brings it back."""

    name = "dice"

    def start(self, ctx) -> None:
        super().start(ctx)
        self.period = 0.5
        self.off: str | None = None
        # a placement before the first step, as a judge setting up its scene would
        self.world.set_model_state("ball", x=_entropy.uniform(-2, 2), y=_entropy.uniform(-2, 2))

    def tick(self, now: float) -> None:
        self.world.set_model_state("ball", x=_entropy.uniform(-5, 5), y=_entropy.uniform(-4, 4), vx=0.5, vy=-0.2)
        robots = [r for r in self.scene.spec.robot_names()]
        if _entropy.random() < 0.5:
            self.world.set_model_state(_entropy.choice(robots), x=_entropy.uniform(-6, 6), y=_entropy.uniform(-4, 4))
        if self.off is None:
            self.off = _entropy.choice(robots)
            self.world.set_enabled(self.off, False)
        else:
            self.world.set_enabled(self.off, True)
            self.off = None
        if _entropy.random() < 0.3:
            self.world.apply_wrench("ball", force=(_entropy.uniform(-3, 3), 0.0, 0.0), duration=0.05)
