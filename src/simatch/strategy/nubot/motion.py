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

import numba
import numpy as np

from ...compiled import entry
from ...exactmath import hypot, pymax, pymin, remainder
from ..base import RoundedMove
from .avoidance import no_charging, sub_target
from .geometry import TWO_PI
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
        # the last command's numbers at the messages' float32 precision (body vx, vy, w, then the target
        # asked for): `_go` writes them, a robot taking its place reads them with tolist (no message holds
        # this array) into a RoundedMove
        self.row = np.zeros(5, dtype=np.float32)
        ar = areas
        # the fixed numbers `_go` reads (see _C_*)
        self.consts = np.array(
            (
                self.xlim,
                self.ylim,
                self.clearance,
                self.ball_clearance,
                self.touch,
                params.contact_speed,
                self._two_turn_acc,
                period,
                ar.L2 if ar is not None else field.half_length,
                ar.goal_half if ar is not None else 0.5 * field.goal_width,
            )
        )
        # the fixed numbers, then `go`'s numbers of the call, for the kernel (`_go_packed`): those of each
        # call written (in one struct call) after the fixed ones at each call; never leaves this robot's Motion
        self.args = np.concatenate((self.consts, np.zeros(_N_ARGS)))
        self._args_buf = memoryview(self.args)
        # the compiled `_go_packed` for its argument types (float64 arrays: the boxes and the observation's
        # opponents and team table, C-contiguous, as `Areas.box_array` and `Observation` make them), called
        # without numba's dispatcher typing its arguments at every call
        self._go = entry(_go_packed, self.args, _NO_BOXES, _NO_BOXES, _NO_BOXES, self.row)

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

        The work is one compiled kernel (`_go`): the same float operations as the Python it replaced, with
        CPython's own hypot and remainder (simatch.exactmath), so the run is the same bit for bit."""
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
        if ball_obstacle is True:
            ball = self.ball_clearance
        else:
            ball = float(ball_obstacle or 0.0)
        if fence is None:
            fx = fy = fr = math.nan
        else:
            fx, fy, fr = fence
        # the kernel's numbers in one float64 array: one argument instead of twenty-seven, written in one call
        # (a kernel call costs some 200 instructions per argument, an array ~1 k)
        _PACK_ARGS(
            self._args_buf,
            _ARGS_AT,
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
        vx, vy, w, side, wx, wy = self._go(self.args, box_array, obs.opp_array, obs.mate_array, self.row)
        self.side = side
        self.last = (wx, wy, w)
        return (vx, vy, w)

    def move(self, role: int, action: int) -> RoundedMove:
        """The last `go` as a command: its body velocity, with the target it was asked for as the intent,
        all rounded as the messages take them (from `row`)."""
        vx, vy, w, ix, iy = self.row.tolist()
        return rounded_move(vx, vy, w, role, action, (ix, iy), ())

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
        return _keep_out_of_circle(x, y, vx, vy, cx, cy, r)

    def body(self, yaw: float, vx: float, vy: float, w: float) -> tuple[float, float, float]:
        """Team-frame velocity to the body frame, at the heading the robot will have half a period on."""
        h = yaw + 0.5 * w * self.period
        c, s = math.cos(h), math.sin(h)
        return (c * vx + s * vy, -s * vx + c * vy, w)


_NO_BOXES = np.zeros((0, 3))
_new = object.__new__


def rounded_move(vx: float, vy: float, w: float, role: int, action: int, intent: tuple, user: tuple) -> RoundedMove:
    """``RoundedMove(vx, vy, w, role, action, intent, user)``: the same object, its attributes written here (a
    class call with a Python ``__init__`` costs CPython 3.11 several times what a function's call does)."""
    move = _new(RoundedMove)
    move.vx, move.vy, move.w = vx, vy, w
    move.role, move.action, move.intent, move.user = role, action, intent, user
    return move


# Motion.args: Motion.consts (_C_*), then `_go`'s numbers of a call in the order of its arguments (the
# flags as 0.0/1.0, the robot's id and the avoidance side, -1, 0 or +1, as floats: exact)
_N_ARGS = 26
_PACK_ARGS = struct.Struct(f"{_N_ARGS}d").pack_into
_ARGS_AT = 10 * 8  # (bytes: after the ten fixed numbers)
# the indices of Motion.consts
_C_XLIM, _C_YLIM, _C_CLEAR, _C_BALL_CLEAR, _C_TOUCH, _C_CONTACT, _C_TWO_TURN_ACC, _C_PERIOD, _C_L2, _C_GOAL_HALF = (
    range(10)
)


@numba.njit(cache=True)
def _keep_out_of_circle(x, y, vx, vy, cx, cy, r):
    """`Motion.keep_out_of_circle`, compiled."""
    dx, dy = cx - x, cy - y
    d = hypot(dx, dy)
    if d > r + FENCE_RANGE or d < 1e-6:
        return vx, vy
    nx, ny = dx / d, dy / d
    inward = vx * nx + vy * ny
    gap = d - r - 0.1
    if gap > 0.0:
        # slow down in time: the drive brakes at about FENCE_BRAKING, a robot running in fast would
        # otherwise overrun the circle (a taker brushing the ball, a defender inside the 3 m)
        allowed = pymin(math.sqrt(2.0 * FENCE_BRAKING * gap), POSITION_GAIN * gap)
    else:
        # inside: move out, at 1 m/s at least, along the way out the target chose (straight away from
        # a ball near a line would drive into the boards)
        allowed = pymax(2.0 * gap, -1.0)
    if inward > allowed:
        vx -= (inward - allowed) * nx
        vy -= (inward - allowed) * ny
    return vx, vy


@numba.njit(cache=True)
def _go(
    mx,
    my,
    yaw,
    mvx,
    mvy,
    me_id,
    tx,
    ty,
    face,
    vmax,
    wmax,
    avoid,
    ball,
    end_speed,
    feed_x,
    feed_y,
    brake,
    gentle,
    turn_first,
    boxes,
    fence_x,
    fence_y,
    fence_r,
    max_x,
    opps,
    mates,
    bx,
    by,
    side,
    consts,
    row,
):
    """Motion.go, compiled: (body vx, vy, w, avoidance side, team-frame vx, vy). ``face``, ``fence_*`` and
    ``max_x`` are NaN where the Python takes None. Writes the body vx, vy, w and the target (tx, ty) as
    asked, rounded to float32 as the messages round them, into ``row`` (5,)."""
    row[3] = tx
    row[4] = ty
    xlim, ylim = consts[_C_XLIM], consts[_C_YLIM]
    tx = pymin(pymax(tx, -xlim), xlim)
    ty = pymin(pymax(ty, -ylim), ylim)
    d = hypot(tx - mx, ty - my)
    vx = vy = 0.0
    if d > 0.01 or end_speed > 0.0:
        sx, sy = tx, ty
        if boxes.shape[0] > 0:
            sx, sy = route(mx, my, tx, ty, boxes, consts[_C_L2], consts[_C_GOAL_HALF])
        if avoid:
            sx, sy, side = sub_target(
                mx, my, sx, sy, opps, mates, me_id, bx, by, ball, consts[_C_CLEAR], LOOK_AHEAD, side
            )
        speed = pymin(pymin(vmax, math.sqrt(end_speed * end_speed + 2.0 * brake * d)), POSITION_GAIN * d + end_speed)
        ex, ey = sx - mx, sy - my
        e = hypot(ex, ey)
        if e > 1e-9:
            vx, vy = ex / e * speed, ey / e * speed
    vx += feed_x
    vy += feed_y
    n = hypot(vx, vy)
    if n > vmax:
        vx, vy = vx / n * vmax, vy / n * vmax
    if gentle:
        vx, vy = no_charging(mx, my, mvx, mvy, vx, vy, opps, consts[_C_TOUCH], consts[_C_CONTACT], CHARGE_BRAKING)
    if fence_r == fence_r:  # not NaN: a fence
        vx, vy = _keep_out_of_circle(mx, my, vx, vy, fence_x, fence_y, fence_r)
    if max_x == max_x:
        vx = pymin(vx, 2.0 * (max_x - mx))
    if face != face:  # NaN: no heading wanted
        w = 0.0
    else:
        err = remainder(face - yaw, TWO_PI)
        aerr = abs(err)
        w = pymin(pymin(wmax, math.sqrt(consts[_C_TWO_TURN_ACC] * aerr)), HEADING_GAIN * aerr)
        if not err >= 0.0:
            w = -w
    speed = hypot(vx, vy)
    if speed * abs(w) > SPIN_COUPLING:
        if turn_first:
            k = SPIN_COUPLING / (speed * abs(w))
            vx, vy = vx * k, vy * k
        else:
            w = math.copysign(SPIN_COUPLING / speed, w)
    h = yaw + 0.5 * w * consts[_C_PERIOD]
    c, s = math.cos(h), math.sin(h)
    bvx, bvy = c * vx + s * vy, -s * vx + c * vy
    row[0] = bvx
    row[1] = bvy
    row[2] = w
    return bvx, bvy, w, side, vx, vy


@numba.njit(cache=True)
def _go_packed(args, boxes, opps, mates, row):
    """`_go` with its numbers in one float64 array ``args`` (Motion.args: the ten fixed numbers `_go` reads as
    ``consts``, then the call's in `_go`'s order of arguments, the robot's id, the flags and the avoidance
    side as floats), for a call of five arguments instead of thirty-one."""
    a = 10
    return _go(
        args[a],
        args[a + 1],
        args[a + 2],
        args[a + 3],
        args[a + 4],
        args[a + 5],
        args[a + 6],
        args[a + 7],
        args[a + 8],
        args[a + 9],
        args[a + 10],
        args[a + 11] != 0.0,
        args[a + 12],
        args[a + 13],
        args[a + 14],
        args[a + 15],
        args[a + 16],
        args[a + 17] != 0.0,
        args[a + 18] != 0.0,
        boxes,
        args[a + 19],
        args[a + 20],
        args[a + 21],
        args[a + 22],
        opps,
        mates,
        args[a + 23],
        args[a + 24],
        int(args[a + 25]),
        args,
        row,
    )
