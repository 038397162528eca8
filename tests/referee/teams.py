"""Teams that misbehave at restarts, for the tests that the referee keeps any match going.

Each differs from a shipped team in one way a real team might: ``OriginalSimple`` is the baseline team
``simple`` as the original Simatch's own code plays it; the others are the default team ``nubot`` with one
habit at restarts (otherwise it keeps the rules, so that what stops the match is that habit)."""

from __future__ import annotations

import math

from simatch.msgs.game_commands import MatchMode, is_ours
from simatch.strategy import Command
from simatch.strategy.nubot.robot import NubotRobot, NubotTeam
from simatch.strategy.roles import Action
from simatch.strategy.simple import SimpleRobot


def _set_piece(mode: int) -> bool:
    return 1 <= mode <= 13 and mode != MatchMode.DROPBALL


class OriginalSimple(SimpleRobot):
    """As the original Simatch's own robot code behaves: it stands 3.2 m from the ball's centre at the
    opponents' set pieces (stopping up to 0.2 m short of its target) and goes for the ball at START,
    whoever's restart it is (it never waits for the ball to be in play)."""

    stand_at = 3.2

    def follow_restart(self, world) -> None:
        self.last_mode = world.match_mode


class _Habit(NubotRobot):
    """nubot, remembering the last set piece called and when START came after it."""

    def __init__(self, ctx, shared=None):
        super().__init__(ctx, shared)
        self.set_piece = 0  # the last set-piece command (0: none since the last STOP)
        self.started_at: float | None = None

    def follow(self, world) -> None:
        mode = world.match_mode
        if _set_piece(mode):
            self.set_piece, self.started_at = mode, None
        elif mode == MatchMode.STARTROBOT:
            if self.set_piece and self.started_at is None:
                self.started_at = world.time
        else:
            self.set_piece, self.started_at = 0, None

    def since_start(self, world, ours: bool) -> float | None:
        """Seconds since START of a set piece of ours (``ours``) or theirs; None when there is none."""
        if not self.set_piece or self.started_at is None or is_ours(self.set_piece) != ours:
            return None
        return world.time - self.started_at


class Encroacher(_Habit):
    """At START of every opponents' set piece, every robot but the goalkeeper charges the ball for 3 s."""

    def decide(self, world) -> Command:
        self.follow(world)
        command = super().decide(world)
        t = self.since_start(world, ours=False)
        ball = world.ball
        if t is not None and t < 3.0 and ball is not None and not self.ctx.is_goalkeeper:
            me = world.me
            return Command(target=(ball.x, ball.y), target_ori=math.atan2(ball.y - me.y, ball.x - me.x), max_vel=3.0)
        return command


class EncroachingNubot(NubotTeam):
    def make_robot(self, ctx):
        return Encroacher(ctx, self.shared)


class Bystander(_Habit):
    """Never takes its own set pieces: after START of one it stands still for longer than the referee's
    restart timeout (7 s), then plays on."""

    def decide(self, world) -> Command:
        self.follow(world)
        command = super().decide(world)
        t = self.since_start(world, ours=True)
        if t is not None and t < 10.0:
            return Command(action=Action.NO_ACTION)
        return command


class NeverTakesRestarts(NubotTeam):
    def make_robot(self, ctx):
        return Bystander(ctx, self.shared)
