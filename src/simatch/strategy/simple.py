"""The baseline team "simple": the original Simatch demo strategy, in SI units (simatch-original.md 6.4).

It is what the original shipped instead of a real team, kept for comparison:

* play: the robot nearest to the ball (the goalkeeper excepted) is active: without the ball it turns to
  face the ball, then drives to it with the dribbler on; with the ball it dribbles to the fixed point
  (2, 3), then turns towards the middle of the opponents' goal and kicks (ground) as soon as its heading
  points between (11, -0.6) and (11, 0.6), at a speed equal to its distance to the goal (at least 3 m/s).
  Every other robot stands still;
* set pieces: the original's two formations (ours: the second robot 1 m and the third 2 m from the
  ball; theirs: everybody outside 3 m, standing at 3.5 m rather than the original's 3.2 m so that
  stopping 0.2 m short of the target still keeps the rule), all facing the ball;
* STOP: stand still; PARK: line up along the side line.

Motion goes through the robot's low-level controller (target pose, speed limit equal to the distance,
as the original's move2target did), so it is slow to arrive and never avoids anybody. It knows nothing of
the rules (it may dribble farther than 3 m), except the distances at set pieces: it waits at the
opponents' restarts until the ball is in play, and stands a little farther than the original did, since
a team that always breaks those would have every restart retaken and the match would not go on.
"""

from __future__ import annotations

import math

from ..msgs.game_commands import MatchMode, is_ours
from .base import Command, RobotStrategy
from .roles import Action, Role

ARRIVED = 0.2  # move2target's threshold [m]
FACING = math.radians(8.0)  # move2ori's threshold [rad]
DRIBBLE_TO = (2.0, 3.0)  # the fixed point the demo dribbles to [m]
AIM_HALF = 0.6  # the kick window on the goal line: y in [-0.6, 0.6] [m]
REST_AFTER_KICK = 20  # control periods the demo ignores the ball after a kick
OPPONENT_WAIT = 7.0  # at an opponents' restart, the robots keep away this long at most [s]

THEIR_SET_PIECE = {1: (-10.5, 0.0), 2: (-2.0, 1.0), 3: (-2.0, -1.0), 4: (-5.5, 2.0), 5: (-5.5, -2.0)}
KEEP_AWAY = 3.0
#: the original stood at 3.2 m, but move2target stops 0.2 m short of its target: that breaks the 3 m rule
#: (its referee never checked); 3.5 m keeps the formation legal
STAND_AT = 3.5


