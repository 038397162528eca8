"""The goalkeeper: keeps its line, blocks shots (lobs included) where the predicted ball path crosses it,
and clears balls that stop in its penalty area.

Standing: on its line in front of the goal, where the bisector of the angle the ball sees the two posts
under crosses that line (the position that halves the open goal on both sides).

Blocking: the last ball observations are fitted by a straight line on the floor and a parabola in the air
(z = z0 + vz t - g t^2 / 2), which smooths noisy perception and gives a lob's height at the goal. A ball
that will cross the goal line between the posts and under the bar is a threat: the keeper runs to where
the path crosses its line, or, for a lob that would pass over it there, to where the ball comes down to
its height in front of the goal.
"""

from __future__ import annotations

import math
from collections import deque

from ..base import Command
from ..roles import ACTIONS, ROLES
from .active import BallPlayer
from .ballpath import GRAVITY
from .gameflow import PHASES, GameFlow
from .geometry import clamp
from .motion import Motion
from .observation import Observation
from .params import NubotParams
from .picture import Picture
from .positions import Areas

# (what `decide` reads at every tick, as module constants)
_PLAY = PHASES.PLAY
_GOALIE, _CATCH_POSITIONED, _POSITIONED = ROLES.GOALIE, ACTIONS.CATCH_POSITIONED, ACTIONS.POSITIONED

LOB_MIN, LOB_MAX = 3.0, 9.0  # a clearance lob goes to a team-mate this far away (10 m/s reaches 9.8 m) [m]

LINE_DEPTH = 0.7  # the keeper's line, in front of the goal line [m]
KEEPER_HEIGHT = 0.75  # a ball below this height hits the keeper [m]
HISTORY = 6


class BallTracker:
    """The last few ball observations and a least-squares fit of its flight."""

    def __init__(self):
        self.samples: deque = deque(maxlen=HISTORY)

    def add(self, t: float, x: float, y: float, z: float) -> None:
        if self.samples and t - self.samples[-1][0] > 0.2:
            self.samples.clear()  # a gap: old samples belong to another flight
        self.samples.append((t, x, y, z))

    def vertical(self) -> tuple[float, float] | None:
        """(z, vz) now, fitted with gravity known, or None with too few samples."""
        n = len(self.samples)
        if n < 3:
            return None
        t_last = self.samples[-1][0]
        ts = [s[0] - t_last for s in self.samples]
        zs = [s[3] + 0.5 * GRAVITY * tt * tt for s, tt in zip(self.samples, ts)]
        mt = sum(ts) / n
        mz = sum(zs) / n
        var = sum((tt - mt) ** 2 for tt in ts)
        if var < 1e-12:
            return None
        vz = sum((tt - mt) * (z - mz) for tt, z in zip(ts, zs)) / var
        return mz - vz * mt, vz


