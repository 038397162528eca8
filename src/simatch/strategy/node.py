"""The strategy subsystem on the bus: one RobotNode per robot (WorldModel + Control) and one StrategyPub
per team, written against the bus interface only, so the same nodes run embedded or in other processes.
"""

from __future__ import annotations

import logging
import math
import struct
import traceback

import numpy as np

from .. import msgs
from ..bus import Node, NodeContext, Phase, topics
from .base import Command, RobotStrategy
from .hwcontroller import climb_towards, velocity_towards
from .worldmodel import WorldModel

log = logging.getLogger(__name__)
_EMPTY_I32 = np.zeros(0, dtype=np.int32)
_EMPTY_F64 = np.zeros(0)
#: number of values -> the `pack` of that many float64 (native order): a StrategyInfo's ``user`` as bytes
_USER_PACK: dict = {}
_frombuffer = np.frombuffer
# built positionally (three messages per robot and control tick; see msgs.positional)
_VelCmd = msgs.positional(msgs.VelCmd, "stamp tick vx vy w vz")
_ActionCmd = msgs.positional(
    msgs.ActionCmd,
    "stamp tick move_action rotate_action rotate_mode target_x target_y "
    "target_ori target_vx target_vy max_vel max_w dribble kick_speed kick_type",
)
_StrategyInfo = msgs.positional(
    msgs.StrategyInfo,
    "stamp tick agent_id role action is_dribble is_kickoff role_time "
    "target_x target_y target_num static_pass_num static_catch_num pass_cmd user",
)
_TeamStrategy = msgs.positional(msgs.TeamStrategy, "stamp tick strategies")
_MOVE, _NO_ACTION = msgs.ActionCmd.MOVE, msgs.ActionCmd.NO_ACTION
_LOB, _GROUND = msgs.ActionCmd.KICK_LOB, msgs.ActionCmd.KICK_GROUND
#: the "no pass" entry shared by every StrategyInfo without a pass (messages are read-only)
_NO_PASS = msgs.new(msgs.PassCommands)
_f32s = msgs.f32s


