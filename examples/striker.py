"""An example team for simatch: the tutorial's (docs/strategy.md). Short, and it plays by the rules:

* every robot slows down as it comes near an opponent and goes round the ones in its way (the referee books
  a robot that drives into another faster than 1.5 m/s: charging), and never pushes;
* the field robot nearest to the ball takes it, from behind and facing the goal when it has the time,
  carries it a short way (the rules allow 3 m, forwards) and shoots, from close in or when an opponent
  presses it in their half; a ball won in our own half goes to the team-mate waiting in the opponents' half
  first (a goal counts only after such a pass, MSL RC-10.1.2), or is played into their half;
* at our restarts the robot nearest to the ball passes to a team-mate with one touch (a goal straight from
  a restart does not count, nor a second touch by the taker), at theirs everybody keeps 3 m from the ball
  until it is in play; at a kick-off everybody is in our half, away from the opponents' goal and penalty
  areas;
* a goalkeeper stays in front of its goal, level with the ball, takes shots with its dribbler and plays the
  ball it holds up the field, to the side.

Run it against the baseline from the repository's root:

    PYTHONPATH=examples simatch run examples/striker_vs_simple.toml

A strategy sees the world only through its robot's WorldModel (perception, team-mates' StrategyInfo, the
game command) in its team frame: its team always attacks +x, so the same code plays either colour.
"""

from __future__ import annotations

import math

from pydantic import BaseModel, ConfigDict, Field

from simatch.msgs.game_commands import MatchMode, is_ours
from simatch.strategy import Command, RobotStrategy, TeamStrategy
from simatch.strategy.base import PassIntent
from simatch.strategy.roles import Action, Role

CONTACT = 0.5  # centre to centre of two robots that touch [m]
CONTACT_SPEED = 0.15  # how fast a robot may still be going when it reaches an opponent [m/s]
BRAKING = 1.2  # the slowing down planned for that [m/s^2]
NEAR_SPEED = 1.0  # top speed right beside an opponent [m/s] (charging: faster than 1.5 m/s into it)
PASS_BY = 0.8  # centre-to-centre distance at which a robot passes an opponent in its way [m]
CARRY = 1.6  # how far a robot carries the ball before it passes or shoots (the rules allow 3 m) [m]
AFTER_KICK = 1.5  # a robot that has just kicked leaves the ball to the others this long [s]
AFTER_RESTART = 4.0  # ... after a restart pass (it may not touch the ball again before another robot) [s]
# centre-to-ball distances kept at restarts: the rules' 3 m (theirs), 2 m (ours) and 1 m (dropped ball) count
# from the nearest point of a robot's footprint, 0.25 m from its centre; a little more for the way there [m]
THEIRS, OURS, DROPPED = 3.85, 2.85, 1.75


class StrikerParams(BaseModel):
    """Checked against ``teams.<team>.strategy_params`` in the scene."""

    model_config = ConfigDict(extra="forbid")
    speed: float = Field(3.0, gt=0.0, le=6.0, description="top speed [m/s]")
    shoot_from: float = Field(4.0, gt=0.0, description="shoot when this close to the goal [m]")


def toward(a: tuple[float, float], b: tuple[float, float]) -> float:
    return math.atan2(b[1] - a[1], b[0] - a[0])


def safe_speed(world, target: tuple[float, float], top: float) -> float:
    """The speed from which this robot can still slow down to CONTACT_SPEED before it reaches an opponent that
    stands (or comes) in its way to ``target``, and no more than NEAR_SPEED beside one: it never charges, and
    it never pushes."""
    me = world.me
    headings = [toward((me.x, me.y), target)]
    if math.hypot(me.vx, me.vy) > 0.5:  # and the way it is still going (it needs time to turn)
        headings.append(math.atan2(me.vy, me.vx))
    speed = top
    for x, y, vx, vy in world.opponents:
        d = math.hypot(x - me.x, y - me.y)
        coming = max(0.0, -(vx * (x - me.x) + vy * (y - me.y)) / max(d, 1e-6))  # its speed towards me
        gap = d - CONTACT - coming * 1.0  # (what it covers in the second it takes me to slow down)
        for heading in headings:
            ahead = (me.x + 3.0 * math.cos(heading), me.y + 3.0 * math.sin(heading))
            if _off_line((me.x, me.y), ahead, (x, y)) < CONTACT + 0.35:  # in my way (the next 3 m of it)
                speed = min(speed, CONTACT_SPEED + math.sqrt(2 * BRAKING * max(gap - 0.05, 0.0)))
            elif gap < 0.6 and abs(math.remainder(toward((me.x, me.y), (x, y)) - heading, 2 * math.pi)) < math.pi / 2:
                speed = min(speed, NEAR_SPEED)  # beside me, a little ahead
    return speed


