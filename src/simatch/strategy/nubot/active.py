"""The active robot: takes the ball, and with it shoots, passes or dribbles, within the rules.

Taking the ball: the robot runs to its interception point on the ball's predicted path, facing the ball,
dribbler on; close to a ball rolling at it, it lines its mouth up with the ball's path and gives way along
it so that the ball arrives slowly enough for the dribbler; against an opponent that holds the ball it
closes in gently (no charging) and wrestles for it.

With the ball, every tick, in this order:
* shoot when the shot can count (from the opponents' half, not straight from a set piece) and part of the
  goal stays open long enough for the ball to pass;
* pass when a team-mate is clearly better placed and its lane is free, when an opponent presses, when the
  dribble is running out, or always first after a set piece;
* otherwise dribble towards the best nearby point, never farther than ``dribble_limit`` from where the
  ball was taken (MSL: 3 m) and never far backwards; at the limit the ball is passed, shot, or played
  forward into space and released, so the dribble ends in time.

A shot or pass is aimed by turning with the ball (slowly, so that the dribbler keeps it) and fired once
the heading is within the tolerance the target allows.
"""

from __future__ import annotations

import math

import numpy as np

from ...compiled import Bool, Float, Matrix, bind, kernel
from ..base import Command, PassIntent
from ..roles import ACTIONS, ROLES
from .evaluate import POST_MARGIN, lane_clear, pass_speed, position_value, shot_window
from .gameflow import PHASES, GameFlow
from .geometry import clamp, time_to_cover, wrap
from .motion import Motion
from .observation import Observation
from .params import NubotParams
from .picture import Picture
from .positions import Areas, PitchType

# (what `fetch` and `play` read at every tick, as module constants)
_PLAY = PHASES.PLAY
_CATCH_BALL, _CATCH_POSITIONED = ACTIONS.CATCH_BALL, ACTIONS.CATCH_POSITIONED

MOUTH = 0.29  # robot centre to a held ball's centre [m]
PASS_KEEP = 1.5  # a pass being lined up keeps its receiver unless another is this much better
TASTE = 0.3  # spread of a possession's taste for each receiver (position value units)
LEAN = 0.15  # weight of a possession's preferred dribbling side
#: the open part of the goal (as the shooter sees it, opponents' reach included) that makes a shot worth it,
#: and that keeps a shot being lined up [rad]
SHOT_WIDTH = 0.045
SHOT_KEEP_WIDTH = 0.03
AIM_SPREAD = 0.25  # a shot aims this fraction of the open width either side of its middle
OPEN_GOAL_VALUE = 15.0  # value of a place with an open shot, per radian of open goal (capped at 0.15 rad)
CONTACT_THREAT = 0.3  # an opponent this close in time is on the ball: kick where the robot faces [s]
ESCAPE_RANGE = 3.0  # opponents nearer than this push the dribble away from them [m]
CONTACT_DISTANCE = 0.42  # ball centre this close to the robot's centre: touching it [m]
RELEASE_DISTANCE = 0.75  # a dribble ends once the ball centre is this far from the robot's (referee: 0.6) [m]
CLEAR_SPEED = 4.0  # a first-time kick into space, at most [m/s] ...
CLEAR_MIN_SPEED = 1.8  # ... and at least (slower is no clearance: dribble away instead) [m/s]
PASS_ANNOUNCE = 1.0  # a kicked pass is announced this long beyond its expected travel time [s]
DRIBBLE_DIRECTIONS = [(math.cos(k * math.pi / 8), math.sin(k * math.pi / 8)) for k in range(16)]
_DIRECTIONS = np.array(DRIBBLE_DIRECTIONS)


