"""A small deterministic strategy for the distributed tests: it moves, plays the ball and depends on the team
picture, so that any difference in data flow between embedded and distributed runs changes the state digest.

Not a team strategy (it ignores game commands, so a test needs no referee)."""

from __future__ import annotations

import math
import time

from simatch.strategy import Command, RobotStrategy


class Chaser(RobotStrategy):
    """Each robot tells its team how far it is from the ball (StrategyInfo.user[0]); the robot the team picture
    says is closest (its own fresh estimate breaks ties in its favour) chases the ball with the dribbler on and
    kicks it towards +x once it holds it; the others circle around their start pose."""

    def decide(self, world) -> Command:
        me, ball = world.me, world.ball
        x0, y0, yaw0 = self.ctx.start
        t = world.time
        if ball is None:
            return Command(target=(x0, y0), target_ori=yaw0, user=(1e9,))
        mine = ball.distance
        claims = {aid: float(s.user[0]) for aid, s in world.strategies.items() if len(s.user) and aid != self.ctx.id}
        best = min(claims.values(), default=math.inf)
        if not self.ctx.is_goalkeeper and mine <= best:
            if me.holding_ball:
                aim = math.atan2(-me.y, 11.0 - me.x)
                turn = math.remainder(aim - me.yaw, 2 * math.pi)
                kick = 6.0 if abs(turn) < 0.15 else 0.0
                return Command(target_ori=aim, dribble=True, kick_speed=kick, max_w=4.0, user=(mine,), role=1)
            return Command(
                target=(ball.x, ball.y),
                target_ori=math.atan2(ball.y - me.y, ball.x - me.x),
                dribble=True,
                max_vel=3.0,
                user=(mine,),
                role=1,
            )
        r = 0.5 if self.ctx.is_goalkeeper else 1.5
        phase = 0.7 * t + self.ctx.id
        return Command(
            target=(x0 + r * math.cos(phase), y0 + r * math.sin(phase)),
            target_ori=phase,
            max_vel=2.0,
            user=(mine,),
            role=2,
        )


class SlowChaser(Chaser):
    """A Chaser whose every decision takes 35 ms of wall time: more than a 25 ms control period (a robot
    process that falls behind for good)."""

    def decide(self, world) -> Command:
        time.sleep(0.035)
        return super().decide(world)


class SideAware(Chaser):
    """A Chaser whose robot 5 drives to a point fixed in the world, (2, 3) for cyan and (2, -3) for magenta,
    turned into its team frame with the side its WorldModel believes the team attacks: after the teams change
    ends it drives to the same world point only if its process learnt the new side (from the game state)."""

    def decide(self, world) -> Command:
        if self.ctx.id != 5:
            return super().decide(world)
        wx, wy = 2.0, (3.0 if self.ctx.team == "cyan" else -3.0)
        return Command(target=(world.sign * wx, world.sign * wy), max_vel=2.5, user=(1e9,))