class RobotNode(Node):
    """One robot's WorldModel and Control: perception in, VelCmd/ActionCmd/StrategyInfo out."""

    phase = Phase.ROBOT

    def __init__(self, team: str, rid: int, strategy: RobotStrategy, world: WorldModel, period: float):
        self.team, self.rid = team, rid
        self.name = f"{team}/{rid}"
        self.strategy = strategy
        self.world = world
        self.period = period
        self.errors = 0
        self.detached = False
        self._user: tuple = ((), _EMPTY_F64)  # the last StrategyInfo.user tuple and its array

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        bus, t, r, w = ctx.bus, self.team, self.rid, self.world
        self.subs = [
            bus.subscribe(topics.robot_topic(t, r, topics.OMNI_VISION), msgs.OmniVisionInfo, w.on_vision),
            bus.subscribe(topics.team_topic(t, topics.TEAM_STRATEGY), msgs.TeamStrategy, w.on_team),
            bus.subscribe(topics.team_topic(t, topics.RECEIVE_FROM_COACH), msgs.CoachInfo, w.on_coach),
            bus.subscribe(topics.GAME_STATE, msgs.GameState, w.on_game),
        ]
        self.pub_vel = bus.publisher(topics.robot_topic(t, r, topics.VEL_CMD), msgs.VelCmd)
        self.pub_action = bus.publisher(topics.robot_topic(t, r, topics.ACTION_CMD), msgs.ActionCmd)
        self.pub_info = bus.publisher(topics.robot_topic(t, r, topics.STRATEGY_INFO), msgs.StrategyInfo)
        self.pub_events = bus.publisher(topics.EVENTS, msgs.GameEvent)

    def tick(self, now: float) -> None:
        world = self.world
        if self.detached or world.vision is None:  # (not `world.ready`: the same test without the property's call)
            return
        try:
            cmd = self.strategy.decide(world)
            if not isinstance(cmd, Command):
                raise TypeError(f"decide() returned {type(cmd).__name__}, not a Command")
            vx, vy, w = self._velocity(cmd)
        except Exception as exc:  # a strategy bug must not stop the match: this robot stands still
            self._error(now, exc)
            cmd, (vx, vy, w) = Command(), (0.0, 0.0, 0.0)
        self.publish(now, world.tick, cmd, vx, vy, w)

    def _velocity(self, cmd: Command) -> tuple[float, float, float]:
        if cmd.target is None and cmd.target_ori is None:
            return cmd.vx, cmd.vy, cmd.w  # a velocity command: no limits to look up
        coach = self.world.coach
        max_vel, max_w = cmd.max_vel, cmd.max_w
        if coach is not None and coach.max_vel > 0:
            max_vel = min(max_vel, coach.max_vel)
        if coach is not None and coach.max_w > 0:
            max_w = min(max_w, coach.max_w)
        me = self.world.me
        vx, vy, w = velocity_towards(me.x, me.y, me.yaw, cmd, max_vel, max_w)
        if cmd.target is None:
            vx, vy = cmd.vx, cmd.vy
        if cmd.target_ori is None:
            w = cmd.w
        return vx, vy, w

    def publish(self, now: float, tick: int, cmd: Command, vx: float, vy: float, w: float) -> None:
        target, ori = cmd.target, cmd.target_ori
        if target is None:
            move, tx, ty = _NO_ACTION, 0.0, 0.0
        else:
            move, (tx, ty) = _MOVE, target
        rotate, ori = (_NO_ACTION, 0.0) if ori is None else (_MOVE, ori)
        tvx, tvy = cmd.target_vel
        info = self.pub_info.active
        intent = cmd.intent if cmd.intent is not None else target
        ix, iy = intent if info and intent is not None else (math.nan, math.nan)
        vz = cmd.vz if cmd.altitude is None else self._climb(cmd)
        # the messages' float32 numbers are rounded here, where they are made (see simatch.msgs), all at once
        vx, vy, w, vz, tx, ty, ori, tvx, tvy, max_vel, max_w, kick, ix, iy = _f32s(
            vx, vy, w, vz, tx, ty, ori, tvx, tvy, cmd.max_vel, cmd.max_w, cmd.kick_speed, ix, iy
        )
        self.pub_vel.put(_VelCmd(now, tick, vx, vy, w, vz))
        self.pub_action.put(
            _ActionCmd(
                now,
                tick,
                move,
                rotate,
                0,
                tx,
                ty,
                ori,
                tvx,
                tvy,
                max_vel,
                max_w,
                cmd.dribble,
                kick,
                _LOB if cmd.lob else _GROUND,
            )
        )
        if info:
            self.pub_info.put(self.strategy_info(now, tick, cmd, ix, iy))

    def _climb(self, cmd: Command) -> float:
        try:
            z = self.world.me.z
        except LookupError:
            return 0.0
        return climb_towards(z, cmd.altitude, cmd.max_vz)

    def strategy_info(self, now: float, tick: int, cmd: Command, ix: float, iy: float):
        """The StrategyInfo this robot tells its team for ``cmd`` (``ix``, ``iy``: its intent, float32)."""
        p = cmd.pass_intent
        if p is None:
            pass_cmd = _NO_PASS
        else:
            px, py, cx, cy = _f32s(p.pass_x, p.pass_y, p.catch_x, p.catch_y)
            pass_cmd = msgs.PassCommands(
                pass_id=self.rid,
                catch_id=p.catch_id,
                pass_x=px,
                pass_y=py,
                catch_x=cx,
                catch_y=cy,
                is_passout=bool(p.kicked),
                is_dynamic_pass=bool(p.dynamic),
                is_static_pass=bool(p.static),
                is_valid=True,
            )
        world = self.world
        me = world._me  # (`WorldModel.me`, without the property's call when found already)
        try:
            holding = bool((me if me is not None else world.me).holding_ball)
        except LookupError:
            holding = False
        return _StrategyInfo(
            now,
            tick,
            self.rid,
            cmd.role,
            cmd.action,
            holding,
            False,
            0.0,
            ix,
            iy,
            np.array(cmd.target_num, dtype=np.int32) if cmd.target_num else _EMPTY_I32,
            0,
            0,
            pass_cmd,
            self._user_array(cmd.user),
        )

    def _user_array(self, user: tuple) -> np.ndarray:
        """``user`` as the StrategyInfo's float64 array; the array of the tick before again when the command
        carries the very same tuple (a robot repeating its command; messages are read-only, so they may share it)."""
        if not user:
            return _EMPTY_F64
        if user is self._user[0]:
            return self._user[1]
        n = len(user)
        pack = _USER_PACK.get(n)
        if pack is None:
            pack = _USER_PACK[n] = struct.Struct(f"{n}d").pack
        try:
            # (read-only, as messages are: the numbers np.array(user, dtype=np.float64) holds)
            arr = _frombuffer(pack(*user))
        except struct.error:  # (something else than numbers: NumPy's conversion, or its error)
            arr = np.array(user, dtype=np.float64)
        if type(user) is tuple:  # (a list may change in place: never kept)
            self._user = (user, arr)
        return arr

    def _error(self, now: float, exc: Exception) -> None:
        self.errors += 1
        if self.errors == 1 or self.errors % 100 == 0:
            where = traceback.extract_tb(exc.__traceback__)[-1] if exc.__traceback__ else None
            detail = f"{type(exc).__name__}: {exc}" + (f" ({where.filename}:{where.lineno})" if where else "")
            log.warning("strategy of %s failed (%d errors so far): %s", self.name, self.errors, detail)
            self.pub_events.put(
                msgs.GameEvent(
                    stamp=now,
                    type="strategy_error",
                    team=self.team,
                    robot=self.rid,
                    x=0.0,
                    y=0.0,
                    value=float(self.errors),
                    limit=0.0,
                    detail=detail,
                )
            )

    def stop(self) -> None:
        for sub in getattr(self, "subs", []):
            sub.close()


class StrategyPub(Node):
    """Gathers the StrategyInfo of a team's robots and publishes the fused team picture, dropping entries
    older than ``stale_after`` (a robot that went silent disappears from its teammates' picture)."""

    phase = Phase.TEAM

    def __init__(self, team: str, period: float, stale_after: float):
        self.team = team
        self.name = f"{team}/strategy_pub"
        self.period = period
        self.stale_after = stale_after
        self.latest: dict[int, object] = {}

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        self.sub = ctx.bus.subscribe(
            topics.team_topic(self.team, f"*/{topics.STRATEGY_INFO}"), msgs.StrategyInfo, self._on_info
        )
        self.pub = ctx.bus.publisher(topics.team_topic(self.team, topics.TEAM_STRATEGY), msgs.TeamStrategy)

    def _on_info(self, msg) -> None:
        self.latest[msg.agent_id] = msg

    def tick(self, now: float) -> None:
        latest = self.latest
        limit = self.stale_after + 1e-9
        fresh = []  # (in id order: the ids are the dict's keys, each once; a loop, not a comprehension's frame)
        for rid in sorted(latest):
            m = latest[rid]
            if now - m.stamp <= limit:
                fresh.append(m)
        self.pub.put(_TeamStrategy(now, 0, fresh))

    def stop(self) -> None:
        self.sub.close()