class BallPlayer:
    def __init__(
        self,
        params: NubotParams,
        motion: Motion,
        areas: Areas,
        goal_half: float,
        rng: np.random.Generator | None = None,
    ):
        self.p = params
        # the run's seed varies play: each possession draws a preferred dribbling side, a taste for each
        # receiver and an aim within the open part of the goal (the same seed always draws the same)
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.taste: dict[int, float] = {}
        self.lean = (1.0, 0.0)
        self.aim_offset = 0.0
        self.motion = motion
        self.areas = areas
        self.goal_half = goal_half
        self.dribble_from: tuple[float, float] | None = None
        self.back = 0.0  # backward travel while holding [m]
        self._last_pos = (0.0, 0.0)
        self.plan: tuple | None = None
        self.announce: PassIntent | None = None
        self.announce_until = -1.0
        self.pa_since: float | None = None  # when I entered the opponents' penalty area
        self.dribble_dir: tuple[float, float] | None = None
        # the judges `passes` calls for every candidate, and the dribble's choice
        self._lane_clear = bind(lane_clear)
        self._position_value = bind(position_value)
        self._shot_window = bind(shot_window)
        self._dribble_choice = bind(dribble_choice)

    # --- bookkeeping every tick --------------------------------------------------------------------------
    def track(self, obs: Observation) -> None:
        me = obs.me
        dball = math.hypot(obs.bx - me.x, obs.by - me.y)
        if me.holding or dball < CONTACT_DISTANCE:
            # the referee counts a dribble from the first touch (a push is one), not from the catch
            if self.dribble_from is None:
                self.dribble_from = (me.x, me.y)
                self.back = 0.0
                self.plan = None
                self.dribble_dir = None
                self.new_possession()
            elif me.holding:
                dx, dy = me.x - self._last_pos[0], me.y - self._last_pos[1]
                along = dx * math.cos(me.yaw) + dy * math.sin(me.yaw)
                if along < 0.0:
                    self.back -= along
        elif self.dribble_from is not None and dball > RELEASE_DISTANCE:
            # released: the ball is clearly away from the robot (a grip lost and regained at once, the ball
            # still at the robot, continues the same dribble)
            self.dribble_from = None
        self._last_pos = (me.x, me.y)
        if self.areas.in_opp_penalty_area(me.x, me.y):
            if self.pa_since is None:
                self.pa_since = obs.t
        else:
            self.pa_since = None
        if self.announce is not None and (obs.t > self.announce_until or (not me.holding and obs.holder is not None)):
            self.announce = None

    def new_possession(self) -> None:
        rng = self.rng
        a = float(rng.uniform(-math.pi, math.pi))
        self.lean = (math.cos(a), math.sin(a))
        self.taste = {rid: float(x) for rid, x in zip(range(1, 33), rng.normal(0.0, TASTE, 32))}
        self.aim_offset = float(rng.uniform(-AIM_SPREAD, AIM_SPREAD))

    def may_enter_opp_area(self, obs: Observation) -> bool:
        return self.pa_since is None or obs.t - self.pa_since < self.p.area_time

    def pass_intent(self, obs: Observation) -> PassIntent | None:
        return self.announce if self.announce is not None and obs.t <= self.announce_until else None

    # --- without the ball --------------------------------------------------------------------------------
    def fetch(
        self, obs: Observation, pic: Picture, role: int = ROLES.ACTIVE, stay_out_own_area: bool = True
    ) -> Command:
        p, me = self.p, obs.me
        bx, by = obs.bx, obs.by
        vbx, vby = obs.bvx, obs.bvy
        speed = obs.ball_speed
        dball = math.hypot(bx - me.x, by - me.y)
        face = math.atan2(by - me.y, bx - me.x)
        err = abs(wrap(face - me.yaw))
        feed = (0.0, 0.0)
        end = 0.0
        vmax = p.max_speed
        action = _CATCH_BALL
        t, tx, ty = pic.catch.get(me.id, (0.0, bx, by))
        if pic.opp_holds or speed < 0.4:
            tx, ty = bx, by
            end = 0.8 if dball < 1.5 else 0.0
        else:
            # rolling towards me and close: line the mouth up with its path and give way along it
            rx, ry = me.x - bx, me.y - by
            towards = (rx * vbx + ry * vby) / speed
            if 0.0 < towards < 2.0:
                ux, uy = vbx / speed, vby / speed
                fx, fy = bx + ux * towards, by + uy * towards
                # stand so that the mouth (not the centre) is on the path
                tx, ty = fx + ux * MOUTH, fy + uy * MOUTH
                face = math.atan2(-uy, -ux)
                err = abs(wrap(face - me.yaw))
                give = max(0.0, speed - p.catch_speed + 0.6)
                feed = (ux * give, uy * give)
                action = _CATCH_POSITIONED
            elif dball < 1.0:
                tx, ty = bx + vbx * 0.15, by + vby * 0.15
                end = 0.6
        if dball < 1.3:
            # turn before touching it: the ball enters the mouth only within 10 degrees of the heading
            vmax = min(vmax, max(0.35, 2.6 * (1.0 - err / 0.5)) + speed)
        if stay_out_own_area:
            tx, ty = self.areas.keep_out(tx, ty, own_pa=True, opp_pa=not self.may_enter_opp_area(obs))
        else:
            tx, ty = self.areas.keep_out(tx, ty, own_pa=False, opp_pa=not self.may_enter_opp_area(obs))
        if self.dribble_from is not None and not me.holding:
            # touching the ball without holding it (pushing it) counts as dribbling: when that runs out,
            # let the ball go clear before taking it again
            used = math.hypot(me.x - self.dribble_from[0], me.y - self.dribble_from[1])
            if used > p.dribble_limit - 0.4:
                ux, uy = math.cos(face), math.sin(face)
                tx, ty = obs.bx - ux * (RELEASE_DISTANCE + 0.3), obs.by - uy * (RELEASE_DISTANCE + 0.3)
                vx, vy, w = self.motion.go(obs, tx, ty, face, p.max_speed, p.max_turn, avoid=False)
                return Command(
                    vx=vx, vy=vy, w=w, dribble=False, role=role, action=ACTIONS.CATCH_BALL_SLOW, intent=(tx, ty)
                )
        boxes = self.areas.forbidden(self.may_enter_opp_area(obs)) if stay_out_own_area else ()
        vx, vy, w = self.motion.go(
            obs, tx, ty, face, vmax, p.max_turn, end_speed=end, feed=feed, turn_first=dball < 2.5, boxes=boxes
        )
        return Command(vx=vx, vy=vy, w=w, dribble=dball < 2.0, role=role, action=action, intent=(tx, ty))

    # --- with the ball -------------------------------------------------------------------------------------
    def play(self, obs: Observation, pic: Picture, flow: GameFlow, role: int = ROLES.ACTIVE) -> Command:
        p, me = self.p, obs.me
        L2 = self.areas.L2
        used = math.hypot(me.x - self.dribble_from[0], me.y - self.dribble_from[1]) if self.dribble_from else 0.0
        left = p.dribble_limit - used
        opps = obs.opp_array
        bx, by = obs.bx, obs.by
        can_score = not flow.pass_pending and not flow.need_pass and me.x > 0.3 and flow.phase == _PLAY
        threat = self.threat_time(obs)
        prev = self.plan
        plan = None
        # 1. shoot, when part of the goal stays open and there is time to turn to it
        if can_score and math.hypot(L2 - bx, by) < p.shoot_range:
            aim_y, width = shot_window(bx, by, opps, L2, self.goal_half, p.shot_speed, POST_MARGIN)
            need = SHOT_KEEP_WIDTH if (prev and prev[0] == "shoot") else SHOT_WIDTH
            if left < 0.4 or threat < 0.8:
                need = 0.025
            if width > need and self.turn_time(obs, L2, aim_y) < threat + 0.3:
                aim_y += self.aim_offset * width * (L2 - bx)
                plan = ("shoot", L2 + 0.3, aim_y, p.shot_speed, width)
        # 2. pass, when a team-mate is clearly better placed, or pressed, or the dribble runs out
        if plan is None:
            mine = position_value(bx, by, opps, L2)
            best, best_score = None, -math.inf
            for value, rid, cx, cy, v in self.passes(obs):
                late = self.turn_time(obs, cx, cy) > threat
                keep = prev is not None and prev[0] == "pass" and prev[4] == rid
                score = value - (2.0 if late else 0.0) + (PASS_KEEP if keep else 0.0)
                if score > best_score:
                    best, best_score = (value, rid, cx, cy, v, keep), score
            if best is not None:
                value, rid, cx, cy, v, keep = best
                margin = 0.4 if keep else 1.0
                urgent = left < 0.8 or threat < 1.2
                forced = flow.pass_pending or (flow.need_pass and cx > 0.3)  # MSL RC-10.1.2
                if forced or value > mine + margin or (urgent and value > mine - 2.5):
                    plan = ("pass", cx, cy, v, rid)
            if plan is None and threat < CONTACT_THREAT:
                plan = self.first_time(obs, can_score)
            if plan is None and left < 0.35:
                plan = self.release(obs, can_score)
        # 3. dribble, away from pressure, towards the best point in reach
        if plan is None:
            plan = self.dribble_target(obs, left, can_score)
        self.plan = plan
        return self.execute(obs, plan, role)

    def threat_time(self, obs: Observation) -> float:
        """Seconds before the nearest opponent can reach the ball (and challenge for it)."""
        p = self.p
        best = math.inf
        for ox, oy, vx, vy in obs.opps:
            dx, dy = obs.bx - ox, obs.by - oy
            d = math.hypot(dx, dy)
            gap = d - 0.55
            if gap <= 0.0:
                return 0.0
            # (Python's max and min of two, inline: the first unless the second is larger / smaller)
            v0 = (vx * dx + vy * dy) / d
            v0 = v0 if v0 > 0.0 else 0.0
            t = time_to_cover(gap, v0, p.max_speed, p.acceleration)
            best = t if t < best else best
        return best

    def turn_time(self, obs: Observation, tx: float, ty: float) -> float:
        """Seconds to turn (with the ball) to face (tx, ty)."""
        me = obs.me
        err = abs(wrap(math.atan2(ty - me.y, tx - me.x) - me.yaw))
        return err / (0.7 * self.p.dribble_turn) + 0.1

    def passes(self, obs: Observation) -> list[tuple]:
        """(value, receiver id, catch x, catch y, kick speed) of every pass worth considering."""
        p, me = self.p, obs.me
        bx, by = obs.bx, obs.by
        out = []
        for m in obs.mates:
            if m is me or not m.valid or m.is_goalie:
                continue
            cx, cy = m.x + 0.3 * m.vx, m.y + 0.3 * m.vy
            if self.areas.in_opp_penalty_area(cx, cy) or self.areas.near_own_penalty_area(cx, cy, 0.3):
                continue
            d = math.hypot(cx - bx, cy - by)
            if d < 1.8 or d > p.max_pass:
                continue
            v = pass_speed(d, p.pass_arrival_speed, p.ball_deceleration)
            margin = self._lane_clear(bx, by, cx, cy, obs.opp_array, 0.5 * (v + p.pass_arrival_speed), 0.0)
            if margin < 0.15:
                continue
            # (min(..., default=9.0) of the opponents' distances, as a plain loop: the first, then any smaller)
            near = None
            for o in obs.opps:
                h = math.hypot(o[0] - cx, o[1] - cy)
                if near is None or h < near:
                    near = h
            if near is not None and near < 1.1:
                continue
            value = self._position_value(cx, cy, obs.opp_array, self.areas.L2) + 0.3 * (1.5 if 1.5 < margin else margin)
            value += self.taste.get(m.id, 0.0)
            if cx > 0.0 and self.areas.L2 - cx < p.shoot_range:
                value += OPEN_GOAL_VALUE * min(
                    self._shot_window(cx, cy, obs.opp_array, self.areas.L2, self.goal_half, p.shot_speed, POST_MARGIN)[
                        1
                    ],
                    0.15,
                )
            out.append((value, m.id, cx, cy, v))
        return out

    def best_pass(self, obs: Observation):
        """(value, receiver id, catch x, catch y, kick speed) of the best pass, or None."""
        return max(self.passes(obs), default=None, key=lambda c: c[0])

    def first_time(self, obs: Observation, can_score: bool):
        """An opponent is on the ball: no time to turn. Play it where the robot already faces, if that is
        forward: at the goal, to a team-mate, or into space; else None (dribble away)."""
        me, p = obs.me, self.p
        c, s = math.cos(me.yaw), math.sin(me.yaw)
        if c < -0.2:
            return None
        L2 = self.areas.L2
        if can_score and c > 0.3:
            y_goal = me.y + s / c * (L2 - me.x)
            if abs(y_goal) < self.goal_half - 0.1 and L2 - me.x < p.shoot_range:
                return ("shoot", L2 + 0.3, y_goal, p.shot_speed, 0.0)
        for _value, rid, cx, cy, v in self.passes(obs):
            if abs(wrap(math.atan2(cy - me.y, cx - me.x) - me.yaw)) < 0.2:
                return ("pass", cx, cy, v, rid)
        tx, ty = me.x + 4.0 * c, me.y + 4.0 * s
        if abs(ty) > self.areas.W2 - 0.5 or abs(tx) > L2 - 0.5:
            return None
        if lane_clear(obs.bx, obs.by, tx, ty, obs.opp_array, CLEAR_SPEED, 0.0) < 0.0:
            return None  # straight into an opponent: the ball would only bounce back (dribble away)
        # no harder than the ball can roll and stay on the field: a clearance over a line is the
        # opponents' throw-in
        room = self.room_ahead(obs.bx, obs.by, c, s)
        speed = min(CLEAR_SPEED, math.sqrt(2.0 * max(p.ball_deceleration, 0.05) * room))
        if speed < CLEAR_MIN_SPEED:
            return None
        return ("clear", tx, ty, speed, 0)

    def room_ahead(self, x: float, y: float, c: float, s: float) -> float:
        """How far a ball can roll from (x, y) along (c, s) before it leaves the field (with a margin) [m]."""
        lx, ly = self.areas.L2 - 0.3, self.areas.W2 - 0.3
        room = math.inf
        if abs(c) > 1e-6:
            room = min(room, ((lx if c > 0 else -lx) - x) / c)
        if abs(s) > 1e-6:
            room = min(room, ((ly if s > 0 else -ly) - y) / s)
        return max(0.0, room)

    def release(self, obs: Observation, can_score: bool):
        """The dribble must end now and nothing better is on: shoot if the shot can count, else play the ball
        forward into space (ground kick) and go after it."""
        p = self.p
        L2 = self.areas.L2
        if can_score:
            aim_y, _ = shot_window(obs.bx, obs.by, obs.opp_array, L2, self.goal_half, p.shot_speed, POST_MARGIN)
            return ("shoot", L2 + 0.3, aim_y, p.shot_speed, 0.0)
        tx, ty = self.dribble_target(obs, 2.5)[1:3]
        d = max(2.0, math.hypot(tx - obs.bx, ty - obs.by))
        return ("clear", tx, ty, pass_speed(d, 1.0, p.ball_deceleration, 1.8, 4.0), 0)

    def dribble_target(self, obs: Observation, left: float, can_score: bool = False):
        """("dribble", x, y): the best point within reach of the ball, inside the dribble circle; near the
        opponents' goal, one from which more of the goal is open. (The sixteen directions are scored by the
        kernel `dribble_choice`.)"""
        me, areas, p = obs.me, self.areas, self.p
        cx, cy = self.dribble_from or (me.x, me.y)
        others_in_area = any(areas.in_opp_penalty_area(m.x, m.y) for m in obs.mates if m is not me)
        dx, dy = self.dribble_dir if self.dribble_dir is not None else (math.nan, math.nan)
        found, tx, ty, ux, uy = self._dribble_choice(
            me.x,
            me.y,
            me.yaw,
            clamp(left, 0.3, 1.5),
            cx,
            cy,
            max(0.0, p.dribble_limit - 0.15),
            obs.opp_array,
            areas.pitch,
            others_in_area or not self.may_enter_opp_area(obs),
            can_score,
            p.shoot_range,
            self.goal_half,
            p.shot_speed,
            self.lean[0],
            self.lean[1],
            self.back > p.dribble_back_limit - 0.5,
            dx,
            dy,
        )
        if not found:
            return ("dribble", me.x, me.y)
        self.dribble_dir = (ux, uy)
        return ("dribble", tx, ty)

    def kick_heading(self, obs: Observation, tx: float, ty: float, speed: float) -> float:
        """The heading to kick at ``speed`` so that the ball heads for (tx, ty): the kicker adds its speed to
        the mouth's own velocity, so the heading leans against the robot's drift across the line to the
        target (drifting 1 m/s sideways put a 10 m/s shot 0.6 m wide at 6 m). The turning part of the
        mouth's velocity is left out: it changes with the heading error it would correct (the robot
        would chase its own turn), and the kick waits for the turn to settle."""
        me = obs.me
        ux, uy = tx - obs.bx, ty - obs.by
        d = math.hypot(ux, uy)
        if d < 1e-6 or speed <= 0.0:
            return math.atan2(ty - me.y, tx - me.x)
        ux, uy = ux / d, uy / d
        across = clamp((me.vx * -uy + me.vy * ux) / speed, -0.5, 0.5)
        along = math.sqrt(1.0 - across * across)
        return math.atan2(along * uy - across * ux, along * ux + across * uy)

    def execute(self, obs: Observation, plan: tuple, role: int) -> Command:
        """Carry out a plan: ("dribble", x, y) or (kind, x, y, kick speed, extra) for "shoot" (extra: the
        open width), "pass" (extra: the receiver), "clear" (a ground kick into space) and "lob"."""
        p, me = self.p, obs.me
        kind = plan[0]
        if kind == "dribble":
            tx, ty = plan[1], plan[2]
            d = math.hypot(tx - me.x, ty - me.y)
            face = math.atan2(ty - me.y, tx - me.x) if d > 0.3 else me.yaw
            err = abs(wrap(face - me.yaw))
            vmax = p.dribble_speed * max(0.15, math.cos(min(err, 1.5)))
            vx, vy, w = self.motion.go(
                obs,
                tx,
                ty,
                face,
                vmax,
                p.dribble_turn,
                avoid=True,
                boxes=self.areas.forbidden(self.may_enter_opp_area(obs)) if role != ROLES.GOALIE else (),
            )
            return Command(vx=vx, vy=vy, w=w, dribble=True, role=role, action=ACTIONS.MOVE_WITH_BALL, intent=(tx, ty))
        tx, ty, speed = plan[1], plan[2], plan[3]
        # a shot leans against the robot's drift; a pass does not need it (the receiver gives way along the
        # ball's path), and a target that moves with the robot's own speed would delay the kick
        face = self.kick_heading(obs, tx, ty, speed) if kind == "shoot" else math.atan2(ty - me.y, tx - me.x)
        err = wrap(face - me.yaw)
        d = math.hypot(tx - me.x, ty - me.y)
        if kind == "shoot":
            tol = max(0.02, min(0.06, 0.35 * plan[4])) if plan[4] > 0.0 else 0.05
            action = ACTIONS.TURN_FOR_SHOOT
        else:
            tol = max(0.03, min(0.12, 0.45 / max(d, 0.5)))
            action = ACTIONS.TURN_TO_PASS
        vx, vy, w = self.motion.go(obs, me.x, me.y, face, 0.5, p.dribble_turn, avoid=False)
        kick = 0.0
        spin = 2.5 if kind == "clear" else 1.2  # turning adds the mouth's sideways speed to the kick
        if abs(err) < tol and abs(me.w) < spin and me.holding:
            kick = speed
            action = ACTIONS.AT_SHOOT_SITUATION if kind == "shoot" else ACTIONS.STATIC_PASS
        # a kick slower than the dribbler can take would be taken straight back by the robot's own dribbler:
        # for those the dribbler lets go as the kicker fires (the ball must then lie in the mouth); a faster
        # kick fires from the held ball
        dribble = kick == 0.0 or kick > p.catch_speed + 0.6
        cmd = Command(
            vx=vx,
            vy=vy,
            w=w,
            dribble=dribble,
            kick_speed=kick,
            lob=kind == "lob",
            role=role,
            action=action,
            intent=(tx, ty),
        )
        if kind == "pass":
            intent = PassIntent(
                catch_id=plan[4], pass_x=obs.bx, pass_y=obs.by, catch_x=tx, catch_y=ty, kicked=kick > 0.0
            )
            cmd.pass_intent = intent
            if kick > 0.0:
                self.announce = intent
                travel = d / max(0.5 * (speed + p.pass_arrival_speed), 0.5)
                self.announce_until = obs.t + travel + PASS_ANNOUNCE
        return cmd


