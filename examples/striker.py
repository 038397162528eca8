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

from simatch.msgs.game_commands import MatchMode, is_ours
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
        return Command(
            target=(goal_x, y),
            target_ori=face,
            max_vel=self.ctx.params.speed,
            role=Role.GOALIE,
            action=Action.POSITIONED,
        )


class Striker(RobotStrategy):
    """The robot nearest to the ball takes it, carries it towards the goal and shoots; the others wait
    on their start spots. At set pieces it keeps the distances of the rules (3 m from the ball at the
    opponents' restarts, until the ball is in play; 2 m for team-mates at ours)."""

    def __init__(self, ctx):
        super().__init__(ctx)
        self.last_mode = MatchMode.STOPROBOT
        self.wait_from = None  # where the ball was when an opponents' restart began
        self.took_at = None  # where this robot took the ball (the 3 m dribbling rule)

    def decide(self, world) -> Command:
        p, me, ball = self.ctx.params, world.me, world.ball
        mode, last = world.match_mode, self.last_mode
        self.last_mode = mode
        if mode in (MatchMode.STOPROBOT, MatchMode.TEST) or ball is None:
            return Command(action=Action.NO_ACTION)
        if mode == MatchMode.PARKINGROBOT:
            return Command(target=(-3.0 * self.ctx.id, -self.ctx.field.half_width - 0.5), target_ori=math.pi / 2)
        if mode == MatchMode.STARTROBOT and 1 <= last <= 12 and not is_ours(last):
            self.wait_from = (ball.x, ball.y)
        if self.wait_from is not None and math.hypot(ball.x - self.wait_from[0], ball.y - self.wait_from[1]) > 0.5:
            self.wait_from = None  # the ball is in play
        if 1 <= mode <= 13 or self.wait_from is not None or not self.nearest(world):
            return self.wait(world, mode if 1 <= mode <= 13 else world.match_type)
        goal = (self.ctx.field.half_length, 0.0)
        if me.holding_ball and self.took_at is None:
            self.took_at = (me.x, me.y)
        elif not me.holding_ball and math.hypot(ball.x - me.x, ball.y - me.y) > 0.8:
            self.took_at = None
        if not me.holding_ball:
            face = math.atan2(ball.y - me.y, ball.x - me.x)
            return Command(
                target=(ball.x, ball.y),
                target_ori=face,
                max_vel=p.speed,
                dribble=True,
                role=Role.ACTIVE,
                action=Action.CATCH_BALL,
            )
        face = math.atan2(goal[1] - me.y, goal[0] - me.x)
        close = math.hypot(goal[0] - me.x, goal[1] - me.y) < p.shoot_from
        aimed = abs(math.remainder(face - me.yaw, 2 * math.pi)) < 0.1
        carried = math.hypot(me.x - self.took_at[0], me.y - self.took_at[1])
        if (close and aimed) or carried > 2.3:
            # shoot, or (carried 2.3 m: 3 m is the limit) play it on towards the goal
            # a kick releases the dribbler; fast enough that the dribbler cannot take the ball back
            return Command(target_ori=face, kick_speed=8.0, role=Role.ACTIVE, action=Action.AT_SHOOT_SITUATION)
        # carry the ball a short way (the rules allow 3 m from where it was taken), turning to the goal
        step = (me.x + 0.8 * math.cos(face), me.y + 0.8 * math.sin(face))
        return Command(
            target=step if not close else None,
            target_ori=face,
            max_vel=1.5,
            max_w=3.0,
            dribble=True,
            role=Role.ACTIVE,
            action=Action.MOVE_WITH_BALL,
        )

    def wait(self, world, set_piece: int) -> Command:
        """Stand on the start spot, pushed away from the ball as far as the set piece requires."""
        ball = world.ball
        x, y, _ = self.ctx.start
        keep = 2.5 if is_ours(set_piece) else 3.5
        d = math.hypot(x - ball.x, y - ball.y)
        if d < keep and not (is_ours(set_piece) and self.nearest(world)):
            x, y = ball.x + (x - ball.x) / max(d, 1e-6) * keep, ball.y + (y - ball.y) / max(d, 1e-6) * keep
        face = math.atan2(ball.y - world.me.y, ball.x - world.me.x)
        return Command(
            target=(x, y), target_ori=face, max_vel=self.ctx.params.speed, role=Role.PASSIVE, action=Action.POSITIONED
        )

    def nearest(self, world) -> bool:
        """Whether this robot is the field robot nearest to the ball (team-mates from perception)."""
        ball = world.ball
        mine = math.hypot(ball.x - world.me.x, ball.y - world.me.y)
        return all(r.id == world.goalkeeper or math.hypot(ball.x - r.x, ball.y - r.y) >= mine for r in world.teammates)


class StrikerTeam(TeamStrategy):
    """The team: one Keeper (the scene's goalkeeper id), Strikers for the rest."""

    Params = StrikerParams

    def make_robot(self, ctx) -> RobotStrategy:
        return Keeper(ctx) if ctx.is_goalkeeper else Striker(ctx)
