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
import struct

import numpy as np

from ...compiled import Array, Float, Matrix, bind, kernel
from ..base import Command
from .avoidance import no_charging, sub_target
from .geometry import _wrap
from .observation import Observation
from .params import NubotParams
from .positions import route

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
        # the last `go`'s command: body vx, vy, w and the target asked for (see `move`)
        self.command = (0.0, 0.0, 0.0, 0.0, 0.0)
        # what `steer` reads: the fixed numbers, written here, then each call's, written by `go` in one struct
        # call through a float64 view of the same memory (never leaves this robot's Motion)
        self.args = np.zeros(1, dtype=STEER_ARGS)
        fixed = self.args[0]
        fixed["xlim"], fixed["ylim"] = self.xlim, self.ylim
        fixed["clearance"], fixed["ball_clearance"], fixed["touch"] = self.clearance, self.ball_clearance, self.touch
        fixed["contact_speed"], fixed["two_turn_acc"], fixed["period"] = (
            params.contact_speed,
            self._two_turn_acc,
            period,
        )
        fixed["half_length"] = areas.L2 if areas is not None else field.half_length
        fixed["goal_half"] = areas.goal_half if areas is not None else 0.5 * field.goal_width
        self._call_buf = memoryview(self.args.view(np.float64))
        self._steer = bind(steer)
        self._to_body = bind(to_body)

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
        line it must not cross (the half-way line at a kick-off).

        The work is one compiled kernel, `steer`."""
        me = obs.me
        c = obs.coach
        if c is not None:  # the speed limits the coach allows (CoachInfo max_vel / max_w)
            # (min(vmax, c.max_vel) and min(wmax, c.max_w), inline: the first unless the second is smaller)
            lim = c.max_vel
            if lim > 0.0 and lim < vmax:
                vmax = lim
            lim = c.max_w
            if lim > 0.0 and lim < wmax:
                wmax = lim
        box_array = self.areas.box_array(boxes) if boxes else _NO_BOXES
        ball = self.ball_clearance if ball_obstacle is True else float(ball_obstacle or 0.0)
        fx, fy, fr = _NO_FENCE if fence is None else fence
        # the call's fields of `args` (STEER_CALL's order), written in one call
        _PACK_CALL(
            self._call_buf,
            _CALL_AT,
            me.x,
            me.y,
            me.yaw,
            me.vx,
            me.vy,
            me.id,
            tx,
            ty,
            math.nan if face is None else face,
            vmax,
            wmax,
            avoid,
            ball,
            end_speed,
            feed[0],
            feed[1],
            self.p.braking if brake is None else brake,
            gentle and bool(obs.opps),
            turn_first,
            fx,
            fy,
            fr,
            math.nan if max_x is None else max_x,
            obs.bx,
            obs.by,
            self.side,
        )
        vx, vy, w, side, wx, wy = self._steer(self.args, box_array, obs.opp_array, obs.mate_array)
        self.side = side
        self.last = (wx, wy, w)
        self.command = (vx, vy, w, tx, ty)
        return (vx, vy, w)

    def turn_rate(self, err: float, wmax: float) -> float:
        """The turn rate for heading error ``err`` (`turn_rate`)."""
        return turn_rate(err, wmax, self._two_turn_acc)

    def body(self, yaw: float, vx: float, vy: float, w: float) -> tuple[float, float, float]:
        """Team-frame velocity to the body frame (`to_body`)."""
        bx, by = self._to_body(yaw, vx, vy, w, self.period)
        return bx, by, w

    def move(self, role: int, action: int) -> Command:
        """The last `go` as a command: its body velocity, with the target it was asked for as the intent."""
        vx, vy, w, tx, ty = self.command
        return _move(vx, vy, w, role, action, (tx, ty))


_NO_BOXES = np.zeros((0, 3))
_NO_FENCE = (math.nan, math.nan, math.nan)
_move = Command.move


#: `steer`'s numbers: a robot's fixed ones (STEER_FIXED), then those of a call (STEER_CALL, as `Motion.go` gets
#: them; the flags as 0.0/1.0, the robot's id and the avoidance side, -1, 0 or +1, as floats: exact)
STEER_FIXED = (
    "xlim",
    "ylim",
    "clearance",
    "ball_clearance",
    "touch",
    "contact_speed",
    "two_turn_acc",
    "period",
    "half_length",
    "goal_half",
)
STEER_CALL = (
    "x",
    "y",
    "yaw",
    "vx",
    "vy",
    "id",
    "tx",
    "ty",
    "face",
    "vmax",
    "wmax",
    "avoid",
    "ball",
    "end_speed",
    "feed_x",
    "feed_y",
    "brake",
    "gentle",
    "turn_first",
    "fence_x",
    "fence_y",
    "fence_r",
    "max_x",
    "bx",
    "by",
    "side",
)
STEER_ARGS = np.dtype([(name, np.float64) for name in STEER_FIXED + STEER_CALL])
_PACK_CALL = struct.Struct(f"{len(STEER_CALL)}d").pack_into
_CALL_AT = STEER_ARGS.fields[STEER_CALL[0]][1]  # (in bytes)


@kernel
def turn_rate(err, wmax, two_turn_acc):
    """The turn rate for heading error ``err``: as fast as the robot can still brake (turning acceleration
    ``two_turn_acc`` / 2) to face the heading, within ``wmax``, proportional (HEADING_GAIN) near it."""
    aerr = abs(err)
    w = min(min(wmax, math.sqrt(two_turn_acc * aerr)), HEADING_GAIN * aerr)
    return w if err >= 0.0 else -w


@kernel(yaw=Float, vx=Float, vy=Float, w=Float, period=Float)
def to_body(yaw, vx, vy, w, period):
    """Team-frame velocity (vx, vy) of a robot at heading ``yaw`` turning at ``w`` in the body frame, at the
    heading it will have half a control period on: a robot that turns while it drives keeps its course."""
    h = yaw + 0.5 * w * period
    c, s = math.cos(h), math.sin(h)
    return c * vx + s * vy, -s * vx + c * vy


@kernel
def keep_out_of_circle(x, y, vx, vy, cx, cy, r):
    """The velocity (vx, vy) of a robot at (x, y) with its part towards the centre of the circle (cx, cy, r)
    capped so that the robot stops at the circle (and leaves it at once if it is inside)."""
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


@kernel(args=Array(STEER_ARGS, 1), boxes=Matrix, opps=Matrix, mates=Matrix)
def steer(args, boxes, opps, mates):
    """`Motion.go`'s command: (body vx, vy, w, avoidance side, team-frame vx, vy) of the call in ``args[0]``
    (STEER_ARGS; ``face``, ``fence_*`` and ``max_x`` NaN where `go` takes None), ``boxes`` (K, 3) the areas to
    go round, ``opps`` and ``mates`` the observation's opponents and team table."""
    a = args[0]
    mx, my, yaw, me_id = a.x, a.y, a.yaw, a.id
    tx, ty, face, vmax, wmax = a.tx, a.ty, a.face, a.vmax, a.wmax
    end_speed, brake, side = a.end_speed, a.brake, int(a.side)
    fence_x, fence_y, fence_r, max_x = a.fence_x, a.fence_y, a.fence_r, a.max_x
    xlim, ylim = a.xlim, a.ylim
    tx = min(max(tx, -xlim), xlim)
    ty = min(max(ty, -ylim), ylim)
    d = math.hypot(tx - mx, ty - my)
    vx = vy = 0.0
    if d > 0.01 or end_speed > 0.0:
        sx, sy = tx, ty
        if boxes.shape[0] > 0:
            sx, sy = route(mx, my, tx, ty, boxes, a.half_length, a.goal_half)
        if a.avoid != 0.0:
            sx, sy, side = sub_target(
                mx, my, sx, sy, opps, mates, me_id, a.bx, a.by, a.ball, a.clearance, LOOK_AHEAD, side
            )
        speed = min(min(vmax, math.sqrt(end_speed * end_speed + 2.0 * brake * d)), POSITION_GAIN * d + end_speed)
        ex, ey = sx - mx, sy - my
        e = math.hypot(ex, ey)
        if e > 1e-9:
            vx, vy = ex / e * speed, ey / e * speed
    vx += a.feed_x
    vy += a.feed_y
    n = math.hypot(vx, vy)
    if n > vmax:
        vx, vy = vx / n * vmax, vy / n * vmax
    if a.gentle != 0.0:
        vx, vy = no_charging(mx, my, a.vx, a.vy, vx, vy, opps, a.touch, a.contact_speed, CHARGE_BRAKING)
    if fence_r == fence_r:  # not NaN: a fence
        vx, vy = keep_out_of_circle(mx, my, vx, vy, fence_x, fence_y, fence_r)
    if max_x == max_x:
        vx = min(vx, 2.0 * (max_x - mx))
    w = 0.0 if face != face else turn_rate(_wrap(face - yaw), wmax, a.two_turn_acc)  # NaN: no heading
    speed = math.hypot(vx, vy)
    if speed * abs(w) > SPIN_COUPLING:
        if a.turn_first != 0.0:
            k = SPIN_COUPLING / (speed * abs(w))
            vx, vy = vx * k, vy * k
        else:
            w = math.copysign(SPIN_COUPLING / speed, w)
    bvx, bvy = to_body(yaw, vx, vy, w, a.period)
    return bvx, bvy, w, side, vx, vy