def waypoint(start, goal, blocks) -> tuple[float, float]:
    """``goal``, or a point on the way round the first of ``blocks`` (x, y, clearance) that the straight way to
    it passes too near: a robot goes round opponents, and round the ball at a restart (on a circle a little
    wider than the clearance, 35 degrees at a time, so that the way to the point stays clear too)."""
    inside = [b for b in blocks if 0.3 < math.hypot(start[0] - b[0], start[1] - b[1]) < b[2] - 0.15]
    if inside:  # well inside one: straight out of it first, away from every one it is near (not into another)
        ax = ay = 0.0
        for bx, by, clear in blocks:
            d = math.hypot(start[0] - bx, start[1] - by)
            if 1e-6 < d < clear + 0.3:
                ax, ay = ax + (start[0] - bx) / d, ay + (start[1] - by) / d
        bx, by, clear = inside[0]
        if math.hypot(ax, ay) < 0.3:  # squeezed between two: sideways
            ax, ay = -(start[1] - by), start[0] - bx
        n = math.hypot(ax, ay)
        return (start[0] + ax / n * (clear + 0.3), start[1] + ay / n * (clear + 0.3))
    blocks = _clusters(blocks)  # overlapping ones are gone round as one (never between them, back and forth)
    first, at = None, 2.0
    dx, dy = goal[0] - start[0], goal[1] - start[1]
    length2 = max(dx * dx + dy * dy, 1e-9)
    for bx, by, clear in blocks:
        t = ((bx - start[0]) * dx + (by - start[1]) * dy) / length2
        if 0.0 < t < at and _off_line(start, goal, (bx, by)) < clear and math.hypot(bx - start[0], by - start[1]) > 0.3:
            first, at = (bx, by, clear), t
    if first is None:
        return goal
    bx, by, clear = first
    a0, a1 = toward((bx, by), start), toward((bx, by), goal)
    turn = math.remainder(a1 - a0, 2 * math.pi)
    sides = []
    for way in (turn, turn - math.copysign(2 * math.pi, turn)):  # the short way round, then the long one
        a = a0 + math.copysign(min(abs(way), math.radians(35)), way)
        sides.append((bx + (clear + 0.5) * math.cos(a), by + (clear + 0.5) * math.sin(a)))
    for point in sides:  # the first side whose next point keeps clear of the others (a cluster: round it all)
        if all(math.hypot(point[0] - x, point[1] - y) >= c for x, y, c in blocks if (x, y, c) != first):
            return point
    return sides[0]


def _clusters(blocks, largest: float = 2.5) -> list:
    """``blocks`` with every two that overlap replaced by the circle round both (up to ``largest``; one that
    lies inside another is dropped whatever their size)."""
    blocks = list(blocks)
    merged = True
    while merged:
        merged = False
        for i in range(len(blocks)):
            for j in range(i + 1, len(blocks)):
                (ax, ay, ra), (bx, by, rb) = blocks[i], blocks[j]
                d = math.hypot(bx - ax, by - ay)
                if d >= ra + rb:
                    continue
                if d + rb <= ra:
                    both = blocks[i]
                elif d + ra <= rb:
                    both = blocks[j]
                else:
                    r = (d + ra + rb) / 2
                    both = (ax + (r - ra) * (bx - ax) / d, ay + (r - ra) * (by - ay) / d, r)
                if both[2] <= largest or both[2] == max(ra, rb):
                    blocks[i], merged = both, True
                    del blocks[j]
                    break
            if merged:
                break
    return blocks