class Goalkeeper:
    def __init__(self, params: NubotParams, motion: Motion, areas: Areas, field, player: BallPlayer):
        self.p = params
        self.motion = motion
        self.areas = areas
        self.player = player
        self.goal_half = 0.5 * field.goal_width
        self.goal_height = field.goal_height
        self.line_x = -areas.L2 + LINE_DEPTH
        self.tracker = BallTracker()

    def decide(self, obs: Observation, pic: Picture, flow: GameFlow) -> Command:
        me = obs.me
        if obs.ball_seen:
            self.tracker.add(obs.t, obs.bx, obs.by, obs.bz)
        if flow.phase == _PLAY and pic.goalie_plays:
            return self.play_ball(obs, pic, flow)
        target, urgent = self.block_point(obs)
        face = math.atan2(obs.by - me.y, obs.bx - me.x)
        vmax = self.p.max_speed + (1.0 if urgent else 0.0)
        motion = self.motion
        motion.go(obs, target[0], target[1], face, vmax, self.p.max_turn, avoid=False, brake=6.0 if urgent else None)
        return motion.move(_GOALIE, _CATCH_POSITIONED if urgent else _POSITIONED)

    # --- where to stand ------------------------------------------------------------------------------------
    def block_point(self, obs: Observation) -> tuple[tuple[float, float], bool]:
        gl = -self.areas.L2
        gh = self.goal_half
        bx, by = obs.bx, obs.by
        speed = obs.ball_speed
        ymax = gh - 0.15
        if speed > 0.5 and obs.bvx < -0.3:
            ux, uy = obs.bvx / speed, obs.bvy / speed
            s_line = (gl - bx) / ux
            stop = speed * speed / (2.0 * max(self.p.ball_deceleration, 1e-3))
            y_goal = by + uy * s_line
            if abs(y_goal) < gh + 0.35 and s_line <= stop + 0.5:
                t_line = s_line / speed
                s_keeper = (self.line_x - bx) / ux
                fit = self.tracker.vertical()
                if fit is not None and (fit[0] > 0.2 or fit[1] > 0.5):
                    z0, vz = fit
                    z_goal = z0 + vz * t_line - 0.5 * GRAVITY * t_line * t_line
                    if z_goal > self.goal_height + 0.11:
                        return self.standing_point(bx, by), False  # over the bar
                    t_k = s_keeper / speed
                    z_k = z0 + vz * t_k - 0.5 * GRAVITY * t_k * t_k
                    if z_k > KEEPER_HEIGHT:
                        # it would pass over the keeper on its line: meet it where it comes down
                        t_down = (vz + math.sqrt(max(0.0, vz * vz + 2 * GRAVITY * (z0 - KEEPER_HEIGHT)))) / GRAVITY
                        dx, dy = bx + ux * speed * t_down, by + uy * speed * t_down
                        if self.areas.near_own_penalty_area(dx, dy, -0.2) and dx > gl + 0.3:
                            return (dx, dy), True
                y_k = by + uy * s_keeper
                return (self.line_x, clamp(y_k, -ymax, ymax)), True
        return self.standing_point(bx, by), False

    def standing_point(self, bx: float, by: float) -> tuple[float, float]:
        """On the keeper's line where the bisector of the ball's view of the goal crosses it."""
        gl, gh = -self.areas.L2, self.goal_half
        a1 = math.atan2(gh - by, gl - bx)
        a2 = math.atan2(-gh - by, gl - bx)
        mid = math.atan2(math.sin(a1) + math.sin(a2), math.cos(a1) + math.cos(a2))
        c = math.cos(mid)
        if abs(c) < 1e-6:
            y = clamp(by, -gh, gh)
        else:
            y = by + math.tan(mid) * (self.line_x - bx)
        return self.line_x, clamp(y, -(gh - 0.25), gh - 0.25)

    # --- a ball in the penalty area ----------------------------------------------------------------------
    def play_ball(self, obs: Observation, pic: Picture, flow: GameFlow) -> Command:
        me = obs.me
        a = self.areas
        if not me.holding:
            cmd = self.player.fetch(obs, pic, role=ROLES.GOALIE, stay_out_own_area=False)
            if cmd.intent is not None:
                # stay inside the penalty area
                tx = clamp(cmd.intent[0], -a.L2 + 0.2, -a.L2 + a.pa_depth - 0.1)
                ty = clamp(cmd.intent[1], -a.pa_half + 0.1, a.pa_half - 0.1)
                if (tx, ty) != cmd.intent:
                    face = math.atan2(obs.by - me.y, obs.bx - me.x)
                    cmd.vx, cmd.vy, cmd.w = self.motion.go(obs, tx, ty, face, self.p.max_speed, self.p.max_turn)
            return cmd
        best = self.player.best_pass(obs)
        if best is not None:
            plan = ("pass", best[2], best[3], best[4], best[1])
        else:
            plan = self.clearance(obs)
        return self.player.execute(obs, plan, ROLES.GOALIE)

    def clearance(self, obs: Observation) -> tuple:
        """A lob up the field, to the side with more room, landing at the team-mate nearest to that point (MSL:
        a lob from the own half must come down within 3 m of a team-mate); with no team-mate in a lob's reach, a
        ground clearance to that point instead."""
        side = 1.0 if sum(o[1] for o in obs.opps if o[0] < 0.0) < 0.0 else -1.0
        tx, ty = -2.0, side * 4.0
        reach = [
            m
            for m in obs.mates
            if m.valid and not m.is_goalie and LOB_MIN < math.hypot(m.x - obs.bx, m.y - obs.by) < LOB_MAX
        ]
        if not reach:
            return ("clear", tx, ty, 6.0, 0)
        mate = min(reach, key=lambda m: math.hypot(m.x - tx, m.y - ty))
        d = math.hypot(mate.x - obs.bx, mate.y - obs.by)
        return ("lob", mate.x, mate.y, min(10.0, math.sqrt(d * GRAVITY / 0.96)), 0)