@kernel(
    x=Float,
    y=Float,
    yaw=Float,
    step=Float,
    cx=Float,
    cy=Float,
    radius=Float,
    opps=Matrix,
    pitch=PitchType,
    keep_out_of_area=Bool,
    can_score=Bool,
    shoot_range=Float,
    goal_half=Float,
    shot_speed=Float,
    lean_x=Float,
    lean_y=Float,
    backed=Bool,
    dir_x=Float,
    dir_y=Float,
)
def dribble_choice(
    x,
    y,
    yaw,
    step,
    cx,
    cy,
    radius,
    opps,
    pitch,
    keep_out_of_area,
    can_score,
    shoot_range,
    goal_half,
    shot_speed,
    lean_x,
    lean_y,
    backed,
    dir_x,
    dir_y,
):
    """`BallPlayer.dribble_target`'s scoring of the sixteen directions: (found, x, y, ux, uy) of the best
    point (the first of equals) a step ``step`` from (x, y), within ``radius`` of where the dribble began
    (cx, cy). ``dir_x`` is NaN with no dribbling direction yet; ``backed``: the robot went backwards nearly as
    far as it may."""
    L2, W2 = pitch.half_length, pitch.half_width
    pa_depth, pa_half = pitch.penalty_depth, pitch.penalty_half_width
    ga_x0, ga_half = pitch.opp_goal.x0, pitch.opp_goal.half_width
    best_s = -math.inf
    found = False
    bx = by = bux = buy = 0.0
    c, s = math.cos(yaw), math.sin(yaw)
    for k in range(_DIRECTIONS.shape[0]):
        ux, uy = _DIRECTIONS[k, 0], _DIRECTIONS[k, 1]
        tx, ty = x + step * ux, y + step * uy
        dx, dy = tx - cx, ty - cy
        r = math.hypot(dx, dy)
        if r > radius:
            tx, ty = cx + dx / r * radius, cy + dy / r * radius
        if abs(tx) > L2 - 0.8 or abs(ty) > W2 - 0.8:
            continue
        # our penalty area (the robot's centre on the line counts), the opponents' goal area
        if (tx <= -L2 + pa_depth and abs(ty) <= pa_half) or (tx > ga_x0 and abs(ty) < ga_half):
            continue
        if (tx >= L2 - pa_depth and abs(ty) <= pa_half) and keep_out_of_area:
            continue
        score = position_value(tx, ty, opps, L2)
        score += 0.35 * min(lane_clear(x, y, tx, ty, opps, 1.5, 0.0), 0.5)
        if can_score and tx > 0.0 and L2 - tx < shoot_range:
            score += OPEN_GOAL_VALUE * min(shot_window(tx, ty, opps, L2, goal_half, shot_speed, POST_MARGIN)[1], 0.15)
        # away from opponents closing in: keep the body between them and the ball
        for j in range(opps.shape[0]):
            rx, ry = opps[j, 0] - x, opps[j, 1] - y
            d = math.hypot(rx, ry)
            if d < ESCAPE_RANGE:
                score -= 2.0 * max(0.0, (ux * rx + uy * ry) / d + 0.3) * (ESCAPE_RANGE - d) / ESCAPE_RANGE
        turn = 1.0 - (ux * c + uy * s)
        score -= 0.25 * turn
        score += LEAN * (ux * lean_x + uy * lean_y)
        if ux * c + uy * s < -0.3 and backed:
            score -= 5.0
        if dir_x == dir_x:
            score -= 0.3 * (1.0 - (ux * dir_x + uy * dir_y))
        if score > best_s:
            found, bx, by, bux, buy, best_s = True, tx, ty, ux, uy, score
    return found, bx, by, bux, buy
