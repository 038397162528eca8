"""What the example team's nodes share: robot names, the field (cm), the demo's decisions and the low-level
controller's law. Pure Python on the original's messages (nubot_common), no simatch inside: this is team
code, as any team would write it against the original interface.

The decisions are the original Simatch demo (its nubot_control.cpp, described in simatch's reference):
the robot nearest to the ball (the goalkeeper aside) is active, faces the ball and takes it with the
dribbler on, dribbles to the point (200, 300) cm, turns to the goal and shoots (ground kick, speed = its
distance to the goal / 100 m/s, at least 3) when its heading lies in the kick window; the others stand
still; set pieces take the original's two formations; STOP stops, PARK lines up at the side line.
Where the original breaks the MSL rules simatch's referee judges, or cannot score against a standing
team, it plays as NuBot's own code did instead: it dribbles towards the opponents' goal rather than to
the fixed point, at most 2.5 m from where it took the ball (NuBot's DribbleState keeps dribble targets
within 3 m), and shoots when there, or when a robot stands within 1.2 m ahead; it aims at the most open of
five points of the goal mouth (NuBot's evaluateKick looks for the open angle); it slows down near
other robots so as to meet them at no more than 1.2 m/s (MSL's charging rule); at the opponents'
restarts it keeps 3.5 m from the ball (the original's 3.2 m with its 20 cm arrival threshold broke the
3 m rule) and waits until the ball is in play; at its own restarts robot 3 waits 2.5 m beside the ball and the taker
passes to the nearest team-mate first (NuBot's StaticPass): a goal straight from a restart does not count.

``original=True`` (the launch files' ``original:=true``) keeps the original's own habits at the opponents'
restarts instead, as its C++ code plays: 3.2 m from the ball's centre, and for the ball at START whoever's
restart it is (it does not wait for the ball to be in play); the referee cautions it for that.
"""

from __future__ import annotations

import math
import re

# core.hpp: game commands, actions, roles
STOPROBOT, DROPBALL, STARTROBOT, PARKINGROBOT, TEST = 0, 13, 15, 25, 27
OUR_KICKOFF = 1
STUCKED, TURN_FOR_SHOOT, AT_SHOOT_SITUATION, POSITIONED = 0, 4, 6, 12
CATCH_POSITIONED, CATCH_BALL, CATCH_BALL_SLOW, MOVE_WITH_BALL, TELEOP_JOY, NO_ACTION = 11, 16, 17, 19, 20, 21
GOALIE, ACTIVE, NOROLE = 0, 1, 8
RUN = 1
MAXVEL, MAXW = 500.0, 10.0  # cm/s, rad/s (core.hpp)

ARRIVED = 20.0  # move2target's threshold [cm]
FACING = math.radians(8.0)  # move2ori's threshold
DRIBBLE_LIMIT = 250.0  # from where the ball was taken (the rule: 300)
BLOCKED_AHEAD = 120.0  # a robot this close ahead ends the dribble: shoot [cm]
CAREFUL_NEAR, CAREFUL_SPEED, CAREFUL_DECEL = 70.0, 120.0, 200.0  # near robots: slow enough to stop [cm, cm/s, cm/s2]
REST_AFTER_KICK = 20  # cycles
REST_AFTER_PASS = 60  # cycles: the taker leaves the ball to the receiver (a second touch would be a foul)
KEEP_AWAY, STAND_AT, ORIGINAL_STAND_AT = 300.0, 350.0, 320.0
THEIR_SET_PIECE = {1: (-1050.0, 0.0), 2: (-200.0, 100.0), 3: (-200.0, -100.0), 4: (-550.0, 200.0), 5: (-550.0, -200.0)}
OPPONENT_WAIT = 7.0  # [s]
AIM_YS = (0.0, -45.0, 45.0, -85.0, 85.0)  # points of the goal mouth (2.4 m wide) the shooter may aim at [cm]
KICK_WINDOW = 30.0  # the heading must point within this of the aim point on the goal line [cm]
ROBOT_RADIUS = 30.0  # [cm] what an obstacle blocks of a shot line


