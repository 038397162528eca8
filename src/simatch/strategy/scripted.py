"""Scripted robots for tests and validations (not team strategies)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

from .base import Command, RobotStrategy


class ConstantParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    vx: float = Field(0.0, description="body-frame forward speed [m/s]")
    vy: float = Field(0.0, description="body-frame leftward speed [m/s]")
    w: float = Field(0.0, description="turn rate [rad/s]")


class ConstantVelocity(RobotStrategy):
    """Sends the same body-frame velocity command every control period (the paper's locomotion test)."""

    Params = ConstantParams

    def decide(self, world) -> Command:
        p = self.ctx.params
        return Command(vx=p.vx, vy=p.vy, w=p.w)


class StartPose(RobotStrategy):
    """Drives each robot back to its start pose and holds it there, and stands still on STOP. It exercises
    the plumbing (perception and game commands in, commands out) and is not a team strategy: it never
    plays the ball."""

    def decide(self, world) -> Command:
        if world.match_mode == 0:  # STOPROBOT
            return Command()
        x, y, yaw = self.ctx.start
        return Command(target=(x, y), target_ori=yaw, max_vel=2.0, max_w=3.0)
