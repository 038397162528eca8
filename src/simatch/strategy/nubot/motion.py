"""From "go there, face that way" to a body-frame velocity command.

* Path: sub-target obstacle avoidance (avoidance.py) around every other robot.
* Speed: as fast as allowed while the robot can still brake to the wanted end speed at the target
  (v = sqrt(v_end^2 + 2 a d)), proportional in the last centimetres so that it settles without dithering.
* No charging: the velocity towards each opponent nearby is capped so that the robot could slow down to
  a gentle contact speed before touching it (the MSL rules let robots touch, not ram).
* Heading: the same braking law on the angle error, within the turn-rate limit, and turning slower while
  driving fast (|v| |w| bounded: the wheels' acceleration limit makes fast turns at speed cost speed).
* The world (team-frame) velocity is turned into the body frame at the middle of the control period, so
  that a robot that turns while it drives keeps its course.
"""

from __future__ import annotations

import math

from .avoidance import no_charging, sub_target
from .geometry import TWO_PI
from .observation import Observation
from .params import NubotParams

#: within this distance the position law is proportional (gain POSITION_GAIN)
POSITION_GAIN = 3.0
#: largest |v| |w| [m/s^2]. A body-frame command for a fixed course turns with the robot, at |v| |w|; the
#: wheels follow at 2.5 m/s^2 at most, so a robot turning fast at speed never reaches its speed (measured:
#: starting at 3.5 m/s with 2 rad/s it only reaches 2.5 m/s). Turning slowly at speed leaves the wheels the
#: acceleration to get there; the robot turns fully once it slows down near its target.
SPIN_COUPLING = 1.5
#: robots are avoided where they will be this much later [s]
LOOK_AHEAD = 0.3
#: the braking assumed when closing in on an opponent (below the drive's, which also has to turn) [m/s^2]
CHARGE_BRAKING = 2.0
HEADING_GAIN = 5.0
#: a fenced circle (a restart's ball) is approached at a speed from which the robot can stop at it, from
#: this far out [m], braking at [m/s^2]
FENCE_RANGE = 3.0
FENCE_BRAKING = 2.0


