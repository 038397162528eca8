"""Taking a restart of ours once START is given.

The taker lines up behind the ball with its pass (or, at a penalty, its shot), then drives gently through
it with the dribbler off and the kicker armed: the kick fires as the ball enters the mouth, so the ball is
kicked at once, never dragged or dribbled. The pass is announced to the team first (so the receiver faces
the ball) and marked as played once it is kicked.
"""

from __future__ import annotations

import math

from ..base import Command, PassIntent
from ..roles import ACTIONS, ROLES
from .active import MOUTH, BallPlayer
from .evaluate import POST_MARGIN, pass_speed, shot_window
from .gameflow import MODES, GameFlow
from .geometry import unit, wrap
from .motion import Motion
from .observation import Observation
from .params import NubotParams
from .picture import Picture

KICKOFF_ARRIVAL = 0.6  # the kick-off pass nearly stops where the receiver takes it [m/s]
KICKOFF_MAX_X = -0.01  # the kick-off taker's centre stays behind this line (the referee: 0) [m]
LINE_UP = 0.55  # the taker lines up this far behind the ball [m]
ALIGNED = 0.08  # heading error allowed before driving through the ball [rad]
#: going round the ball to the line-up point, the taker's centre stays this far (+ 0.1 m) from the ball's
#: (touching: 0.36 m): brushing it would be the taker's touch, and its kick a second one [m]
ROUND_CLEARANCE = 0.42
ON_LINE = 0.045  # distance off the kick line allowed (the ball must enter the mouth) [m]


