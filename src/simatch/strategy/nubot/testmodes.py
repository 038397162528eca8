"""The coach's TEST commands (CoachInfo match_mode TEST, test_mode, points A/B, angles, ids, kick force),
as the original coach's test tab offered them. Points are in the team frame; robots not named stand
still. No game rule applies in a test (a dribble may be as long as the test needs).

* MOVE_NOBALL_NOAVOID / MOVE_NOBALL_AVOID: robot id_a goes to A, heading angle_a, without / with obstacle
  avoidance.
* MOVE_BALL_NOAVOID / MOVE_BALL_AVOID: robot id_a takes the ball, then dribbles it to A, heading angle_a.
* PASS_BALL: robot id_a takes the ball, brings it to A and passes it to robot id_b, which waits at B and
  takes it (kick_force is the pass speed; 0 picks one for the distance).
* CATCH_BALL: robot id_a takes the ball and holds it.
* SHOOT_BALL: robot id_a takes the ball and kicks it at point A at kick_force (0: the shot speed).
* LOCATION_TEST: robot id_a goes to A (heading angle_a), then B (heading angle_b), and again.
* CIRCLE_TEST: robot id_a drives round the circle through B centred on A (radius 1 m if B is A), facing
  along it, at 1.5 m/s.
* TEST_STOP (and any other value): everybody stands still.
"""

from __future__ import annotations

import math

from ...msgs.game_commands import TestMode
from ..base import Command
from ..roles import ACTIONS, ROLES
from .active import BallPlayer
from .evaluate import pass_speed
from .geometry import wrap
from .motion import Motion
from .observation import Observation
from .params import NubotParams
from .picture import Picture

ARRIVED = 0.12  # [m]
ARRIVED_YAW = 0.08  # [rad]
CIRCLE_SPEED = 1.5  # [m/s]


