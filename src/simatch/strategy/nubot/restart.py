"""Taking a restart of ours once START is given.

The taker lines up behind the ball with its pass (or, at a penalty, its shot), then drives gently through
it with the dribbler off and the kicker armed: the kick fires as the ball enters the mouth, so the ball is
kicked at once, never dragged or dribbled. The pass is announced to the team first (so the receiver faces
the ball) and marked as played once it is kicked.
"""

from __future__ import annotations

import math

from ...scene.commands import MatchMode
from ..base import Command, PassIntent
from ..roles import Action, Role
from .active import MOUTH, BallPlayer
from .evaluate import pass_speed, shot_window
from .gameflow import GameFlow
from .geometry import unit, wrap
from .motion import Motion
from .observation import Observation
from .params import NubotParams
from .picture import Picture

LINE_UP = 0.55          # the taker lines up this far behind the ball [m]
ALIGNED = 0.07          # heading error allowed before driving through the ball [rad]


class RestartTaker:
    def __init__(self, params: NubotParams, motion: Motion, player: BallPlayer, goal_half: float, L2: float):
        self.p = params
        self.motion = motion
        self.player = player
        self.goal_half = goal_half
        self.L2 = L2

    def take(self, obs: Observation, pic: Picture, flow: GameFlow) -> Command:
        p, me = self.p, obs.me
        bx, by = obs.bx, obs.by
        receiver = None
        if flow.kind == MatchMode.OUR_PENALTY:
            aim_y, _ = shot_window(bx, by, obs.opps, self.L2, self.goal_half, p.shot_speed)
            ax, ay, speed = self.L2 + 0.3, aim_y, p.shot_speed
        else:
            slot = pic.slots.get(me.id)
            mate = next((m for m in obs.mates if pic.roles.get(m.id) == Role.ASSISTANT and m is not me), None)
            if flow.kind == MatchMode.OUR_KICKOFF and slot is not None:
                ax, ay = slot[2], slot[3]                  # the lead point in front of the receiver
                arrival = 2.0
            elif mate is not None:
                ax, ay = mate.x, mate.y
                arrival = p.pass_arrival_speed
            elif slot is not None:
                ax, ay = slot[2], slot[3]
                arrival = p.pass_arrival_speed
            else:
                ax, ay, arrival = self.L2, 0.0, 3.0
            receiver = mate
            speed = pass_speed(math.hypot(ax - bx, ay - by), arrival, p.ball_deceleration)
        ux, uy = unit(ax - bx, ay - by)
        face = math.atan2(uy, ux)
        err = abs(wrap(face - me.yaw))
        # where the taker stands, lined up, and how far it is off that line
        lx, ly = bx - LINE_UP * ux, by - LINE_UP * uy
        rx, ry = me.x - bx, me.y - by
        behind = -(rx * ux + ry * uy)               # distance behind the ball along the kick line
        off = abs(rx * uy - ry * ux)                # distance off the kick line
        kick = 0.0
        if behind > MOUTH - 0.05 and off < 0.06 and err < ALIGNED:
            # lined up: drive through the ball with the kicker armed
            tx, ty = bx - (MOUTH - 0.1) * ux, by - (MOUTH - 0.1) * uy
            vx, vy, w = self.motion.go(obs, tx, ty, face, 0.6, 2.0, avoid=False, end_speed=0.4, gentle=False)
            kick = speed
            action = Action.STATIC_PASS if receiver is not None else Action.AT_SHOOT_SITUATION
        else:
            vx, vy, w = self.motion.go(obs, lx, ly, face, p.max_speed, p.max_turn, avoid=True,
                                       ball_obstacle=behind < LINE_UP - 0.1 or off > 0.2)
            action = Action.POSITIONED_STATIC
        cmd = Command(vx=vx, vy=vy, w=w, dribble=False, kick_speed=kick, role=Role.ACTIVE, action=action,
                      intent=(lx, ly))
        if receiver is not None:
            intent = PassIntent(catch_id=receiver.id, pass_x=bx, pass_y=by, catch_x=ax, catch_y=ay,
                                kicked=kick > 0.0, static=True)
            cmd.pass_intent = intent
            if kick > 0.0:
                self.player.announce = intent
                travel = math.hypot(ax - bx, ay - by) / max(0.5 * (speed + 1.0), 0.5)
                self.player.announce_until = obs.t + travel + 1.0
        return cmd