class SimpleRobot(RobotStrategy):
    #: how far from the ball the robots stand at the opponents' set pieces [m]
    stand_at = STAND_AT

    def __init__(self, ctx):
        super().__init__(ctx)
        self.rest = 0
        self.last_mode = -1
        self.wait_from: tuple[float, float, float] | None = None  # (time, ball x, y) of an opponents' restart
        L2 = ctx.field.half_length
        self.goal = (L2, 0.0)
        self.own_penalty = (-L2 + ctx.field.penalty_area_depth, 0.5 * ctx.field.penalty_area_width)

    def decide(self, world) -> Command:
        mode = world.match_mode
        me = world.me
        self.follow_restart(world)
        if mode == MatchMode.STOPROBOT or mode == MatchMode.TEST:
            return Command(action=Action.NO_ACTION)
        if mode == MatchMode.PARKINGROBOT:
            x = -self.ctx.field.half_length + 1.5 * self.ctx.id
            return self.move(me, (x, -self.ctx.field.half_width + 0.2), math.pi / 2)
        if 1 <= mode <= 13:
            return self.set_piece(world, mode)
        return self.play(world)

    def follow_restart(self, world) -> None:
        """Remember when START follows an opponents' set piece, and where the ball was then: until the
        ball is in play the robots keep away (the one rule the demo is taught, so that matches go on)."""
        mode, ball = world.match_mode, world.ball
        if (
            mode == MatchMode.STARTROBOT
            and 1 <= self.last_mode <= 13
            and not is_ours(self.last_mode)
            and self.last_mode != MatchMode.DROPBALL
            and ball is not None
        ):
            self.wait_from = (world.time, ball.x, ball.y)
        if self.wait_from is not None and ball is not None:
            t0, x0, y0 = self.wait_from
            moved = math.hypot(ball.x - x0, ball.y - y0) > 0.5
            if mode != MatchMode.STARTROBOT or world.time - t0 > OPPONENT_WAIT or moved:
                self.wait_from = None
        self.last_mode = mode

    # --- motion, as the original's move2target / move2ori through the low-level controller --------------
    def move(self, me, target, ori, dribble=False, role=Role.NOROLE, action=Action.POSITIONED) -> Command:
        d = math.hypot(target[0] - me.x, target[1] - me.y)
        err = abs(math.remainder(ori - me.yaw, 2 * math.pi))
        return Command(
            target=target if d > ARRIVED else None,
            target_ori=ori,
            max_vel=max(d, 0.05),
            max_w=max(2.0 * err, 0.05),
            dribble=dribble,
            role=role,
            action=action,
        )

    # --- set pieces -----------------------------------------------------------------------------------
    def set_piece(self, world, mode: int) -> Command:
        me, ball = world.me, world.ball
        bx, by = (ball.x, ball.y) if ball is not None else (0.0, 0.0)
        rid = self.ctx.id
        if is_ours(mode) and rid in (2, 3):
            # the original's OurDefaultReady: robot 2 one metre, robot 3 two metres (here 2.5 m, for the same
            # reason as STAND_AT) from the ball; at a kick-off from our side of it
            r = 1.0 if rid == 2 else 2.5
            dx, dy = me.x - bx, me.y - by
            if mode == MatchMode.OUR_KICKOFF:
                dx = min(dx, -0.5)
            d = math.hypot(dx, dy) or 1.0
            target = (bx + dx / d * r, by + dy / d * r)
        else:
            target = THEIR_SET_PIECE.get(rid, (-5.5, 0.0))
            tx, ty = target
            inside_own_area = tx <= self.own_penalty[0] and abs(ty) <= self.own_penalty[1]
            d = math.hypot(tx - bx, ty - by)
            if d < KEEP_AWAY and not inside_own_area:
                d = d or 1.0
                target = (bx + (tx - bx) / d * self.stand_at, by + (ty - by) / d * self.stand_at)
        return self.move(me, target, math.atan2(by - me.y, bx - me.x))

    # --- play -----------------------------------------------------------------------------------------
    def play(self, world) -> Command:
        me, ball = world.me, world.ball
        if ball is None:
            return Command(action=Action.CAN_NOT_SEE_BALL)
        if self.rest > 0:
            self.rest -= 1
        if not self.is_active(world, ball) or self.wait_from is not None:
            return Command(action=Action.NO_ACTION)
        if not me.holding_ball:
            face = math.atan2(ball.y - me.y, ball.x - me.x)
            if abs(math.remainder(face - me.yaw, 2 * math.pi)) > FACING:
                return self.move(
                    me, (me.x, me.y), face, dribble=self.rest == 0, role=Role.ACTIVE, action=Action.CATCH_BALL
                )
            return self.move(
                me, (ball.x, ball.y), face, dribble=self.rest == 0, role=Role.ACTIVE, action=Action.CATCH_BALL
            )
        if math.hypot(DRIBBLE_TO[0] - me.x, DRIBBLE_TO[1] - me.y) > 0.3:
            face = math.atan2(DRIBBLE_TO[1] - me.y, DRIBBLE_TO[0] - me.x)
            return self.move(me, DRIBBLE_TO, face, dribble=True, role=Role.ACTIVE, action=Action.MOVE_WITH_BALL)
        gx, gy = self.goal
        face = math.atan2(gy - me.y, gx - me.x)
        lo = math.atan2(-AIM_HALF - me.y, gx - me.x)
        hi = math.atan2(AIM_HALF - me.y, gx - me.x)
        cmd = self.move(me, (me.x, me.y), face, dribble=True, role=Role.ACTIVE, action=Action.TURN_FOR_SHOOT)
        if lo <= me.yaw <= hi:
            cmd.kick_speed = max(3.0, math.hypot(gx - me.x, gy - me.y))
            cmd.dribble = False
            cmd.action = Action.AT_SHOOT_SITUATION
            self.rest = REST_AFTER_KICK
        return cmd

    def is_active(self, world, ball) -> bool:
        """The nearest valid field robot to the ball (ties to the lower id)."""
        best, best_d = None, math.inf
        for r in world.robots:
            if not r.valid or (world.goalkeeper is not None and r.id == world.goalkeeper):
                continue
            d = math.hypot(ball.x - r.x, ball.y - r.y)
            if d < best_d:
                best, best_d = r.id, d
        return best == self.ctx.id