def parse_robot(name: str) -> tuple[str, int]:
    """``NuBot3`` -> ("NuBot", 3): the team prefix and the robot's id, as the original's nodes took them."""
    m = re.fullmatch(r"(.*?)(\d+)", name.strip("/"))
    if not m or not m.group(1):
        raise SystemExit(f"expected a robot name like NuBot3, got {name!r}")
    return m.group(1), int(m.group(2))


def wrap(a: float) -> float:
    return math.remainder(a, 2 * math.pi)


def hwcontrol(cmd) -> tuple[float, float, float]:
    """The original nubot_hwcontroller's law: from an ActionCmd (team frame, cm) to a body-frame VelCmd
    (cm/s, rad/s). Position P = 5 capped at maxvel, plus target_vel; heading P = 2 capped at maxw (3 rad/s
    unless catching the ball)."""
    vx = vy = w = 0.0
    if cmd.move_action != NO_ACTION:
        dx, dy = cmd.target.x - cmd.robot_pos.x, cmd.target.y - cmd.robot_pos.y
        dist = math.hypot(dx, dy)
        speed = min(5.0 * dist, cmd.maxvel)
        if dist > 1e-6:
            vx, vy = dx / dist * speed, dy / dist * speed
        vx += cmd.target_vel.x
        vy += cmd.target_vel.y
        norm = math.hypot(vx, vy)
        if norm > cmd.maxvel > 0:
            vx, vy = vx / norm * cmd.maxvel, vy / norm * cmd.maxvel
    if cmd.rotate_acton != NO_ACTION:
        maxw = cmd.maxw if cmd.move_action in (CATCH_POSITIONED, CATCH_BALL, CATCH_BALL_SLOW, TELEOP_JOY) else 3.0
        maxw = min(maxw, cmd.maxw)
        err = wrap(cmd.target_ori - cmd.robot_ori)
        if cmd.rotate_mode == 1 and err < 0:
            err += 2 * math.pi
        elif cmd.rotate_mode == -1 and err > 0:
            err -= 2 * math.pi
        w = max(-maxw, min(maxw, 2.0 * err))
    c, s = math.cos(cmd.robot_ori), math.sin(cmd.robot_ori)
    return c * vx + s * vy, -s * vx + c * vy, w


class Motion:
    """An ActionCmd's fields as the decision node fills them (move2target / move2ori)."""

    def __init__(self, action: int = NO_ACTION, role: int = NOROLE):
        self.target = None
        self.ori = None
        self.maxvel = 0.0
        self.maxw = 0.0
        self.dribble = False
        self.strength = 0.0
        self.action = action
        self.role = role