class Motion:
    def __init__(self, params: NubotParams, period: float, field, areas=None):
        self.p = params
        self.areas = areas
        self.period = period
        self.field = field
        self.side = 0  # side of the last avoidance, for its hysteresis
        self.last = (0.0, 0.0, 0.0)  # the last course: team-frame velocity and turn rate
        self.clearance = 2.0 * params.robot_radius + 0.3  # robot to robot centres
        self.ball_clearance = params.robot_radius + 0.11 + 0.12  # robot centre to ball centre
        self.touch = 2.0 * params.robot_radius + 0.05  # robots closer than this touch
        self.xlim = field.half_length + 0.9
        self.ylim = field.half_width + 0.9
        self._two_turn_acc = 2.0 * params.turn_acceleration

    # -----------------------------------------------------------------------------------------------------
    def go(
        self,
        obs: Observation,
        tx: float,
        ty: float,
        face: float | None,
        vmax: float,
        wmax: float,
        avoid: bool = True,
        ball_obstacle: bool | float = False,
        end_speed: float = 0.0,
        feed: tuple[float, float] = (0.0, 0.0),
        brake: float | None = None,
        gentle: bool = True,
        turn_first: bool = False,
        boxes: list[tuple[float, float, float]] = (),
        fence: tuple[float, float, float] | None = None,
        max_x: float | None = None,
    ) -> tuple[float, float, float]:
        """Body-frame (vx, vy, w) towards (tx, ty) and heading ``face`` (None: keep turning as is, w = 0).
        Turning and driving fast at once cost the same wheel acceleration: by default the robot keeps its
        speed and turns slowly; with ``turn_first`` it slows down to turn (to take the ball, the heading
        matters more). ``boxes`` are areas to go round (see `Areas.route`); ``fence`` = (x, y, r) is a
        circle the robot must not enter (a restart's ball), whatever avoiding others asks; ``max_x`` a
        line it must not cross (the half-way line at a kick-off)."""
        me = obs.me
        mx, my = me.x, me.y
        c = obs.coach
        if c is not None:  # the speed limits the coach allows (CoachInfo max_vel / max_w)
            if c.max_vel > 0.0:
                vmax = min(vmax, c.max_vel)
            if c.max_w > 0.0:
                wmax = min(wmax, c.max_w)
        # keep targets on the floor, inside the boards
        tx = min(max(tx, -self.xlim), self.xlim)
        ty = min(max(ty, -self.ylim), self.ylim)
        d = math.hypot(tx - mx, ty - my)
        vx = vy = 0.0
        if d > 0.01 or end_speed > 0.0:
            sx, sy = tx, ty
            if boxes:
                sx, sy = self.areas.route(mx, my, tx, ty, boxes)
            if avoid:
                ball = self.ball_clearance if ball_obstacle is True else float(ball_obstacle or 0.0)
                sx, sy, self.side = sub_target(
                    mx,
                    my,
                    sx,
                    sy,
                    obs.opp_array,
                    obs.mate_array,
                    me.id,
                    obs.bx,
                    obs.by,
                    ball,
                    self.clearance,
                    LOOK_AHEAD,
                    self.side,
                )
            a = self.p.braking if brake is None else brake
            speed = min(vmax, math.sqrt(end_speed * end_speed + 2.0 * a * d), POSITION_GAIN * d + end_speed)
            ex, ey = sx - mx, sy - my
            e = math.hypot(ex, ey)
            if e > 1e-9:
                vx, vy = ex / e * speed, ey / e * speed
        vx += feed[0]
        vy += feed[1]
        n = math.hypot(vx, vy)
        if n > vmax:
            vx, vy = vx / n * vmax, vy / n * vmax
        if gentle and obs.opps:
            vx, vy = no_charging(
                mx, my, me.vx, me.vy, vx, vy, obs.opp_array, self.touch, self.p.contact_speed, CHARGE_BRAKING
            )
        if fence is not None:
            vx, vy = self.keep_out_of_circle(mx, my, vx, vy, fence[0], fence[1], fence[2])
        if max_x is not None:
            vx = min(vx, 2.0 * (max_x - mx))
        yaw = me.yaw
        if face is None:
            w = 0.0
        else:  # (self.turn_rate(wrap(face - yaw), wmax), inline)
            err = math.remainder(face - yaw, TWO_PI)
            aerr = abs(err)
            w = min(wmax, math.sqrt(self._two_turn_acc * aerr), HEADING_GAIN * aerr)
            if not err >= 0.0:
                w = -w
        # turning while driving costs the wheels |v| |w| of acceleration: keep the product within what they
        # can give, so that the robot keeps its speed (it turns fully once it slows down near the target)
        speed = math.hypot(vx, vy)
        if speed * abs(w) > SPIN_COUPLING:
            if turn_first:
                k = SPIN_COUPLING / (speed * abs(w))
                vx, vy = vx * k, vy * k
            else:
                w = math.copysign(SPIN_COUPLING / speed, w)
        self.last = (vx, vy, w)
        h = yaw + 0.5 * w * self.period  # (self.body, inline)
        c, s = math.cos(h), math.sin(h)
        return (c * vx + s * vy, -s * vx + c * vy, w)

    def turn_rate(self, err: float, wmax: float) -> float:
        a = abs(err)
        w = min(wmax, math.sqrt(self._two_turn_acc * a), HEADING_GAIN * a)
        return w if err >= 0.0 else -w

    @staticmethod
    def keep_out_of_circle(
        x: float, y: float, vx: float, vy: float, cx: float, cy: float, r: float
    ) -> tuple[float, float]:
        """The velocity with its part towards the circle's centre capped so that the robot stops at the
        circle (and leaves it at once if it is inside)."""
        dx, dy = cx - x, cy - y
        d = math.hypot(dx, dy)
        if d > r + FENCE_RANGE or d < 1e-6:
            return vx, vy
        nx, ny = dx / d, dy / d
        inward = vx * nx + vy * ny
        gap = d - r - 0.1
        if gap > 0.0:
            # slow down in time: the drive brakes at about FENCE_BRAKING, a robot running in fast would
            # otherwise overrun the circle (a taker brushing the ball, a defender inside the 3 m)
            allowed = min(math.sqrt(2.0 * FENCE_BRAKING * gap), POSITION_GAIN * gap)
        else:
            # inside: move out, at 1 m/s at least, along the way out the target chose (straight away from
            # a ball near a line would drive into the boards)
            allowed = max(2.0 * gap, -1.0)
        if inward > allowed:
            vx -= (inward - allowed) * nx
            vy -= (inward - allowed) * ny
        return vx, vy

    def body(self, yaw: float, vx: float, vy: float, w: float) -> tuple[float, float, float]:
        """Team-frame velocity to the body frame, at the heading the robot will have half a period on."""
        h = yaw + 0.5 * w * self.period
        c, s = math.cos(h), math.sin(h)
        return (c * vx + s * vy, -s * vx + c * vy, w)
