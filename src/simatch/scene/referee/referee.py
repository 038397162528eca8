"""The automatic MSL referee (``judge.kind = "msl_referee"``): an explicit state machine fed by what it
observes, judging the RoboCup MSL rules, explaining every decision in an append-only event log.

Inputs are topics only: ``model_states`` (every physics step), ``ball_contacts`` (steps where a robot
touches the ball) and ``referee_command`` (an operator). Outputs: each team's game command (CoachInfo on
``<team>/receive_from_coach``, mirrored per team, re-sent every control period), ``game_state`` and the
event log on ``events``. It acts on the world only to place the ball and to park or bring back robots.

When it judges: what must be exact in time — the ball wholly over a line, every touch of the ball — at every
physics step, with a few float comparisons; everything else (positions, areas, dribbling, contacts between
robots, timers) at the control period, on plain lists read from the latest model states.

This file is the state machine: each phase's handling (`state.py` draws the phases), the transitions
between them, and the decisions: every rule's `Call` logged, then enforced. The rest of the referee, one
concern per file: `stages.py` (halves, change of ends, end of the match), `shootout.py` (the penalty
shoot-out), `takeover.py` (the operator's requests), `report.py` (what it reports), `match.py` (what the
rules read), `rules/` (one rule per file).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import replace
from functools import partial
from types import SimpleNamespace

import numpy as np

from ... import msgs
from ...bus import NodeContext, topics
from ...config.loader import SceneError
from ...msgs.game_commands import SET_PIECES, MatchMode, for_team
from ...msgs.game_commands import name as command_name
from ..judges.base import Judge
from . import report
from .discipline import Discipline
from .log import EventLog
from .match import Match
from .params import RefereeParams
from .restarts import NAMES, Restart
from .rules import CONTROL_RULES, BallOutRule, Call, GoalRule, PositionRule
from .shootout import ShootOut, ShootOutKicks
from .stages import StageChanges
from .state import LIVE, Phase
from .takeover import OperatorTakeover

# the phases as plain attributes, read at every step without the Enum metaclass's attribute lookup
_Phase = SimpleNamespace(**Phase.__members__)
_ENDED, _PAUSED = Phase.ENDED, Phase.PAUSED  # (read at every step: globals)
_F32 = np.dtype(np.float32)  # the precision of ModelStates' numbers


class MslReferee(OperatorTakeover, StageChanges, ShootOutKicks, Judge):
    """The referee node: the state machine and its decisions here; the operator's requests, the stage
    changes and the shoot-out's kicks mixed in from `takeover.py`, `stages.py` and `shootout.py`."""

    Params = RefereeParams
    name = "msl_referee"
    gives_commands = True
    set_pieces = True

    def __init__(self, scene, params: RefereeParams, world):
        super().__init__(scene, params, world)
        spec = scene.spec
        if len(spec.teams) != 2:
            raise SceneError(
                f"{scene.source}: judge.kind: msl_referee judges two teams, the scene has {len(spec.teams)}"
            )
        a, b = spec.teams
        if spec.team_sign(a) == spec.team_sign(b):
            raise SceneError(
                f"{scene.source}: teams.{b}.attacks: {a} and {b} both attack "
                f"{'+x' if spec.team_sign(a) > 0 else '-x'}; a referee needs them to attack "
                f"opposite goals"
            )
        self.m = m = Match(scene, params)
        self.p = params
        self.dt = m.dt
        self.period = m.dt
        self.control_steps = m.control_steps
        self.teams = m.game.teams
        self.match_spec = spec.match
        disabled = set(params.disabled_rules)
        self.rules = [cls(m) for cls in CONTROL_RULES if cls.name not in disabled]
        self.position_rules = [r for r in self.rules if isinstance(r, PositionRule)]
        # the rules that judge in each phase, in their order, during a shoot-out or not (a shoot-out judges
        # the set-piece distance and charging alone); keyed by the phase's value, a plain str to hash
        self._judging = {
            (phase._value_, shootout): [
                r
                for r in self.rules
                if phase in r.phases and not (shootout and r.name not in ("set_piece_distance", "charging"))
            ]
            for phase in Phase
            for shootout in (False, True)
        }
        self.goal_rule = GoalRule(m) if "goal" not in disabled else None
        self.out_rule = BallOutRule(m) if "ball_out" not in disabled else None
        self.log = EventLog()
        self._retakes = 0  # times in a row the current restart was taken again (see `_enact`)
        self.discipline = Discipline(m.obs, params, world, self._log_robot)
        self.shootout: ShootOut | None = None
        f = m.obs.field
        # the whole ball past the outer edge of a line (the lines belong to the field)
        self._xlim = f.outer_half_length + m.obs.ball_radius
        self._ylim = f.outer_half_width + m.obs.ball_radius
        # the same limits at the precision of the messages' float32 positions, which NumPy compares with a
        # Python float in float32: comparing the positions read as plain floats with these is the same test
        self._xlim32, self._ylim32 = msgs.f32s(self._xlim, self._ylim)
        # (each limit and its negative, made once for the test at every step)
        self._lims = (self._xlim, -self._xlim, self._ylim, -self._ylim)
        self._lims32 = (self._xlim32, -self._xlim32, self._ylim32, -self._ylim32)
        self._ball_row = -1
        self._out_latched = False
        self._ops: deque = deque()
        self._ticked = -1  # the step of the last tick
        self._begun = False
        self.coach_info: dict[str, object] = {}
        self._published = (-1, -math.inf)  # (game version, time) of the last GameState
        self._last_replace = -math.inf
        self._settle_spot = False
        self._kick_step = 0  # step of the last START
        self._cause = ""  # why play stopped (explains the restart called next)
        self.goals: list[dict] = []

    # --- the run ---------------------------------------------------------------------------------------
    @property
    def duration(self) -> float:
        """Regular time plus the longest shoot-out (the run ends as soon as the match does)."""
        spec, p = self.match_spec, self.p
        total = spec.halves * spec.half_duration + (spec.halves - 1) * spec.half_time
        if spec.penalty_shootout:
            kick = p.stop_time + p.prepare_time + p.shootout_shot_time + 1.0
            total += 2 * (p.shootout_kicks + p.shootout_max_rounds) * kick
        return total + self.m.control_dt

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        bus = ctx.bus
        self.pub_coach = {
            t: bus.publisher(topics.team_topic(t, topics.RECEIVE_FROM_COACH), msgs.CoachInfo) for t in self.teams
        }
        self.pub_state = bus.publisher(topics.GAME_STATE, msgs.GameState)
        pub_events = bus.publisher(topics.EVENTS, msgs.GameEvent)
        self.pub_operator = bus.publisher(topics.OPERATOR, msgs.OperatorCommand)
        self.log = EventLog(pub_events.put)
        self.subs = [
            # the latest states kept by the observation (a reference), set by the bus itself: no callback of
            # ours runs at every step
            bus.subscribe(topics.MODEL_STATES, msgs.ModelStates, partial(setattr, self.m.obs, "msg")),
            bus.subscribe(topics.BALL_CONTACTS, msgs.BallContacts, self._on_contacts),
            bus.subscribe(self.operator_topic, msgs.RefereeCommand, self._on_operator),
        ]

    def stop(self) -> None:
        for sub in getattr(self, "subs", []):
            sub.close()

    def _on_contacts(self, msg) -> None:
        if self._begun:
            self.m.touches.on_contacts(msg)

    # --- every physics step ----------------------------------------------------------------------------------
    def tick(self, now: float) -> None:
        self._ticked = self.ctx.step()
        m = self.m
        msg = m.obs.msg
        if msg is None:
            return
        g = m.game
        if not self._begun:
            self._begin(now)
        if self._ops:
            self._operator_queue(now)
        phase = g.phase
        if phase is _ENDED:
            return
        if phase is not _PAUSED:
            d = g.stages[g.stage_index].duration  # (`g.stage` read directly: this runs at every step)
            if d is not None and g.stage_steps * self.dt >= d - 1e-9:
                self._end_stage(now)
                if g.phase is _ENDED:
                    return
            g.stage_steps += 1
            g.phase_steps += 1
            pose = msg.pose
            b = self._ball_row
            if pose.dtype is _F32:  # read as plain floats: the test at every step compares Python floats
                item = pose.item
                bx, by = item(b), item(b + 1)
                xlim, nxlim, ylim, nylim = self._lims32
            else:  # positions of another precision (not the message's own): compared as they are
                bx, by = pose[b], pose[b + 1]
                xlim, nxlim, ylim, nylim = self._lims
            if bx > xlim or bx < nxlim or by > ylim or by < nylim:
                if g.phase in LIVE and not self._out_latched:
                    self._boundary(now, float(bx), float(by), float(pose[b + 2]))
            elif self._out_latched:
                self._out_latched = False
        if self._ticked % self.control_steps == 0:
            self._control(now)

    def _begin(self, now: float) -> None:
        self._begun = True
        m = self.m
        obs = m.obs
        self._ball_row = 7 * obs.ball_row()
        obs.refresh()
        g = m.game
        spec = self.match_spec
        g.kickoff_team = spec.kickoff
        self._log(now, "stage", detail=f"{g.stage.name} begins", value=g.stage.duration or 0.0)
        if spec.start == "kickoff":
            self._stop(now, m.spots.kickoff(g.kickoff_team), "the match begins")
        elif spec.start == "play":  # a situation looked at again: the ball is in play from the first step
            g.go(_Phase.PLAY)
            self._send(now, MatchMode.STARTROBOT, "", "the match begins with the ball in play (match.start)")
        else:  # ... or a restart
            team = "" if spec.start == "dropped_ball" else (spec.start_team or spec.kickoff)
            x, y = spec.start_spot if spec.start_spot is not None else (obs.bx, obs.by)
            if spec.start == "penalty":
                restart = m.spots.penalty(team, obs.own_goal_side(obs.other(team)))
            else:
                restart = Restart(spec.start, team, float(x), float(y))
            self._stop(now, restart, f"the match begins with a {NAMES[spec.start]} (match.start)")

    # --- every control period ------------------------------------------------------------------------------
    def _control(self, now: float) -> None:
        """Every control period: the phase's own handling, then the rules that judge in it, each call enacted
        (the first that changes the phase ends the round), then every team's command re-sent."""
        m = self.m
        g = m.game
        m.obs.refresh()
        if g.phase is not _Phase.PAUSED:
            m.contacts.update()
        if g.phase is _Phase.STOPPED or g.phase is _Phase.PREPARE:
            for i in self.discipline.due(now):
                self.discipline.bring_back(i, "its time off is over and the ball is dead")
        if g.phase is _Phase.STOPPED:
            self._stopped(now)
        elif g.phase is _Phase.PREPARE:
            self._prepare(now)
        elif g.phase is _Phase.TAKING:
            self._taking(now)
        shootout = g.stages[g.stage_index].kind == "shootout"  # (`g.stage` read directly, as in `tick`)
        if shootout and (g.phase is _Phase.TAKING or g.phase is _Phase.PLAY):
            self._shootout_check(now)
            shootout = g.stages[g.stage_index].kind == "shootout"
        phase = g.phase
        if phase is not _Phase.PAUSED and phase is not _Phase.ENDED:
            for rule in self._judging[phase._value_, shootout]:
                calls = rule.check()
                if calls is None:
                    continue
                for call in calls if isinstance(calls, list) else (calls,):
                    self._enact(now, call)
                if g.phase is not phase:
                    break
        self._publish(now)

    def _taking(self, now: float) -> None:
        """A set piece is being taken: the ball is in play once it has moved ``in_play_distance``."""
        g, obs = self.m.game, self.m.obs
        r = g.restart
        moved = math.hypot(obs.bx - r.x, obs.by - r.y)
        if moved >= self.p.in_play_distance:
            self._log(
                now,
                "ball_in_play",
                team=r.team,
                x=obs.bx,
                y=obs.by,
                value=moved,
                limit=self.p.in_play_distance,
                detail=f"the {NAMES[r.kind]} is taken: the ball moved {moved:.2f} m, it is in play",
            )
            self._retakes = 0
            g.go(_Phase.PLAY)

    def _stopped(self, now: float) -> None:
        g = self.m.game
        if g.hold or not g.auto or g.stage.kind not in ("half", "shootout"):
            return
        if g.phase_time >= self.p.stop_time - 1e-9 and g.next_restart is not None:
            self._call_restart(now, g.next_restart, self._cause)

    def _prepare(self, now: float) -> None:
        m = self.m
        g, obs, r = m.game, m.obs, m.game.restart
        bx, by = obs.bx, obs.by
        off = math.hypot(bx - r.x, by - r.y)
        if self._settle_spot:
            self._settle_spot = False
            if 1e-6 < off < 0.6:  # placed against a robot: the simulator moved it out; that is the spot
                g.restart = r = replace(r, x=bx, y=by)
                off = 0.0
        if off > self.p.replace_distance and now - self._last_replace >= 1.0:
            self._last_replace = now
            self._place_ball(r.x, r.y)
            self._log(
                now,
                "ball_placed",
                team=r.team,
                x=r.x,
                y=r.y,
                value=off,
                limit=self.p.replace_distance,
                detail=f"the ball had moved {off:.2f} m off the spot of the {NAMES[r.kind]}: put back",
            )
        if not g.auto:
            return
        t = g.phase_time
        longest = self.p.kickoff_prepare_time if r.kind == "kickoff" else self.p.prepare_time
        if t >= longest - 1e-9 or (
            t >= self.p.prepare_min_time - 1e-9 and all(rl.ready() for rl in self.position_rules)
        ):
            self._start(now)

    # --- transitions -----------------------------------------------------------------------------------------
    def _call_restart(self, now: float, r: Restart, reason: str) -> None:
        """Place the ball and call the restart (stopped -> prepare)."""
        m = self.m
        g = m.game
        self._place_ball(r.x, r.y)
        self._settle_spot = True
        self._last_replace = now
        self._log(now, "ball_placed", team=r.team, x=r.x, y=r.y, detail=f"ball placed for the {r.describe()}")
        g.restart = r
        g.next_restart = None
        g.hold = False
        m.touches.on_restart()
        for rule in self.rules:
            rule.on_restart()
        g.go(_Phase.PREPARE)
        self._send(now, r.command_for(r.team) if r.team else MatchMode.DROPBALL, r.team, f"{r.describe()} ({reason})")

    def _start(self, now: float) -> None:
        """START: log who is out of position, then the set piece is taken (a dropped ball is in play)."""
        m = self.m
        g = m.game
        for rule in self.position_rules:
            for call in rule.at_start():
                self._enact(now, call)
        r = g.restart
        m.touches.on_restart()
        if r.kind != "dropped_ball":
            m.touches.arm_taker()
        self._kick_step = self.ctx.step()
        g.go(_Phase.PLAY if r.kind == "dropped_ball" else _Phase.TAKING)
        self._send(now, MatchMode.STARTROBOT, "", f"START: the {r.describe()}")

    def _stop(self, now: float, restart: Restart, reason: str) -> None:
        """Stop play (STOP to every team); ``restart`` follows when the stoppage is over."""
        g = self.m.game
        if g.phase is _Phase.PAUSED:
            g.paused_phase = _Phase.STOPPED
        else:
            g.go(_Phase.STOPPED)
        g.next_restart = restart
        g.hold = False
        self._cause = reason
        self._send(now, MatchMode.STOPROBOT, "", f"{reason}; next: {restart.describe()}")

    def _boundary(self, now: float, bx: float, by: float, bz: float) -> None:
        """The ball is wholly over a line (physics rate)."""
        self._out_latched = True
        self.m.obs.refresh()
        over_x = abs(bx) - self._xlim
        over_y = abs(by) - self._ylim
        side = 1 if bx > 0 else -1
        call = None
        in_goal = over_x > 0 and self.goal_rule is not None and self.goal_rule.in_goal(by, bz)
        if self.m.game.stage.kind == "shootout":
            self._shootout_result(now, in_goal, "the ball went in" if in_goal else "the ball left the field")
            return
        if in_goal:
            call = self.goal_rule.crossed(side, bx, by, bz)
        elif self.out_rule is not None:
            if over_x > 0 and over_x >= over_y:
                call = self.out_rule.crossed_goal_line(side, bx, by, bz)
            else:
                call = self.out_rule.crossed_side_line(bx, by)
        if call is not None:
            self._enact(now, call)

    # --- decisions ----------------------------------------------------------------------------------------------
    def _enact(self, now: float, call: Call) -> None:
        """A rule's call: logged, then enforced (in manual mode only logged, as a proposal to the operator)."""
        m = self.m
        g = m.game
        if not g.auto:
            self._log_call(now, call, "proposal", f"{call.type} (not enforced: manual mode): {call.detail}")
            return
        self._log_call(now, call)
        if g.stage.kind == "shootout" and call.restart is not None and g.restart is not None:
            self._shootout_foul(now, call)
            return
        if call.goal_for:
            self._score(now, call)
        if call.card and call.robot >= 0:
            self.discipline.card(call.robot, call.card, now, call.detail)
        if call.in_play and g.phase is _Phase.TAKING:
            # the set piece was not taken: the ball is in play for everybody and nobody is its taker
            m.touches.disarm()
            g.go(_Phase.PLAY)
        if call.restart is not None:
            retake = call.restart is g.restart and g.phase is _Phase.TAKING
            self._retakes = self._retakes + 1 if retake else 0
            if retake and self._retakes > self.p.max_retakes:
                self._end_restart_loop(now, call)
                return
            self._stop(now, call.restart, call.detail)

    def _end_restart_loop(self, now: float, call: Call) -> None:
        """The guard no rule provides: a restart that would be taken again more than ``max_retakes`` times in
        a row is not; the ball is in play for everybody, as when a set piece is not taken in time (the
        offenders have been cautioned each time). Whatever a team does, the match goes on."""
        g, r = self.m.game, self.m.game.restart
        self._retakes = 0
        self._log(
            now,
            "restart_loop",
            team=r.team,
            x=r.x,
            y=r.y,
            value=self.p.max_retakes + 1,
            limit=self.p.max_retakes,
            detail=f"the {NAMES[r.kind]} would be taken again a {self.p.max_retakes + 1}th time in a row "
            f"({call.type}): it is not; the ball is in play for everybody",
        )
        self.m.touches.disarm()
        g.go(_Phase.PLAY)

    def _score(self, now: float, call: Call) -> None:
        """A goal that counts: the score, and the goal in the result (its scorer; whether it is an own goal)."""
        g, obs = self.m.game, self.m.obs
        g.score[call.goal_for] += 1
        g.version += 1
        scorer = call.scorer if call.scorer >= 0 else call.robot
        goal = {"t": round(now, 6), "team": call.goal_for, "robot": obs.names[scorer] if scorer >= 0 else ""}
        if scorer >= 0 and obs.team_of[scorer] != call.goal_for:
            goal["own_goal"] = True
        self.goals.append(goal)

    # --- commands to the teams ---------------------------------------------------------------------------------------
    def _send(self, now: float, cmd: MatchMode, team: str, reason: str) -> None:
        """Give ``cmd`` (from ``team``'s point of view; "" for a neutral command) to every team."""
        g = self.m.game
        g.command, g.command_team, g.reason = MatchMode(cmd), team, reason
        g.version += 1
        r = g.restart if cmd != MatchMode.STOPROBOT else (g.next_restart or g.restart)
        for t in self.teams:
            mode = for_team(cmd, team, t) if team else MatchMode(cmd)
            if mode in SET_PIECES:
                g.match_type[t] = mode
            sign = self.m.obs.sign[t]
            bx, by = (sign * r.x, sign * r.y) if r is not None else (0.0, 0.0)
            info = msgs.new(
                msgs.CoachInfo,
                stamp=now,
                match_mode=int(mode),
                match_type=int(g.match_type[t]),
                max_vel=self.p.max_vel,
                max_w=self.p.max_w,
                ball_x=bx,
                ball_y=by,
            )
            self.coach_info[t] = info
            self.pub_coach[t].put(info)  # at once; and again every control period
        self._log(
            now,
            "command",
            team=team,
            value=float(cmd),
            detail=f"{command_name(cmd)}" + (f" for {team}" if team else "") + f": {reason}",
        )

    def _publish(self, now: float, force: bool = False) -> None:
        for t, pub in self.pub_coach.items():
            info = self.coach_info.get(t)
            if info is not None:
                pub.put(info)
        g = self.m.game
        version, last = self._published
        if force or g.version != version or now - last >= self.p.game_state_period - 1e-9:
            self._published = (g.version, now)
            if self.pub_state.active:
                self.pub_state.put(self.game_state(now))

    # --- ball and log helpers -----------------------------------------------------------------------------------------
    def _place_ball(self, x: float, y: float) -> None:
        self.world.set_model_state(
            "ball", x=x, y=y, z=self.m.obs.ball_radius, vx=0.0, vy=0.0, vz=0.0, wx=0.0, wy=0.0, wz=0.0
        )
        self._out_latched = False

    def _log(self, now: float, type: str, **fields):
        return self.log.add(now, type, **fields)

    def _log_call(self, now: float, call: Call, type: str = "", detail: str | None = None) -> None:
        """Log a rule's call: as its own type and detail, or as ``type`` with ``detail``."""
        self.log.add(
            now,
            type or call.type,
            team=call.team,
            robot=self.m.obs.rid[call.robot] if call.robot >= 0 else 0,
            x=call.x,
            y=call.y,
            value=call.value,
            limit=call.limit,
            detail=call.detail if detail is None else detail,
        )

    def _log_robot(
        self, type: str, i: int, value: float, limit: float, detail: str, at: tuple[float, float] | None = None
    ) -> None:
        obs = self.m.obs
        x, y = at if at is not None else (obs.X[i], obs.Y[i])
        self.log.add(
            self.ctx.now(),
            type,
            team=obs.team_of[i],
            robot=obs.rid[i],
            x=x,
            y=y,
            value=value,
            limit=limit,
            detail=detail,
        )

    # --- what the referee reports (see report.py) ------------------------------------------------------------
    def winner(self) -> str | None:
        return report.winner(self)

    def game(self) -> dict:
        return report.game(self)

    def result(self) -> dict:
        return report.result(self)

    def game_state(self, now: float):
        return report.game_state(self, now)