class Keeper(RobotStrategy):
    """Stays in front of its goal, level with the ball, the dribbler on to take a shot rather than let it bounce
    off; a ball it holds it plays to the side, up the field."""

    def decide(self, world) -> Command:
        me, ball = world.me, world.ball
        if world.match_mode in (MatchMode.STOPROBOT, MatchMode.TEST) or ball is None:
            return Command(role=Role.GOALIE, action=Action.NO_ACTION)
        if me.holding_ball:
            at = (-self.ctx.field.half_length / 2, 4.0 if me.y >= 0 else -4.0)
            face = toward((me.x, me.y), at)
            aimed = abs(math.remainder(face - me.yaw, 2 * math.pi)) < 0.15
            return Command(
                target=(me.x, me.y),
                target_ori=face,
                max_w=3.0,
                dribble=not aimed,
                kick_speed=4.0 if aimed else 0.0,
                role=Role.GOALIE,
                action=Action.KICK_COOP if aimed else Action.TURN_TO_PASS,
            )
        goal_x = -self.ctx.field.half_length + 0.5
        spot = (goal_x, max(-1.0, min(1.0, ball.y)))
        return Command(
            target=spot,  # a target pose: the robot's low-level controller turns it into a velocity
            target_ori=toward((me.x, me.y), (ball.x, ball.y)),
            max_vel=safe_speed(world, spot, self.ctx.params.speed),
            dribble=True,
            role=Role.GOALIE,
            action=Action.POSITIONED,
        )