class TestModes:
    def __init__(self, params: NubotParams, motion: Motion, player: BallPlayer):
        self.p = params
        self.motion = motion
        self.player = player
        self.leg = 0  # LOCATION_TEST: 0 going to A, 1 going to B
        self.passed = False

    def decide(self, obs: Observation, pic: Picture) -> Command:
        c = obs.coach
        me = obs.me
        mode = c.test_mode
        a = (c.point_a_x, c.point_a_y)
        b = (c.point_b_x, c.point_b_y)
        if mode != TestMode.PASS_BALL:
            self.passed = False
        if mode == TestMode.PASS_BALL and me.id == c.id_b:
            return self.receive(obs, pic, b)
        if me.id != c.id_a:
            return Command(role=ROLES.NOROLE, action=ACTIONS.NO_ACTION)
        if mode in (TestMode.MOVE_NOBALL_NOAVOID, TestMode.MOVE_NOBALL_AVOID):
            return self.move(obs, a, c.angle_a, avoid=mode == TestMode.MOVE_NOBALL_AVOID)
        if mode in (TestMode.MOVE_BALL_NOAVOID, TestMode.MOVE_BALL_AVOID):
            if not me.holding:
                return self.player.fetch(obs, pic, ROLES.ACTIVE, stay_out_own_area=False)
            return self.carry(obs, a, c.angle_a, avoid=mode == TestMode.MOVE_BALL_AVOID)
        if mode == TestMode.CATCH_BALL:
            if me.holding:
                return Command(dribble=True, role=ROLES.ACTIVE, action=ACTIONS.CATCH_BALL)
            return self.player.fetch(obs, pic, ROLES.ACTIVE, stay_out_own_area=False)
        if mode == TestMode.SHOOT_BALL:
            if not me.holding:
                return self.player.fetch(obs, pic, ROLES.ACTIVE, stay_out_own_area=False)
            speed = c.kick_force if c.kick_force > 0.0 else self.p.shot_speed
            return self.player.execute(obs, ("shoot", a[0], a[1], speed, 0.0), ROLES.ACTIVE)
        if mode == TestMode.PASS_BALL:
            return self.give(obs, pic, a, c.id_b, c.kick_force)
        if mode == TestMode.LOCATION_TEST:
            goal, yaw = (a, c.angle_a) if self.leg == 0 else (b, c.angle_b)
            if math.hypot(goal[0] - me.x, goal[1] - me.y) < ARRIVED and abs(wrap(yaw - me.yaw)) < ARRIVED_YAW:
                self.leg = 1 - self.leg
            return self.move(obs, goal, yaw, avoid=True)
        if mode == TestMode.CIRCLE_TEST:
            return self.circle(obs, a, b)
        return Command(role=ROLES.NOROLE, action=ACTIONS.NO_ACTION)

    def move(self, obs: Observation, a, yaw: float, avoid: bool) -> Command:
        vx, vy, w = self.motion.go(obs, a[0], a[1], yaw, self.p.max_speed, self.p.max_turn, avoid=avoid)
        return Command(vx=vx, vy=vy, w=w, role=ROLES.NOROLE, action=ACTIONS.POSITIONED, intent=a)

    def carry(self, obs: Observation, a, yaw: float, avoid: bool) -> Command:
        me = obs.me
        d = math.hypot(a[0] - me.x, a[1] - me.y)
        face = math.atan2(a[1] - me.y, a[0] - me.x) if d > 0.4 else yaw
        vx, vy, w = self.motion.go(obs, a[0], a[1], face, self.p.dribble_speed, self.p.dribble_turn, avoid=avoid)
        return Command(vx=vx, vy=vy, w=w, dribble=True, role=ROLES.ACTIVE, action=ACTIONS.MOVE_WITH_BALL, intent=a)

    def give(self, obs: Observation, pic: Picture, a, to: int, force: float) -> Command:
        me = obs.me
        mate = obs.by_id.get(to)
        if self.passed and me.holding:
            self.passed = False  # the kick did not fire: try again
        if self.passed:
            return Command(role=ROLES.PASSOFPASS, action=ACTIONS.NO_ACTION, pass_intent=self.player.pass_intent(obs))
        if not me.holding:
            return self.player.fetch(obs, pic, ROLES.ACTIVE, stay_out_own_area=False)
        if math.hypot(a[0] - me.x, a[1] - me.y) > 0.3:
            return self.carry(obs, a, me.yaw, avoid=True)
        if mate is None:
            return Command(dribble=True, role=ROLES.ACTIVE, action=ACTIONS.NO_ACTION)
        d = math.hypot(mate.x - obs.bx, mate.y - obs.by)
        speed = force if force > 0.0 else pass_speed(d, self.p.pass_arrival_speed, self.p.ball_deceleration)
        cmd = self.player.execute(obs, ("pass", mate.x, mate.y, speed, to), ROLES.ACTIVE)
        if cmd.kick_speed > 0.0:
            self.passed = True
        return cmd

    def receive(self, obs: Observation, pic: Picture, b) -> Command:
        me = obs.me
        if me.holding:
            return Command(dribble=True, role=ROLES.CATCHOFPASS, action=ACTIONS.CATCH_BALL)
        rx, ry = me.x - obs.bx, me.y - obs.by
        speed = obs.ball_speed
        coming = speed > 0.3 and (rx * obs.bvx + ry * obs.bvy) > 0.7 * speed * math.hypot(rx, ry)
        if coming or math.hypot(rx, ry) < 0.8:
            return self.player.fetch(obs, pic, ROLES.CATCHOFPASS, stay_out_own_area=False)
        face = math.atan2(obs.by - me.y, obs.bx - me.x)
        vx, vy, w = self.motion.go(obs, b[0], b[1], face, self.p.max_speed, self.p.max_turn)
        return Command(
            vx=vx, vy=vy, w=w, dribble=True, role=ROLES.CATCHOFPASS, action=ACTIONS.CATCH_POSITIONED, intent=b
        )

    def circle(self, obs: Observation, a, b) -> Command:
        me = obs.me
        r = math.hypot(b[0] - a[0], b[1] - a[1]) or 1.0
        rx, ry = me.x - a[0], me.y - a[1]
        d = math.hypot(rx, ry) or 1e-6
        # tangent (counter-clockwise) plus a radial correction towards the circle
        tx, ty = -ry / d, rx / d
        corr = max(-1.0, min(1.0, 2.0 * (r - d)))
        vx = CIRCLE_SPEED * tx + corr * rx / d
        vy = CIRCLE_SPEED * ty + corr * ry / d
        face = math.atan2(ty, tx)
        w = self.motion.turn_rate(wrap(face - me.yaw), self.p.max_turn) + CIRCLE_SPEED / r
        bx, by, w = self.motion.body(me.yaw, vx, vy, w)
        return Command(vx=bx, vy=by, w=w, role=ROLES.NOROLE, action=ACTIONS.CIRCLE_TEST, intent=a)
