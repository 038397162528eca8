"""An example team for simatch: a goalkeeper that guards its goal and field robots that chase, carry and
shoot. It is the tutorial's example (docs/strategy.md): short, not strong.

Run it against the baseline from the repository's root:

    PYTHONPATH=examples simatch run examples/striker_vs_simple.toml

A strategy sees the world only through its robot's WorldModel (perception, team-mates' StrategyInfo, the
game command) in its team frame: its team always attacks +x, so the same code plays either colour.
"""

from __future__ import annotations

import math

from pydantic import BaseModel, ConfigDict, Field

from simatch.scene.commands import MatchMode, is_ours
from simatch.strategy import Command, RobotStrategy, TeamStrategy
from simatch.strategy.roles import Action, Role


class StrikerParams(BaseModel):
    """Checked against ``teams.<team>.strategy_params`` in the scene."""

    model_config = ConfigDict(extra="forbid")
    speed: float = Field(3.0, gt=0.0, le=6.0, description="top speed [m/s]")
    shoot_from: float = Field(5.0, gt=0.0, description="shoot when this close to the goal [m]")


class Keeper(RobotStrategy):
    """Stays on a line in front of its goal, level with the ball."""

    def decide(self, world) -> Command:
        if world.match_mode in (MatchMode.STOPROBOT, MatchMode.TEST) or world.ball is None:
            return Command(role=Role.GOALIE, action=Action.NO_ACTION)
        goal_x = -self.ctx.field.half_length + 0.5
        y = max(-1.0, min(1.0, world.ball.y))
        face = math.atan2(world.ball.y - world.me.y, world.ball.x - world.me.x)
        # a target pose: the robot's low-level controller turns it into a velocity
        return Command(target=(goal_x, y), target_ori=face, max_vel=self.ctx.params.speed,
                       role=Role.GOALIE, action=Action.POSITIONED)


class Striker(RobotStrategy):
    """The robot nearest to the ball takes it, carries it towards the goal and shoots; the others wait
    on their start spots (at least 3 m from the ball at the opponents' restarts)."""

    def decide(self, world) -> Command:
        p, me, ball = self.ctx.params, world.me, world.ball
        mode = world.match_mode
        if mode in (MatchMode.STOPROBOT, MatchMode.TEST) or ball is None:
            return Command(action=Action.NO_ACTION)
        if mode == MatchMode.PARKINGROBOT:
            return Command(target=(-3.0 * self.ctx.id, -self.ctx.field.half_width - 0.5), target_ori=math.pi / 2)
        if 1 <= mode <= 13 or not self.nearest(world):
            x, y, _ = self.ctx.start
            if 1 <= mode <= 13 and not is_ours(mode) and math.hypot(x - ball.x, y - ball.y) < 3.5:
                x, y = ball.x - 3.5, ball.y      # keep the 3 m of the rules
            return Command(target=(x, y), target_ori=0.0, max_vel=p.speed, role=Role.PASSIVE,
                           action=Action.POSITIONED)
        goal = (self.ctx.field.half_length, 0.0)
        if not me.holding_ball:
            face = math.atan2(ball.y - me.y, ball.x - me.x)
            return Command(target=(ball.x, ball.y), target_ori=face, max_vel=p.speed, dribble=True,
                           role=Role.ACTIVE, action=Action.CATCH_BALL)
        face = math.atan2(goal[1] - me.y, goal[0] - me.x)
        close = math.hypot(goal[0] - me.x, goal[1] - me.y) < p.shoot_from
        aimed = abs(math.remainder(face - me.yaw, 2 * math.pi)) < 0.1
        if close and aimed:
            # a kick releases the dribbler; fast enough that the dribbler cannot take the ball back
            return Command(target_ori=face, kick_speed=8.0, role=Role.ACTIVE, action=Action.AT_SHOOT_SITUATION)
        # carry the ball a short way (the rules allow 3 m from where it was taken), turning to the goal
        step = (me.x + 0.8 * math.cos(face), me.y + 0.8 * math.sin(face))
        return Command(target=step if not close else None, target_ori=face, max_vel=1.5, max_w=3.0,
                       dribble=True, role=Role.ACTIVE, action=Action.MOVE_WITH_BALL)

    def nearest(self, world) -> bool:
        """Whether this robot is the field robot nearest to the ball (team-mates from perception)."""
        ball = world.ball
        mine = math.hypot(ball.x - world.me.x, ball.y - world.me.y)
        return all(r.id == world.goalkeeper or math.hypot(ball.x - r.x, ball.y - r.y) >= mine
                   for r in world.teammates)


class StrikerTeam(TeamStrategy):
    """The team: one Keeper (the scene's goalkeeper id), Strikers for the rest."""

    Params = StrikerParams

    def make_robot(self, ctx) -> RobotStrategy:
        return Keeper(ctx) if ctx.is_goalkeeper else Striker(ctx)