class Demo:
    """The decision of one robot (its nubot_control node), one call per world model."""

    def __init__(
        self, rid: int, goalkeeper: int = 1, half_length: float = 1100.0, half_width: float = 700.0, original=False
    ):
        self.rid = rid
        self.original = bool(original)
        self.stand_at = ORIGINAL_STAND_AT if self.original else STAND_AT
        self.goalkeeper = goalkeeper
        self.L2, self.W2 = half_length, half_width
        self.rest = 0
        self.last_mode = -1
        self.wait_from = None  # (time, ball x, ball y) of an opponents' restart
        self.pass_from = None  # (ball x, ball y) of our restart, until the ball is in play
        self.dribble_start = None
        self.near_robot = None  # distance to the nearest other robot [cm]

    def decide(self, wm, now: float) -> Motion:
        me = next((r for r in wm.robotinfo if r.AgentID == self.rid), None)
        mode = wm.coachinfo.MatchMode
        if me is None:
            return Motion()
        ball = wm.ballinfo[0] if wm.ballinfo else None
        self.near_robot = min((math.hypot(p.x - me.pos.x, p.y - me.pos.y) for p in wm.obstacleinfo.pos), default=None)
        self._follow_restart(mode, ball, now, any(r.isdribble for r in wm.robotinfo))
        if mode in (STOPROBOT, TEST):
            return Motion()
        if mode == PARKINGROBOT:
            return self.move(me, (-self.L2 + 150.0 * self.rid, -self.W2 + 20.0), math.pi / 2)
        if 1 <= mode <= DROPBALL:
            return self.set_piece(me, ball, mode)
        return self.play(wm, me, ball)

    def _follow_restart(self, mode, ball, now, held: bool) -> None:
        last = self.last_mode
        if mode == STARTROBOT and 1 <= last <= 12 and last % 2 == 0 and ball is not None and not self.original:
            self.wait_from = (now, ball.pos.x, ball.pos.y)
        if mode == STARTROBOT and 1 <= last <= 11 and last % 2 == 1 and ball is not None:
            self.pass_from = (ball.pos.x, ball.pos.y)
        if self.pass_from is not None and ball is not None:
            moved = math.hypot(ball.pos.x - self.pass_from[0], ball.pos.y - self.pass_from[1]) > 50.0
            if mode != STARTROBOT or (moved and not held):  # passed (or lost): the ball is in play
                self.pass_from = None
        if self.wait_from is not None and ball is not None:
            t0, x0, y0 = self.wait_from
            moved = math.hypot(ball.pos.x - x0, ball.pos.y - y0) > 50.0
            if mode != STARTROBOT or now - t0 > OPPONENT_WAIT or moved:
                self.wait_from = None
        self.last_mode = mode

    def move(self, me, target, ori, action=POSITIONED, role=NOROLE, dribble=False) -> Motion:
        """move2target and move2ori: speed limit = distance (cm/s), turn-rate limit = 2 |error|."""
        m = Motion(action, role)
        d = math.hypot(target[0] - me.pos.x, target[1] - me.pos.y)
        if d > ARRIVED:
            m.target = target
        m.maxvel = min(MAXVEL, max(d, 5.0))
        m.ori = ori
        m.maxw = min(MAXW, max(2.0 * abs(wrap(ori - me.heading.theta)), 0.05))
        m.dribble = dribble
        if self.near_robot is not None:  # able to slow to 1.2 m/s by the time it reaches another robot
            room = max(0.0, self.near_robot - CAREFUL_NEAR)
            m.maxvel = min(m.maxvel, math.sqrt(CAREFUL_SPEED**2 + 2.0 * CAREFUL_DECEL * room))
        return m

    def set_piece(self, me, ball, mode) -> Motion:
        bx, by = (ball.pos.x, ball.pos.y) if ball is not None else (0.0, 0.0)
        ours = mode % 2 == 1 and mode != DROPBALL
        if ours and self.rid == 2:  # the taker, one metre behind the ball
            target = (bx - 100.0, by)
        elif ours and self.rid == 3:  # the receiver, 2.5 m beside the ball, towards the middle (or its side)
            side = -1.0 if (by > 0 or (by == 0 and me.pos.y < 0)) else 1.0
            target = (bx - 60.0, by + side * 250.0)
        else:
            tx, ty = THEIR_SET_PIECE.get(self.rid, (-550.0, 0.0))
            in_own_area = tx <= -self.L2 + 225.0 and abs(ty) <= 345.0
            d = math.hypot(tx - bx, ty - by)
            if d < KEEP_AWAY and not in_own_area:
                d = d or 1.0
                tx, ty = bx + (tx - bx) / d * self.stand_at, by + (ty - by) / d * self.stand_at
            target = (tx, ty)
        return self.move(me, target, math.atan2(by - me.pos.y, bx - me.pos.x))

    def play(self, wm, me, ball) -> Motion:
        if ball is None or not ball.pos_known:
            return Motion(action=NO_ACTION)
        if self.rest > 0:
            self.rest -= 1
        if not self.is_active(wm, ball) or self.wait_from is not None:
            self.dribble_start = None
            return Motion()
        if not me.isdribble:
            self.dribble_start = None
            face = math.atan2(ball.pos.y - me.pos.y, ball.pos.x - me.pos.x)
            where = (me.pos.x, me.pos.y) if abs(wrap(face - me.heading.theta)) > FACING else (ball.pos.x, ball.pos.y)
            return self.move(me, where, face, CATCH_BALL, ACTIVE, dribble=self.rest == 0)
        if self.dribble_start is None:
            self.dribble_start = (me.pos.x, me.pos.y)
        if self.pass_from is not None:
            return self.restart_pass(wm, me)
        point = self.dribble_point(me)
        if math.hypot(point[0] - me.pos.x, point[1] - me.pos.y) > 30.0 and not self.blocked(wm, me):
            face = math.atan2(point[1] - me.pos.y, point[0] - me.pos.x)
            return self.move(me, point, face, MOVE_WITH_BALL, ACTIVE, dribble=True)
        aim = self.aim(wm, me)
        face = math.atan2(aim[1] - me.pos.y, aim[0] - me.pos.x)
        m = self.move(me, (me.pos.x, me.pos.y), face, TURN_FOR_SHOOT, ACTIVE, dribble=True)
        lo = math.atan2(aim[1] - KICK_WINDOW - me.pos.y, aim[0] - me.pos.x)
        hi = math.atan2(aim[1] + KICK_WINDOW - me.pos.y, aim[0] - me.pos.x)
        if lo <= me.heading.theta <= hi:
            m.strength = max(3.0, math.hypot(aim[0] - me.pos.x, aim[1] - me.pos.y) / 100.0)
            m.dribble = False
            m.action = AT_SHOOT_SITUATION
            self.rest = REST_AFTER_KICK
        return m

    def restart_pass(self, wm, me) -> Motion:
        """Our restart: turn to the nearest field team-mate and pass to it (ground kick)."""
        mates = [r for r in wm.robotinfo if r.isvalid and r.AgentID not in (self.rid, self.goalkeeper)]
        if not mates:
            self.pass_from = None
            return self.move(me, (me.pos.x, me.pos.y), me.heading.theta, TURN_FOR_SHOOT, ACTIVE, dribble=True)
        mate = min(mates, key=lambda r: math.hypot(r.pos.x - me.pos.x, r.pos.y - me.pos.y))
        face = math.atan2(mate.pos.y - me.pos.y, mate.pos.x - me.pos.x)
        m = self.move(me, (me.pos.x, me.pos.y), face, TURN_FOR_SHOOT, ACTIVE, dribble=True)
        if abs(wrap(face - me.heading.theta)) < math.radians(4.0):
            dist = math.hypot(mate.pos.x - me.pos.x, mate.pos.y - me.pos.y)
            m.strength = min(6.0, max(2.5, 1.2 * dist / 100.0))
            m.dribble = False
            m.action = AT_SHOOT_SITUATION
            self.rest = REST_AFTER_PASS
        return m

    def dribble_point(self, me):
        """Towards the middle of the opponents' goal, at most DRIBBLE_LIMIT from where the ball was taken."""
        sx, sy = self.dribble_start
        gx, gy = self.L2, 0.0
        d = math.hypot(gx - sx, gy - sy) or 1.0
        reach = min(DRIBBLE_LIMIT, max(0.0, d - 400.0))
        return (sx + (gx - sx) / d * reach, sy + (gy - sy) / d * reach)

    def blocked(self, wm, me) -> bool:
        """A robot within BLOCKED_AHEAD in front of this one (within 45 degrees of its heading)."""
        for p in wm.obstacleinfo.pos:
            dx, dy = p.x - me.pos.x, p.y - me.pos.y
            if math.hypot(dx, dy) < BLOCKED_AHEAD and abs(wrap(math.atan2(dy, dx) - me.heading.theta)) < math.pi / 4:
                return True
        return False

    def aim(self, wm, me):
        """The point of the goal mouth whose shot line passes farthest from every obstacle."""
        gx = self.L2
        best, best_clear = (gx, 0.0), -math.inf
        for y in AIM_YS:
            clear = math.inf
            ax, ay = gx - me.pos.x, y - me.pos.y
            length = math.hypot(ax, ay) or 1.0
            for p in wm.obstacleinfo.pos:
                ox, oy = p.x - me.pos.x, p.y - me.pos.y
                along = (ox * ax + oy * ay) / length
                if 0.0 < along < length:
                    clear = min(clear, abs(ox * ay - oy * ax) / length)
            if clear > best_clear + 1.0:
                best, best_clear = (gx, y), clear
        return best

    def is_active(self, wm, ball) -> bool:
        """The nearest valid field robot to the ball (ties to the lower id)."""
        best, best_d = None, math.inf
        for r in sorted(wm.robotinfo, key=lambda r: r.AgentID):
            if not r.isvalid or r.AgentID == self.goalkeeper:
                continue
            d = math.hypot(ball.pos.x - r.pos.x, ball.pos.y - r.pos.y)
            if d < best_d:
                best, best_d = r.AgentID, d
        return best == self.rid