class Striker(RobotStrategy):
    """A field robot: on the ball when it is the nearest, else a place that helps (see the module)."""

    def __init__(self, ctx):
        super().__init__(ctx)
        self.last_mode = MatchMode.STOPROBOT
        self.restart = None  # (ours?, where the ball was, which) from START of a restart until it is in play
        self.took_at = None  # where this robot took the ball (the 3 m rule)
        self.rest_until = -math.inf  # it leaves the ball to the others until then (it has just kicked)
        self.taking = False  # it is taking one of our restarts

    def decide(self, world) -> Command:
        me, ball, mode = world.me, world.ball, world.match_mode
        last, self.last_mode = self.last_mode, mode
        if mode in (MatchMode.STOPROBOT, MatchMode.TEST) or ball is None:
            return Command(action=Action.NO_ACTION)
        if mode == MatchMode.PARKINGROBOT:
            return Command(target=(-3.0 * self.ctx.id, -self.ctx.field.half_width - 0.5), target_ori=math.pi / 2)
        if mode == MatchMode.STARTROBOT and 1 <= last <= 13:  # a restart begins
            self.restart = (is_ours(last), self.restart_spot(world), last)
        moved = math.hypot(ball.x - self.restart[1][0], ball.y - self.restart[1][1]) if self.restart else 0.0
        if self.taking and moved > 0.12:  # the ball has left the restart spot: played (or pushed) by the taker
            # (by more than a noisy perception would make it seem to move: the taker would stop short of it)
            self.taking = False
            if math.hypot(me.x - self.restart[1][0], me.y - self.restart[1][1]) < 0.8:
                # it has played our restart: another robot must touch the ball before it may again
                self.rest_until = world.time + AFTER_RESTART
        if self.restart and (world.game.ball_in_play if world.game is not None else moved > 0.5):
            self.restart = None  # the ball is in play (the referee says so; without one: it has moved 0.5 m)
        near = math.hypot(ball.x - me.x, ball.y - me.y)
        if near < 0.42 and self.took_at is None:  # it touches the ball: where the 3 m of a dribble count from
            self.took_at = (me.x, me.y)
        elif not me.holding_ball and near > 0.8:
            self.took_at = None
        if 1 <= mode <= 13:  # a restart is being prepared (what went before it no longer counts)
            self.rest_until, self.taking = -math.inf, False
            return self.prepare(world, mode)
        if self.restart and not self.restart[0]:  # theirs: wait until the ball is in play
            return self.keep_away(world, THEIRS if self.restart[2] != MatchMode.DROPBALL else DROPPED)
        if self.restart:  # ours: the taker passes to a team-mate, who waits for it
            if self.resting(world):  # it has touched the ball: a team-mate must play it next
                return self.go(world, (me.x, me.y), Role.PASSOFPASS, Action.NO_ACTION)
            if moved > 0.15:  # the pass is on its way: the others keep the 2 m from the ball until it is in play
                self.taking = False  # (the pass rolls towards the receiver: it steps back before it)
                return self.keep_away(world, OURS)
            if self.taker(world):
                return self.take_restart(world, self.restart[2])
            self.taking = False
            if self.restart[2] == MatchMode.OUR_PENALTY:  # a shot: the others 3 m away, out of the area
                return self.keep_away(world, THEIRS)
            if self.rank(world) == 0:
                return self.go(world, self.receiving_spot(world), Role.ASSISTANT, Action.CATCH_POSITIONED, clear=OURS)
            return self.keep_away(world, OURS)
        if self.on_the_ball(world):
            return self.play_ball(world)
        return self.support(world)

    def restart_spot(self, world) -> tuple[float, float]:
        """Where the ball lies for the restart: where it is seen, unless the referee's spot is further off than
        the ball's placement and perception differ (it puts a ball that has moved back on its spot at START)."""
        game, ball = world.game, world.ball
        if game is None or game.phase not in ("prepare", "taking"):
            return (ball.x, ball.y)
        spot = (world.sign * game.ball_x, world.sign * game.ball_y)  # (the referee's is in the world frame)
        return spot if math.hypot(spot[0] - ball.x, spot[1] - ball.y) > 0.1 else (ball.x, ball.y)

    def resting(self, world) -> bool:
        return world.time < self.rest_until

    # --- with the ball ------------------------------------------------------------------------------------
    def play_ball(self, world) -> Command:
        me, p = world.me, self.ctx.params
        if not me.holding_ball:
            return self.take_ball(world)
        goal = self.aim(world)
        face = toward((me.x, me.y), goal)
        carried = math.hypot(me.x - self.took_at[0], me.y - self.took_at[1]) if self.took_at else 0.0
        won_at_home = self.took_at is not None and self.took_at[0] < 0.0
        pressed = any(  # an opponent close in front: no time to carry the ball on
            math.hypot(x - me.x, y - me.y) < 1.3
            and abs(math.remainder(toward((me.x, me.y), (x, y)) - face, 2 * math.pi)) < 1.6
            for x, y, _, _ in world.opponents
        )
        done = carried > CARRY or pressed  # it has carried the ball far enough, or cannot carry it further
        mate = self.pass_target(world)
        if mate is not None and (won_at_home or (done and me.x < 0.5)):
            return self.kick(world, (mate.x, mate.y), pass_to=mate)
        shot = math.hypot(goal[0] - me.x, goal[1] - me.y) < p.shoot_from or (done and me.x > 0.5 and not won_at_home)
        if pressed and abs(math.remainder(face - me.yaw, 2 * math.pi)) < 1.0:
            # pressed, and turned roughly to the goal already: no time to turn further, kick it on at once
            if shot and self.on_target(world):
                return self.kick(world, goal)
            return self.kick(world, (me.x + math.cos(me.yaw), me.y + math.sin(me.yaw)), speed=4.0)
        if shot:
            return self.kick(world, goal)
        if done:  # from our half a shot would not count: play the ball into theirs
            return self.kick(world, (self.ctx.field.half_length / 2, 0.0), speed=3.5)
        # carry the ball a short way towards the goal, slowly, once turned to it (driving backwards with the
        # ball is limited to 2 m by the rules)
        facing = abs(math.remainder(face - me.yaw, 2 * math.pi)) < 0.5
        step = (me.x + 0.8 * math.cos(face), me.y + 0.8 * math.sin(face)) if facing else (me.x, me.y)
        step = self.inside(step, self.crowded(world))  # (never into their penalty area where a team-mate is)
        return Command(
            target=step,
            target_ori=face,
            max_vel=min(1.5, safe_speed(world, step, 1.5)),
            max_w=3.0,
            dribble=True,
            role=Role.ACTIVE,
            action=Action.MOVE_WITH_BALL,
        )

    def take_ball(self, world) -> Command:
        """Go and take the ball, slowing down near opponents and arriving gently (so that the dribbler takes it
        rather than the robot pushing it on). With time for it, from behind the ball, already facing the goal:
        a robot that takes the ball facing its own goal has to turn with it, and is robbed while it turns."""
        me, ball, p = world.me, world.ball, self.ctx.params
        crowded = self.crowded(world)
        spot = self.inside((ball.x, ball.y), penalty_area=crowded)  # (never into their goal area)
        to_goal = toward((ball.x, ball.y), (self.ctx.field.half_length, 0.0))
        face = toward((me.x, me.y), (ball.x, ball.y))
        busy = [(x, y) for x, y, _, _ in world.opponents if math.hypot(x - ball.x, y - ball.y) < 1.5]
        if any(math.hypot(x - ball.x, y - ball.y) < 0.45 for x, y in busy):
            # an opponent has it: wait beside the ball on our goal's side, never push
            home = toward((ball.x, ball.y), (-self.ctx.field.half_length, 0.0))
            spot = self.inside((ball.x + 0.95 * math.cos(home), ball.y + 0.95 * math.sin(home)), False)
        elif not busy and math.hypot(ball.vx, ball.vy) < 1.0:
            if abs(math.remainder(face - to_goal, 2 * math.pi)) > 0.5:  # not behind it yet: go round it
                behind = (ball.x - 0.6 * math.cos(to_goal), ball.y - 0.6 * math.sin(to_goal))
                spot = self.inside(waypoint((me.x, me.y), behind, [(ball.x, ball.y, 0.45)]), crowded)
            face = to_goal
        near = math.hypot(ball.x - me.x, ball.y - me.y)
        others = [(x, y, PASS_BY) for x, y, _, _ in world.opponents if math.hypot(x - ball.x, y - ball.y) > 0.8]
        spot = self.inside(waypoint((me.x, me.y), spot, others), crowded)  # round the opponents in its way
        return Command(
            target=spot,
            target_ori=face,
            max_vel=min(safe_speed(world, spot, p.speed), 1.0 + 2.0 * max(0.0, near - 0.6)),
            dribble=True,
            role=Role.ACTIVE,
            action=Action.CATCH_BALL,
        )

    def aim(self, world) -> tuple[float, float]:
        """Where to shoot: the goal's far corner from their goalkeeper (the opponent nearest to the goal)."""
        f = self.ctx.field
        near_goal = [(x, y) for x, y, _, _ in world.opponents if x > f.half_length - 2.0 and abs(y) < 2.0]
        if not near_goal:
            return (f.half_length, 0.0)
        keeper = min(near_goal, key=lambda o: math.hypot(o[0] - f.half_length, o[1]))
        return (f.half_length, -0.75 if keeper[1] > 0 else 0.75)

    def take_restart(self, world, kind: int) -> Command:
        """Our restart: line up behind the ball with the pass to the team-mate who waits for it (a penalty: the
        shot), then drive gently through the ball with the dribbler off and the kicker armed. The kick fires
        as the ball enters the mouth: the pass is the one touch the rules allow before another robot plays."""
        me, ball = world.me, world.ball
        mate = None if kind == MatchMode.OUR_PENALTY else self.receiver(world)
        at = (mate.x, mate.y) if mate is not None else (self.ctx.field.half_length, 0.6)
        if kind == MatchMode.OUR_KICKOFF and mate is not None:  # a little forward, so that the taker stays in
            at = (ball.x + 0.6, ball.y + math.copysign(1.9, mate.y - ball.y))  # our half: the receiver runs on
        face = toward((ball.x, ball.y), at)
        behind = (ball.x - 0.55 * math.cos(face), ball.y - 0.55 * math.sin(face))
        lined = (
            _off_line(behind, (ball.x + math.cos(face), ball.y + math.sin(face)), (me.x, me.y)) < 0.045
            and abs(math.remainder(face - me.yaw, 2 * math.pi)) < 0.08
            and math.hypot(me.x - behind[0], me.y - behind[1]) < 0.6
        )
        distance = math.hypot(at[0] - ball.x, at[1] - ball.y)
        self.taking = True
        way = waypoint((me.x, me.y), behind, [(ball.x, ball.y, 0.45)])  # round the ball, never brushing it
        if kind == MatchMode.OUR_KICKOFF:  # ... and at a kick-off on our side of it
            way = (min(way[0], ball.x - 0.3), way[1])
        # through the ball (at a kick-off only as far as the kick needs: the taker stays in our half)
        through = (
            (ball.x, ball.y)
            if kind != MatchMode.OUR_KICKOFF
            else (ball.x - 0.3 * math.cos(face), ball.y - 0.3 * math.sin(face))
        )
        return Command(
            target=through if lined else way,
            target_ori=face,
            max_vel=(0.5 if kind != MatchMode.OUR_KICKOFF else 0.3)
            if lined
            else safe_speed(world, way, self.ctx.params.speed),
            kick_speed=(min(4.0, math.sqrt(2 * 0.5 * distance + 1.5**2)) if mate is not None else 8.0)
            if lined
            else 0.0,
            role=Role.ACTIVE,
            action=Action.STATIC_PASS,
            pass_intent=PassIntent(mate.id, ball.x, ball.y, at[0], at[1], kicked=lined, static=True)
            if mate is not None
            else None,
        )

    def on_target(self, world) -> bool:
        """The kicker points into the goal's mouth (with a margin for the ball)."""
        me, f = world.me, self.ctx.field
        if math.cos(me.yaw) < 0.1 or me.x >= f.half_length:
            return False
        return abs(me.y + math.tan(me.yaw) * (f.half_length - me.x)) < f.goal_width / 2 - 0.3

    def kick(self, world, at: tuple[float, float], pass_to=None, speed: float = 8.0) -> Command:
        """Turn to ``at`` holding the ball, then kick: a pass just hard enough to arrive, or a shot (aimed as
        soon as the kicker points anywhere into the goal's mouth)."""
        me, f = world.me, self.ctx.field
        face = toward((me.x, me.y), at)
        distance = math.hypot(at[0] - me.x, at[1] - me.y)
        if pass_to is None and at[0] >= f.half_length:
            aimed = self.on_target(world)
        else:
            aimed = abs(math.remainder(face - me.yaw, 2 * math.pi)) < 0.1
        if pass_to is not None:
            speed = min(4.5, math.sqrt(2 * 0.5 * distance + 1.5**2))
        intent = PassIntent(pass_to.id, me.x, me.y, at[0], at[1], kicked=aimed) if pass_to is not None else None
        if aimed:
            self.rest_until = world.time + AFTER_KICK
        return Command(
            target=(me.x, me.y),  # stand and turn
            target_ori=face,
            max_w=3.0,
            dribble=not aimed,
            kick_speed=speed if aimed else 0.0,
            role=Role.PASSOFPASS if pass_to is not None and aimed else Role.ACTIVE,
            action=(Action.KICK_COOP if pass_to is not None else Action.AT_SHOOT_SITUATION)
            if aimed
            else (Action.TURN_TO_PASS if pass_to is not None else Action.TURN_FOR_SHOOT),
            pass_intent=intent,
        )

    # --- without it -------------------------------------------------------------------------------------------
    def support(self, world) -> Command:
        """Wait for a pass in the opponents' half (the first two robots by id), or guard our half."""
        ball, half_l, half_w = world.ball, self.ctx.field.half_length, self.ctx.field.half_width
        if self.resting(world):  # it has just passed: it says so, and its team-mates take the ball
            return self.go(world, (world.me.x, world.me.y), Role.PASSOFPASS, Action.POSITIONED)
        rank = self.rank(world)
        if rank < 2:
            side = -1.0 if (rank == 0) == (ball.y > 0) else 1.0
            spot = (max(1.5, min(half_l - 3.0, ball.x + 3.5)), side * min(half_w - 1.5, 3.0))
            return self.go(world, spot, Role.ASSISTANT, Action.CATCH_POSITIONED)
        spot = (max(-half_l + 3.0, min(-1.0, ball.x - 4.0)), 0.5 * ball.y)
        return self.go(world, spot, Role.PASSIVE, Action.POSITIONED)

    def prepare(self, world, mode: int) -> Command:
        """Before a restart: the taker behind the ball, a receiver beside it, the others away from it (at a
        kick-off everybody in our half)."""
        ball = world.ball
        kickoff = mode in (MatchMode.OUR_KICKOFF, MatchMode.OPP_KICKOFF)
        if not is_ours(mode):
            if kickoff or mode == MatchMode.OPP_PENALTY:  # from our start places (outside our penalty area)
                return self.keep_away(world, THEIRS, home=tuple(self.ctx.start[:2]))
            return self.keep_away(world, THEIRS if mode != MatchMode.DROPBALL else DROPPED)
        if self.taker(world):  # behind the ball, round it: the ball must not move before START
            mate = self.receiving_spot(world)
            away = toward(mate, (ball.x, ball.y)) if not kickoff else math.pi
            me = world.me
            if math.hypot(me.x - ball.x, me.y - ball.y) < 0.5:  # touching it: straight back from it first
                away = toward((ball.x, ball.y), (me.x, me.y))
            spot = (ball.x + 0.7 * math.cos(away), ball.y + 0.7 * math.sin(away))
            return self.go(world, spot, Role.ACTIVE, Action.POSITIONED_STATIC, face=(ball.x, ball.y), clear=0.45)
        if mode == MatchMode.OUR_PENALTY:  # the others 3 m from the mark, in our half (out of the area)
            return self.keep_away(world, THEIRS, home=tuple(self.ctx.start[:2]))
        if self.rank(world) == 0:
            return self.go(world, self.receiving_spot(world), Role.ASSISTANT, Action.CATCH_POSITIONED, clear=OURS)
        return self.keep_away(world, OURS, home=tuple(self.ctx.start[:2]) if kickoff else None)

    def keep_away(self, world, distance: float, home=None) -> Command:
        """Stay where it is (or go ``home``) if that is far enough from the ball, else step away from the ball.
        The way never cuts through the circle the rules keep clear, before START too: START may come while
        a robot is still on its way."""
        me, ball = world.me, world.ball
        spot = home or (me.x, me.y)
        d = math.hypot(spot[0] - ball.x, spot[1] - ball.y)
        if d < distance + 0.3:  # (from its place, or from where it is: straight away from the ball)
            ux, uy = (spot[0] - ball.x) / max(d, 1e-6), (spot[1] - ball.y) / max(d, 1e-6)
            spot = self.inside((ball.x + ux * (distance + 0.6), ball.y + uy * (distance + 0.6)))
            if math.hypot(spot[0] - ball.x, spot[1] - ball.y) < distance + 0.3:
                # the field ends before the circle does (a ball near a corner): round the ball, towards the middle
                n = max(math.hypot(ball.x, ball.y), 1e-6)
                spot = self.inside((ball.x - ball.x / n * (distance + 0.6), ball.y - ball.y / n * (distance + 0.6)))
        return self.go(world, spot, Role.PASSIVE, Action.POSITIONED, face=(ball.x, ball.y), clear=distance + 0.3)

    def receiving_spot(self, world) -> tuple[float, float]:
        """Where the receiver of a restart pass waits: 3 m from the ball, towards the middle of the field and a
        little back (at a kick-off beside the ball, in our half)."""
        ball = world.ball
        side = -1.0 if ball.y > 0 else 1.0
        if abs(ball.x) < 0.1 and abs(ball.y) < 0.1:  # the kick-off: beside the ball, in our half
            return (-0.5, -2.9)
        return self.inside((ball.x - 1.2, ball.y + side * 2.8))

    def go(self, world, spot, role: int, action: int, face=None, clear: float = 0.0) -> Command:
        """To ``spot`` (where a field robot may stand), round opponents and at a restart round the ball by
        ``clear``, slowing down near opponents."""
        me, ball = world.me, world.ball
        face = face or (ball.x, ball.y)
        spot = self.inside(spot, penalty_area=role != Role.ACTIVE)
        blocks = [(ball.x, ball.y, clear)] if clear else []  # (the ball first: the rules' circle comes first)
        blocks += [(x, y, PASS_BY) for x, y, _, _ in world.opponents] + [(r.x, r.y, 0.55) for r in world.teammates]
        step = self.inside(waypoint((me.x, me.y), spot, blocks), penalty_area=role != Role.ACTIVE)  # (a way out
        # of the ball's circle may not cut through an area either)
        return Command(
            target=step,
            target_ori=toward((me.x, me.y), face),
            max_vel=safe_speed(world, step, self.ctx.params.speed),
            role=role,
            action=action,
        )

    # --- who does what -----------------------------------------------------------------------------------------
    def field_mates(self, world) -> list:
        """The team-mates that play the ball: not the goalkeeper, not one that has just kicked it (it says so
        in its StrategyInfo)."""
        return [
            r
            for r in world.teammates
            if r.id != world.goalkeeper
            and not (r.id in world.strategies and world.strategies[r.id].role == Role.PASSOFPASS)
        ]

    def on_the_ball(self, world) -> bool:
        """The field robot nearest to the ball plays it (ties to the lower id), unless it has just kicked it."""
        if self.resting(world):
            return False
        ball, me = world.ball, world.me
        mine = math.hypot(ball.x - me.x, ball.y - me.y)
        return all((math.hypot(ball.x - r.x, ball.y - r.y), r.id) > (mine, me.id) for r in self.field_mates(world))

    def taker(self, world) -> bool:
        return self.on_the_ball(world) or world.me.holding_ball

    def rank(self, world) -> int:
        """This robot's place among the field robots that are not on the ball, by id."""
        ball = world.ball
        mates = [r for r in self.field_mates(world) if r.valid]
        if not mates:
            return 0
        nearest = min(mates + [world.me], key=lambda r: (math.hypot(ball.x - r.x, ball.y - r.y), r.id))
        return sum(1 for r in mates if r.id < self.ctx.id and r.id != nearest.id)

    def receiver(self, world):
        """The team-mate who waits for a restart pass: the one nearest to the receiving spot."""
        spot, mates = self.receiving_spot(world), self.field_mates(world)
        return min(mates, key=lambda r: math.hypot(r.x - spot[0], r.y - spot[1])) if mates else None

    def pass_target(self, world):
        """The team-mate farthest up the field and ahead of the ball, with nobody near the line to it."""
        me, best = world.me, None
        for r in self.field_mates(world):
            if r.x < 0.5 or r.x < me.x - 1.0 or math.hypot(r.x - me.x, r.y - me.y) < 2.0:
                continue
            if any(_off_line((me.x, me.y), (r.x, r.y), (x, y)) < 0.7 for x, y, _, _ in world.opponents):
                continue
            if best is None or r.x > best.x:
                best = r
        return best

    def crowded(self, world) -> bool:
        """A team-mate is in their penalty area (one that has just shot from there too): one attacker at a time."""
        return any(self.in_their_penalty_area(r.x, r.y) for r in world.teammates if r.id != world.goalkeeper)

    def in_their_penalty_area(self, x: float, y: float) -> bool:
        f = self.ctx.field
        return x > f.half_length - f.penalty_area_depth - 0.3 and abs(y) < f.penalty_area_width / 2 + 0.3

    def inside(self, spot: tuple[float, float], penalty_area: bool = True) -> tuple[float, float]:
        """The nearest place to ``spot`` where a field robot may stand: on the field, out of the opponents'
        goal area (only their goalkeeper may enter it) and of our penalty area (our goalkeeper's); out of
        their penalty area too unless it plays the ball (one attacker at a time may be there)."""
        f, margin = self.ctx.field, 0.4
        x = max(-f.half_length + 0.5, min(f.half_length - 0.5, spot[0]))
        y = max(-f.half_width + 0.5, min(f.half_width - 0.5, spot[1]))
        if x > f.half_length - f.goal_area_depth - margin and abs(y) < f.goal_area_width / 2 + margin:
            x = f.half_length - f.goal_area_depth - margin
        if (
            penalty_area
            and x > f.half_length - f.penalty_area_depth - margin
            and abs(y) < f.penalty_area_width / 2 + margin
        ):
            x = f.half_length - f.penalty_area_depth - margin
        if x < -f.half_length + f.penalty_area_depth + margin and abs(y) < f.penalty_area_width / 2 + margin:
            x = -f.half_length + f.penalty_area_depth + margin
        return (x, y)


def _off_line(a, b, p) -> float:
    """Distance of point p from the segment a-b."""
    ax, ay = a
    dx, dy = b[0] - ax, b[1] - ay
    t = max(0.0, min(1.0, ((p[0] - ax) * dx + (p[1] - ay) * dy) / max(dx * dx + dy * dy, 1e-9)))
    return math.hypot(p[0] - ax - t * dx, p[1] - ay - t * dy)


class StrikerTeam(TeamStrategy):
    """The team: one Keeper (the scene's goalkeeper id), Strikers for the rest."""

    Params = StrikerParams

    def make_robot(self, ctx) -> RobotStrategy:
        return Keeper(ctx) if ctx.is_goalkeeper else Striker(ctx)
