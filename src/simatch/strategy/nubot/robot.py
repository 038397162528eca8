"""The nubot robot (one per robot: its Control) and team (makes its robots and lets them share work).

Every control period a robot reads its WorldModel into an Observation, follows the game flow, gets the team
picture (roles and points, see picture.py) and acts on the game command:

    STOP                stand still, dribbler off
    a set piece         go to its set-piece slot (setpieces.py)
    START               play: the active robot plays the ball (active.py), the goalkeeper keeps the goal
                        (goalie.py), the others take their role's point; right after a set piece, the
                        taker passes (restart.py) and everybody else keeps its distance until the ball is
                        in play
    PARK                drive to its parking place beside the field
    TEST                the coach's test commands (testmodes.py)
"""

from __future__ import annotations

import math

from ...msgs.game_commands import is_ours
from ..base import Command, RobotContext, RobotStrategy, TeamContext, TeamStrategy
from ..roles import ACTIONS, ROLES
from ..worldmodel import WorldModel
from .active import BallPlayer
from .gameflow import MODES, PHASES, GameFlow
from .geometry import segment_distance, wrap
from .goalie import Goalkeeper
from .motion import Motion
from .observation import Observation, TeamView, observe
from .params import NubotParams, plain
from .picture import Analyst, Picture, TeamMemo
from .positions import Areas, spot_grid
from .restart import RestartTaker
from .testmodes import TestModes
from .warm import load_kernels

_move = Command.move

# what `decide` and `hold_slot` compare at every tick, as module constants; the
# game flow's phase is always one of PHASES' members, compared by identity
_STOP, _PARK, _TEST, _PLAY, _SETUP, _OUR_RESTART = (
    PHASES.STOP,
    PHASES.PARK,
    PHASES.TEST,
    PHASES.PLAY,
    PHASES.SETUP,
    PHASES.OUR_RESTART,
)
_NOROLE, _ACTIVE, _CATCHOFPASS, _POSITIONED = ROLES.NOROLE, ROLES.ACTIVE, ROLES.CATCHOFPASS, ACTIONS.POSITIONED
_OPP_RESTART = PHASES.OPP_RESTART
# the set pieces `hold_slot` tells apart, as plain ints (the game flow's kind is an int)
_OUR_KICKOFF, _OPP_KICKOFF, _DROPBALL = int(MODES.OUR_KICKOFF), int(MODES.OPP_KICKOFF), int(MODES.DROPBALL)

#: parking: robots line up beside the side line on their right, in their own half, facing the field
PARK_OUTSIDE = 0.7
PARK_SPACING = 1.3
#: a steady robot decides again at once when the ball, or another robot, is this close [m]
STEADY_BALL_DISTANCE = 2.0
STEADY_SET_PIECE_DISTANCE = 4.0  # (at a set piece: near the circle the rules keep clear)
STEADY_ROBOT_DISTANCE = 1.0
#: at a kick-off, robots in their own half keep this far from the half-way line [m]
KICKOFF_LINE_MARGIN = 0.15
#: a robot that must not touch the ball steps this far aside when it rolls within DODGE_WIDTH of it [m]
DODGE_STEP = 1.2
DODGE_WIDTH = 0.8
#: after taking a restart, the taker keeps this far from the ball until another robot has touched it [m]
TAKER_BALL_CLEARANCE = 0.9
#: a robot going round the ball's circle at a restart heads this far (in angle) along it [rad]
ORBIT_STEP = 0.6
#: a robot leaving or going round a restart's ball stays within this far beyond the field lines [m]
ON_FLOOR_MARGIN = 0.4


class _Shared:
    """What the robots of one team in one process may share: fixed tables and the last team picture."""

    def __init__(self, params: NubotParams, field):
        self.params = params
        params = plain(params)
        self.areas = Areas(field, params.robot_radius + 0.15)
        self.spots = spot_grid(self.areas)
        self.analyst = Analyst(params, self.areas, self.spots)
        self.memo = TeamMemo()
        self.view = TeamView()
        self.evaluated = 0  # pictures computed (for profiling)
        self.reused = 0