class RestartTaker:
    def __init__(self, params: NubotParams, motion: Motion, player: BallPlayer, goal_half: float, L2: float):
        self.p = params
        self.motion = motion
        self.player = player
        self.goal_half = goal_half
        self.L2 = L2
        self.restart = -1.0  # the restart (its START time) the choice below is for
        self.choice = 0  # the receiver chosen for it

    def receiver(self, obs: Observation, pic: Picture, flow: GameFlow):
        """The team-mate to pass to: the one set up as receiver (assistant), unless an opponent marks it
        and another one is clearly freer; kept once chosen for this restart unless it gets marked."""
        designated = next((m for m in obs.mates if pic.roles.get(m.id) == ROLES.ASSISTANT and m is not obs.me), None)
        if flow.kind == MODES.OUR_KICKOFF:
            return designated
        if self.restart != flow.t0:
            self.restart, self.choice = flow.t0, designated.id if designated is not None else 0
        options = {rid: value for value, rid, _, _, _ in self.player.passes(obs)}
        if options and self.choice not in options:
            self.choice = max(options, key=options.get)
        return obs.by_id.get(self.choice, designated)

    def take(self, obs: Observation, pic: Picture, flow: GameFlow) -> Command:
        p, me = self.p, obs.me
        bx, by = obs.bx, obs.by
        if obs.ball_speed > 0.3 and math.hypot(bx - flow.ball0[0], by - flow.ball0[1]) > 0.05:
            # kicked: the taker may not touch the ball again before another robot did; it stays put
            return Command(role=ROLES.PASSOFPASS, action=ACTIONS.NO_ACTION, pass_intent=self.player.pass_intent(obs))
        ax, ay, speed, receiver = self.aim(obs, pic, flow)
        ux, uy = unit(ax - bx, ay - by)
        face = math.atan2(uy, ux)
        if receiver is not None and flow.kind != MODES.OUR_KICKOFF:
            # the moment it is lined up, the receiver's current place counts (it may still be moving)
            ax, ay = receiver.x, receiver.y
        err = abs(wrap(face - me.yaw))
        # where the taker stands relative to the kick line through the ball
        rx, ry = me.x - bx, me.y - by
        behind = -(rx * ux + ry * uy)  # distance behind the ball along the kick line
        off = abs(rx * uy - ry * ux)  # distance off the kick line
        kick = 0.0
        # at a kick-off the taker stays in its half until the ball is in play, whatever its momentum
        max_x = KICKOFF_MAX_X if flow.kind == MODES.OUR_KICKOFF else None
        if behind < 0.2 or off > 0.5:
            # beside or in front of the ball: go round it to the line-up point
            tx, ty = bx - LINE_UP * ux, by - LINE_UP * uy
            vx, vy, w = self.motion.go(
                obs,
                tx,
                ty,
                face,
                p.max_speed,
                p.max_turn,
                avoid=True,
                ball_obstacle=0.45,
                fence=(bx, by, ROUND_CLEARANCE),
                max_x=max_x,
            )
            action = ACTIONS.POSITIONED_STATIC
        else:
            # behind it: close in along the line, converging onto it; drive through the ball only when lined
            # up, with the kicker armed (it fires as the ball enters the mouth, before any push)
            armed = off < ON_LINE and err < ALIGNED
            s_back = (MOUTH - 0.12 if armed else MOUTH + 0.3) + 2.5 * off
            tx, ty = bx - s_back * ux, by - s_back * uy
            vmax = 0.7 if behind < 1.2 else p.max_speed
            # brake early: touching the ball before the kick would be the taker's touch (then no second one)
            vx, vy, w = self.motion.go(
                obs,
                tx,
                ty,
                face,
                vmax,
                p.max_turn,
                avoid=False,
                end_speed=0.4 if armed else 0.0,
                gentle=False,
                brake=1.5,
                max_x=max_x,
            )
            if armed:
                kick = speed
                action = ACTIONS.STATIC_PASS if receiver is not None else ACTIONS.AT_SHOOT_SITUATION
            else:
                action = ACTIONS.POSITIONED_STATIC
        lx, ly = bx - LINE_UP * ux, by - LINE_UP * uy
        cmd = Command(
            vx=vx, vy=vy, w=w, dribble=False, kick_speed=kick, role=ROLES.ACTIVE, action=action, intent=(lx, ly)
        )
        if receiver is not None:
            self._announce(cmd, obs, receiver, ax, ay, speed)
        return cmd

    def aim(self, obs: Observation, pic: Picture, flow: GameFlow):
        """(x, y, kick speed, receiver) of the kick: at a penalty a shot into the open part of the goal (no
        receiver); otherwise a pass to the receiver (at a kick-off, to the point in front of it; without
        one, to the taker's slot's facing point or the opponents' goal)."""
        p, me = self.p, obs.me
        bx, by = obs.bx, obs.by
        if flow.kind == MODES.OUR_PENALTY:
            aim_y, _ = shot_window(bx, by, obs.opp_array, self.L2, self.goal_half, p.shot_speed, POST_MARGIN)
            return self.L2 + 0.3, aim_y, p.shot_speed, None
        slot = pic.slots.get(me.id)
        mate = self.receiver(obs, pic, flow)
        if flow.kind == MODES.OUR_KICKOFF and slot is not None:
            ax, ay = slot[2], slot[3]  # the point in front of the receiver
            arrival = KICKOFF_ARRIVAL
        elif mate is not None:
            ax, ay = mate.x, mate.y
            arrival = p.pass_arrival_speed
        elif slot is not None:
            ax, ay = slot[2], slot[3]
            arrival = p.pass_arrival_speed
        else:
            ax, ay, arrival = self.L2, 0.0, 3.0
        return ax, ay, pass_speed(math.hypot(ax - bx, ay - by), arrival, p.ball_deceleration), mate

    def _announce(self, cmd: Command, obs: Observation, receiver, ax: float, ay: float, speed: float) -> None:
        """The pass told to the team with ``cmd``; once kicked, announced until it should have arrived."""
        bx, by = obs.bx, obs.by
        kick = cmd.kick_speed
        intent = PassIntent(
            catch_id=receiver.id, pass_x=bx, pass_y=by, catch_x=ax, catch_y=ay, kicked=kick > 0.0, static=True
        )
        cmd.pass_intent = intent
        if kick > 0.0:
            self.player.announce = intent
            travel = math.hypot(ax - bx, ay - by) / max(0.5 * (speed + 1.0), 0.5)
            self.player.announce_until = obs.t + travel + 1.0