class NubotRobot(RobotStrategy):
    """One robot of the nubot team. Used alone (``teams.X.strategy = "simatch.strategy.nubot:NubotRobot"``)
    each robot computes its own team picture; `NubotTeam` lets the robots of one process share it."""

    Params = NubotParams

    def __init__(self, ctx: RobotContext, shared: _Shared | None = None):
        super().__init__(ctx)
        params = ctx.params if isinstance(ctx.params, NubotParams) else NubotParams.model_validate(ctx.params or {})
        self.shared = shared or _Shared(params, ctx.field)
        self.p = params = plain(params)
        areas = self.shared.areas
        goal_half = 0.5 * ctx.field.goal_width
        self.areas = areas
        self.motion = Motion(params, ctx.control_period, ctx.field, areas)
        self.flow = GameFlow(params.restart_wait)
        self.player = BallPlayer(params, self.motion, areas, goal_half, ctx.rng)
        self.keeper = Goalkeeper(params, self.motion, areas, ctx.field, self.player)
        self.taker = RestartTaker(params, self.motion, self.player, goal_half, areas.L2)
        self.tests = TestModes(params, self.motion, self.player)
        ids = sorted(ctx.ids)
        k = ids.index(ctx.id) if ctx.id in ids else 0
        self.park_at = (-areas.L2 + 1.0 + PARK_SPACING * k, -(areas.W2 + PARK_OUTSIDE))
        self.role = ROLES.NOROLE
        self.picture: Picture | None = None
        self.steady: tuple | None = None  # (tick, game command, command, course) of a steady robot
        self.picture_tick = -1
        self.role_since = 0.0

    @classmethod
    def warm_up(cls) -> None:
        """The kernels that only open play reaches (interceptions, receiving spots, the dribble's choice)."""
        load_kernels()

    # -----------------------------------------------------------------------------------------------------
    def team_picture(self, obs: Observation) -> Picture:
        memo = self.shared.memo
        pic = memo.get(obs, self.flow)
        if pic is not None:
            self.shared.reused += 1
            return pic
        pic = self.shared.analyst.analyse(obs, self.flow)
        memo.put(obs, self.flow, pic)
        self.shared.evaluated += 1
        return pic

    def decide(self, world: WorldModel) -> Command:
        # The team thinks at half rate: on even ticks every robot decides from a fresh team picture; on odd
        # ticks a robot only taking its place keeps its course, and the others (the ball's robots, the
        # goalkeeper, robots close to another) act again on a fresh observation but keep the picture of
        # the tick before. Roles therefore change only on even ticks, for everybody at once (what robots
        # tell each other stays coherent), and each robot relies only on what it saw itself.
        odd = world.tick % 2 == 1
        if odd:
            again = self.repeat(world)
            if again is not None:
                return again
        obs = observe(world, self.shared.view)
        flow = self.flow
        flow.update(obs)
        self.player.track(obs)
        me = obs.me
        phase = flow.phase
        self.steady = None
        if phase is _STOP:
            return Command(role=self.role, action=ACTIONS.NO_ACTION)
        if phase is _PARK:
            return self.park(obs)
        pic = self.picture
        if not (odd and pic is not None and pic.phase == phase and self.picture_tick == obs.tick - 1):
            pic = self.team_picture(obs)
            self.picture, self.picture_tick = pic, obs.tick
        if phase is _TEST:
            cmd = self.tests.decide(obs, pic)
        else:
            role = pic.roles.get(me.id, _NOROLE)
            if me.is_goalie:
                cmd = self.keeper.decide(obs, pic, flow)
            elif phase is _OUR_RESTART and role == _ACTIVE and flow.taker != me.id:
                cmd = self.taker.take(obs, pic, flow)
            elif phase is not _PLAY:
                cmd = self.hold_slot(obs, pic, role)
            elif me.holding:
                cmd = self.player.play(obs, pic, flow, role)
            elif role == _ACTIVE or role == _CATCHOFPASS:
                cmd = self.player.fetch(obs, pic, role)
            else:
                cmd = self.hold_slot(obs, pic, role)
        if cmd.pass_intent is None:
            cmd.pass_intent = self.player.pass_intent(obs)
        if cmd.role != self.role:
            self.role_since = obs.t
        self.role = cmd.role
        # told to the team, for the hysteresis of attacking and of the active role
        cmd.user = (1.0 if pic.attacking else 0.0, obs.t - self.role_since)
        if (
            not odd
            and (phase is _PLAY or phase is _SETUP)
            and cmd.action == _POSITIONED
            and cmd.pass_intent is None
            and pic.receiver != me.id
            and not me.holding
        ):
            self.steady = (obs.tick, obs.mode, cmd, self.motion.last)
        return cmd

    def repeat(self, world: WorldModel) -> Command | None:
        """The last command again, with the course kept in the team frame, when this robot decided on the
        tick before only to take its place and nothing that concerns it changed since: the same game
        command, the ball and the other robots still away from it."""
        steady = self.steady
        if steady is None:
            return None
        self.steady = None
        tick, mode, cmd, (vx, vy, w) = steady
        if world.tick != tick + 1 or world.match_mode != mode:
            return None
        v = world.vision
        me, b = world.me, v.ball
        near = STEADY_SET_PIECE_DISTANCE if 1 <= mode <= 13 else STEADY_BALL_DISTANCE
        if (b.x - me.x) ** 2 + (b.y - me.y) ** 2 < near * near:
            return None
        dist = v.obstacles.distance
        if len(dist) and min(dist.tolist()) < STEADY_ROBOT_DISTANCE:  # (plain floats: a few, every tick)
            return None
        bx, by, w_body = self.motion.body(me.yaw, vx, vy, w)
        return _move(bx, by, w_body, cmd.role, cmd.action, cmd.intent, cmd.user)

    # --- simple movements ---------------------------------------------------------------------------------
    def hold_slot(self, obs: Observation, pic: Picture, role: int) -> Command:
        me = obs.me
        slot = pic.slots.get(me.id)
        if slot is None:
            # no place in the team picture: off the field (come back in) or nothing to do
            x, y = self.areas.inside_field(me.x, me.y, 1.0)
            slot = (x, y, obs.bx, obs.by)
        x, y, fx, fy = slot
        face = math.atan2(fy - me.y, fx - me.x)
        flow = self.flow
        keep = None if flow.phase is _PLAY else self.keep_from_ball(obs)  # (in play: none)
        fence = None
        kickoff = False
        if keep is not None:
            kind = flow.kind
            taker = role == _ACTIVE and is_ours(kind) and kind != _DROPBALL
            x, y = self.round_the_ball(obs, x, y, keep, taker)
            if not taker:
                fence = (obs.bx, obs.by, keep)
            kickoff = kind == _OUR_KICKOFF or kind == _OPP_KICKOFF
        ball = True
        if flow.taker == me.id:
            ball = TAKER_BALL_CLEARANCE  # the restart's taker must not touch the ball again yet
            fence = (obs.bx, obs.by, TAKER_BALL_CLEARANCE)
            x, y = self.out_of_the_way(obs, x, y)
        motion = self.motion
        motion.go(
            obs,
            x,
            y,
            face,
            self.p.max_speed,
            self.p.max_turn,
            ball_obstacle=ball,
            boxes=self.areas.forbidden(False),
            fence=fence,
            max_x=-KICKOFF_LINE_MARGIN if kickoff and me.x < 0.0 else None,
        )
        return motion.move(role, _POSITIONED)

    def out_of_the_way(self, obs: Observation, x: float, y: float) -> tuple[float, float]:
        """Where to go instead of (x, y) when the ball rolls at this robot (which must not touch it): a
        step aside, across the ball's path."""
        me = obs.me
        speed = obs.ball_speed
        if speed < 0.2:
            return x, y
        ux, uy = obs.bvx / speed, obs.bvy / speed
        rx, ry = me.x - obs.bx, me.y - obs.by
        along = rx * ux + ry * uy
        across = rx * uy - ry * ux
        if along <= 0.0 or along > 2.0 * speed or abs(across) > DODGE_WIDTH:
            return x, y
        side = 1.0 if across >= 0.0 else -1.0
        return me.x + side * uy * DODGE_STEP, me.y - side * ux * DODGE_STEP

    def keep_from_ball(self, obs: Observation) -> float | None:
        """The distance the rules keep this robot from the ball while a restart is being set up or taken
        (None in play)."""
        flow = self.flow
        phase = flow.phase  # (one of PHASES' members: compared by identity, the kind as an int)
        if phase is _SETUP or phase is _OUR_RESTART or phase is _OPP_RESTART:
            kind = flow.kind
            if kind == _DROPBALL:
                return self.p.dropball_distance
            if is_ours(kind):
                return self.p.mate_distance
            return self.p.opponent_distance
        return None

    def round_the_ball(
        self, obs: Observation, x: float, y: float, keep: float, taker: bool = False
    ) -> tuple[float, float]:
        """The next point on the way to (x, y) that respects the circle of radius ``keep`` round the ball: a
        robot inside it leaves it straight away, a robot whose straight way would cut through it follows the
        circle round."""
        me = obs.me
        bx, by = obs.bx, obs.by
        d = math.hypot(me.x - bx, me.y - by)
        if math.hypot(x - bx, y - by) < keep - 0.05:
            if taker:
                return x, y  # the taker's slot, behind the ball
            # any other place inside the circle is moved out of it, away from the ball
            ex, ey = x - bx, y - by
            e = math.hypot(ex, ey)
            ux, uy = (ex / e, ey / e) if e > 1e-6 else (-1.0, 0.0)
            x, y = bx + ux * (keep + 0.3), by + uy * (keep + 0.3)
        if d < keep - 0.25:
            a_me = math.atan2(me.y - by, me.x - bx) if d > 1e-6 else math.pi
            # out of the circle by the nearest way that stays on the floor: straight away from a ball near
            # a line would run into the boards and stay inside the circle
            r = keep + 0.4
            for k in range(13):
                for a in (a_me + k * math.pi / 12, a_me - k * math.pi / 12):
                    px, py = bx + r * math.cos(a), by + r * math.sin(a)
                    if self.on_floor(px, py):
                        return px, py
            return bx + r * math.cos(a_me), by + r * math.sin(a_me)
        gap, _ = segment_distance(bx, by, me.x, me.y, x, y)
        if gap >= keep:
            return x, y
        a_me = math.atan2(me.y - by, me.x - bx) if d > 1e-6 else math.pi
        turn = wrap(math.atan2(y - by, x - bx) - a_me)
        step = max(-ORBIT_STEP, min(ORBIT_STEP, turn))
        r = max(d, keep + 0.3)
        px, py = bx + r * math.cos(a_me + step), by + r * math.sin(a_me + step)
        if not self.on_floor(px, py):
            # round the ball the other way: this way runs off the floor
            px, py = bx + r * math.cos(a_me - step), by + r * math.sin(a_me - step)
        return px, py

    def on_floor(self, x: float, y: float) -> bool:
        """Whether a robot can stand at (x, y): inside the lines or just beyond them, short of the boards."""
        return abs(x) <= self.areas.L2 + ON_FLOOR_MARGIN and abs(y) <= self.areas.W2 + ON_FLOOR_MARGIN

    def park(self, obs: Observation) -> Command:
        x, y = self.park_at
        motion = self.motion
        motion.go(obs, x, y, 0.5 * math.pi, self.p.max_speed, self.p.max_turn)
        return motion.move(ROLES.NOROLE, ACTIONS.POSITIONED)


class NubotTeam(TeamStrategy):
    """The default team. Its robots decide each from its own WorldModel; robots of the team that run in
    the same process reuse one another's team picture when they see exactly the same facts."""

    Params = NubotParams

    def __init__(self, ctx: TeamContext):
        super().__init__(ctx)
        params = ctx.params if isinstance(ctx.params, NubotParams) else NubotParams.model_validate(ctx.params or {})
        self.shared = _Shared(params, ctx.field)

    @classmethod
    def warm_up(cls) -> None:
        NubotRobot.warm_up()

    def make_robot(self, ctx: RobotContext) -> RobotStrategy:
        return NubotRobot(ctx, self.shared)
