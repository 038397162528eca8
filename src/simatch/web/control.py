"""Carrying out what the pages ask, inside the run's own thread and lockstep, through calls that a recording
keeps — so that a run driven from the web is reproduced by ``simatch replay --verify``.

The pages' messages arrive in the server's thread; the simulation runs in the main thread. Nothing may
touch the run from the side: `RunControl` queues each validated request and a node of the run
(`ControlNode`, JUDGE phase, every physics step, after the run's own judge and coaches) carries it out
between the nodes of one step. What it calls depends on who gives the game commands:

* a run with a referee (``judge.kind = "msl_referee"``): the referee console is the referee's operator.
  Every request — pause, resume, any command, the ball, send-off and return, cards, a goal, automatic
  judging on/off — goes to the referee as a ``RefereeCommand`` on the bus (`RefereeLink`); the referee
  carries it out at its next step, logs it as an ``operator`` event (or ``operator_refused``, with the
  reason) and records it. Coach pages only watch: the referee gives the commands.
* a run without one: each team's `Coach` (a coach page commands its own team; the referee console gives
  each command to both coaches, mirrored, as the original referee did), and the `Simulation` API for the
  ball and sending off (``set_model_state``, ``take_control``, ``send_vel``, ``release_control``).

Every one of these calls is published on the ``operator`` topic by the part that carries it out (coach
commands and Simulation calls by the Simulation, referee requests by the referee), so a recording holds
them and verification makes them again at the same point. The web never assigns a coach's fields or
switches a robot off behind the run's back.
"""

from __future__ import annotations

import logging
import math
import queue
from collections.abc import Callable
from typing import Any

from .. import frames, msgs
from ..bus import Node, Phase, topics
from ..msgs.game_commands import NEUTRAL, MatchMode, TestMode, for_team
from . import protocol as P

log = logging.getLogger(__name__)

Reply = Callable[[str | None], None]

#: who the referee's log names as the maker of a request from the web (with a request number)
SOURCE = "web console"


class ControlError(ValueError):
    """A request that is valid but cannot be carried out in this run (its text goes back to the page)."""


class RefereeLink:
    """The automatic referee's operator interface on the bus: a ``RefereeCommand`` on ``referee_command``
    per request, and its outcome read back from the event log (``operator`` when carried out,
    ``operator_refused`` with the reason). It needs nothing but a bus, so it works as well for a referee in
    another process as for one in this process.

    Each request carries its own ``source`` (``web console #N``), which the referee names in the event it
    logs; that is how an answer finds the page that asked."""

    def __init__(self, bus, now: Callable[[], float], source: str = SOURCE):
        self.now = now
        self.source = source
        self.pub = bus.publisher(topics.REFEREE_COMMAND, msgs.RefereeCommand)
        self.sub = bus.subscribe(topics.EVENTS, msgs.GameEvent, self._on_event)
        self.waiting: dict[str, Reply] = {}
        self.sent = 0

    def request(self, reply: Reply, op: str, **fields: Any) -> None:
        self.sent += 1
        tag = f"{self.source} #{self.sent}"
        self.waiting[tag] = reply
        self.pub.put(msgs.new(msgs.RefereeCommand, stamp=self.now(), op=op, source=tag, **fields))

    def _on_event(self, ev) -> None:
        if ev.type not in ("operator", "operator_refused") or not self.waiting:
            return
        detail = ev.detail or ""
        head, sep, tail = detail.rpartition(" (by " if ev.type == "operator" else " (from ")
        if not sep or not tail.endswith(")"):
            return
        reply = self.waiting.pop(tail[:-1], None)
        if reply is not None:
            reply(None if ev.type == "operator" else f"the referee refused: {head}")

    def close(self, why: str = "the run has ended") -> None:
        self.sub.close()
        waiting, self.waiting = self.waiting, {}
        for reply in waiting.values():
            reply(why)


class ControlNode(Node):
    phase = Phase.JUDGE
    name = "web/control"

    def __init__(self, control: RunControl, period: float):
        self.control = control
        self.period = period

    def tick(self, now: float) -> None:
        self.control.apply_pending()


class RunControl:
    """Requests from the pages to one embedded `Simulation`. ``submit`` may be called from any thread;
    ``apply_pending`` runs in the run's thread (see the module docstring for what each request calls)."""

    def __init__(self, sim):
        self.sim = sim
        spec = sim.scene.spec
        self.spec = spec
        self.teams = list(spec.teams)
        self.ids = {team: spec.teams[team].robot_ids() for team in self.teams}
        self.field = spec.world.geometry()
        self.sent_off: set[str] = set()  # robots the console sent off in a run without a referee
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self.ended = False
        self.referee = RefereeLink(sim.bus, lambda: sim.time) if self.has_referee else None
        self.judge_commands = bool(getattr(sim.judge, "gives_commands", False))
        self.node = sim.clock.add(ControlNode(self, sim.dt))

    # --- any thread ----------------------------------------------------------------------------------------
    def submit(self, grant, message, reply: Reply) -> None:
        """Queue ``message`` (validated, from a page holding ``grant``); ``reply(error or None)`` follows."""
        if self.ended:
            reply("the run has ended: nothing can be commanded any more")
            return
        self._queue.put((grant, message, reply))

    @property
    def has_referee(self) -> bool:
        """The run's judge takes an operator's requests on the bus (the automatic referee does)."""
        return getattr(self.sim.judge, "operator_topic", None) == topics.REFEREE_COMMAND

    def capabilities(self, grant) -> dict:
        """What a page can do in this run (it greys out the rest)."""
        ref = self.has_referee
        if grant.role == "coach":
            return {"commands": grant.team in self.sim.coaches, "referee": ref}
        return {
            "referee": ref,
            "commands": ref or bool(self.sim.coaches),
            "resume": ref,
            "auto_referee": ref,
            "cards": ref,
            "award_goal": ref,
            "place_ball": True,
            "send_off": True,
        }

    # --- the run's thread ------------------------------------------------------------------------------------
    def apply_pending(self) -> None:
        q = self._queue
        while not q.empty():
            grant, message, reply = q.get_nowait()
            try:
                answered_later = self.apply(grant, message, reply)
            except (ControlError, ValueError) as exc:
                reply(str(exc))
            except Exception as exc:  # a page must never bring the run down
                log.exception("web request %r failed", message)
                reply(f"internal error: {type(exc).__name__}: {exc}")
            else:
                if not answered_later:
                    reply(None)

    def close(self) -> None:
        """The run is over: refuse what comes, answer what waits."""
        self.ended = True
        while not self._queue.empty():
            _, _, reply = self._queue.get_nowait()
            reply("the run has ended")
        if self.referee is not None:
            self.referee.close()
        self.sim.clock.remove(self.node)

    def apply(self, grant, m, reply: Reply) -> bool:
        """Carry out ``m``; True if ``reply`` will be called later (by the referee's answer)."""
        if grant.role == "coach":
            self._coach_request(grant.team, m)
            return False
        if self.referee is not None:
            self._referee_request(m, reply)
            return True
        self._console_request(m)
        return False

    # --- coach pages -------------------------------------------------------------------------------------------
    def _coach_request(self, team: str, m) -> None:
        if getattr(m, "team", None) not in (None, team):
            raise ControlError(f"this page commands {team} only, not {m.team}")
        coach = self._coach(team)
        if isinstance(m, P.Command):
            coach.send(m.cmd)
        elif isinstance(m, P.Limits):
            self._limits(coach, m)
        elif isinstance(m, P.Test):
            self._test(coach, team, m)
        else:
            raise ControlError(f"a coach page cannot send '{m.type}'")

    def _coach(self, team: str):
        coach = self.sim.coaches.get(team)
        if coach is None:
            if self.has_referee:
                raise ControlError(f"the referee gives the commands in this run: the {team} coach page only watches")
            if self.judge_commands:
                raise ControlError(
                    f"the judge ({self.spec.judge.kind}) gives the commands in this run and takes "
                    f"no operator's requests"
                )
            raise ControlError(f"team {team} has no coach in this run")
        return coach

    @staticmethod
    def _limits(coach, m: P.Limits) -> None:
        """New limits, given as a coach command (the one in force, with its fields), so that it is recorded."""
        coach.send(coach.match_mode, max_vel=m.max_vel, max_w=m.max_w, **coach.extra)

    def _test(self, coach, team: str, m: P.Test) -> None:
        ids = self.ids[team]
        if m.mode != "stop" and m.robot not in ids:
            raise ControlError(f"{team} has no robot {m.robot} (ids: {', '.join(map(str, ids))})")
        if m.mode == "pass" and m.receiver not in ids:
            raise ControlError(f"{team} has no robot {m.receiver} to pass to")
        sign = self.spec.team_sign(team)
        x, y = frames.point(sign, m.x, m.y)
        fields: dict[str, Any] = {"id_a": m.robot}
        if m.mode == "move":
            mode = {
                (False, False): TestMode.MOVE_NOBALL_NOAVOID,
                (False, True): TestMode.MOVE_NOBALL_AVOID,
                (True, False): TestMode.MOVE_BALL_NOAVOID,
                (True, True): TestMode.MOVE_BALL_AVOID,
            }[(m.dribble, m.avoid)]
            fields.update(point_a_x=x, point_a_y=y, angle_a=frames.yaw(sign, m.heading))
        elif m.mode == "pass":
            mode = TestMode.PASS_BALL
            fields.update(id_b=m.receiver, point_b_x=x, point_b_y=y, kick_force=m.kick)
        elif m.mode == "shoot":
            mode = TestMode.SHOOT_BALL
            fields.update(point_a_x=x, point_a_y=y, kick_force=m.kick)
        elif m.mode == "catch":
            mode = TestMode.CATCH_BALL
        else:
            mode, fields = TestMode.TEST_STOP, {}
        coach.send(MatchMode.TEST, test_mode=int(mode), **fields)

    # --- the referee console, with a referee: its operator --------------------------------------------------------
    def _referee_request(self, m, reply: Reply) -> None:
        send = self.referee.request
        if isinstance(m, P.Command):
            team = m.team or self.teams[0]
            self._team(team)
            send(reply, "command", command=int(m.cmd), team="" if m.cmd in NEUTRAL else team)
        elif isinstance(m, P.Pause):
            send(reply, "pause")
        elif isinstance(m, P.Resume):
            send(reply, "resume")
        elif isinstance(m, P.PlaceBall):
            send(reply, "place_ball", x=m.x, y=m.y)
        elif isinstance(m, P.SendOff):
            team, rid = self._robot(m.robot)
            if m.off:
                send(reply, "send_off", team=team, robot=rid, seconds=m.seconds or 0.0)
            else:
                send(reply, "return", team=team, robot=rid)
        elif isinstance(m, P.Card):
            team, rid = self._robot(m.robot)
            send(reply, "card", team=team, robot=rid, card=m.card)
        elif isinstance(m, P.AwardGoal):
            self._team(m.team)
            send(reply, "goal", team=m.team)
        elif isinstance(m, P.AutoReferee):
            send(reply, "auto", on=m.on)
        elif isinstance(m, P.Limits):
            raise ControlError("with a referee the speed limits are its settings (judge.max_vel, judge.max_w)")
        else:
            raise ControlError(f"'{m.type}' cannot be carried out on a live run")

    def _team(self, team: str) -> str:
        if team not in self.teams:
            raise ControlError(f"unknown team {team!r} (this run has {', '.join(self.teams)})")
        return team

    def _robot(self, name: str) -> tuple[str, int]:
        try:
            team, rid = topics.split_robot_name(name)
        except ValueError as exc:
            raise ControlError(str(exc)) from None
        if team not in self.ids or rid not in self.ids[team]:
            raise ControlError(f"no robot named {name!r}")
        return team, rid

    # --- the referee console, without a referee: the coaches and the Simulation API ---------------------------------
    def _console_request(self, m) -> None:
        if isinstance(m, P.Command):
            self._both_coaches(m.cmd, self._team(m.team or self.teams[0]))
        elif isinstance(m, P.Pause):
            self._both_coaches(MatchMode.STOPROBOT, self.teams[0])
        elif isinstance(m, P.Limits):
            for team in self.teams:
                self._limits(self._coach(team), m)
        elif isinstance(m, P.PlaceBall):
            self._place_ball(m.x, m.y)
        elif isinstance(m, P.SendOff):
            self._send_off(m.robot, m.off)
        elif isinstance(m, (P.Resume, P.Card, P.AwardGoal, P.AutoReferee)):
            raise ControlError(
                f"this run has no automatic referee ('{m.type}' needs one); Start gives START to both teams"
            )
        else:
            raise ControlError(f"'{m.type}' cannot be carried out on a live run")

    def _both_coaches(self, cmd: MatchMode, given_to: str) -> None:
        """``cmd`` from ``given_to``'s point of view, to every team (mirrored), through their coaches."""
        coaches = [self._coach(team) for team in self.teams]
        for team, coach in zip(self.teams, coaches):
            coach.send(for_team(cmd, given_to, team))

    def _place_ball(self, x: float, y: float) -> None:
        f = self.field
        if not f.in_field(x, y, margin=f.margin - 0.2):
            raise ControlError(f"({x:.2f}, {y:.2f}) is off the floor: the ball stays where it is")
        self.sim.set_model_state(
            "ball", x=x, y=y, z=self.spec.ball.radius, vx=0.0, vy=0.0, vz=0.0, wx=0.0, wy=0.0, wz=0.0
        )

    def _send_off(self, name: str, off: bool) -> None:
        """Send a robot off (to the margin beside the side line, where it stands still under the console's
        control) or return it (to the side line, back to its strategy), as the original referee's keys did."""
        team, rid = self._robot(name)
        if off == (name in self.sent_off):
            raise ControlError(f"{name} is already {'off' if off else 'on'} the field")
        f = self.field
        radius = float(self.spec.teams[team].model_params.get("radius", 0.25))
        if off and 0.5 * f.margin < radius + 0.05:
            raise ControlError(f"this field has no room beside it to park a robot (margin {f.margin:g} m)")
        slot = self.ids[team].index(rid) + 1
        x = -self.spec.team_sign(team) * (0.5 + 0.8 * slot)
        sim = self.sim
        if off:
            sim.take_control(name)
            sim.send_vel(name, 0.0, 0.0, 0.0)
            sim.set_model_state(name, x=x, y=-(f.half_width + 0.5 * f.margin), yaw=math.pi / 2, vx=0.0, vy=0.0, wz=0.0)
            self.sent_off.add(name)
        else:
            sim.set_model_state(name, x=x, y=-(f.half_width - 0.4), vx=0.0, vy=0.0, wz=0.0)
            sim.release_control(name)
            self.sent_off.discard(name)
        sim.bus.publisher(topics.EVENTS, msgs.GameEvent).put(
            msgs.GameEvent(
                stamp=sim.time,
                type="send_off" if off else "robot_returned",
                team=team,
                robot=rid,
                x=0.0,
                y=0.0,
                value=0.0,
                limit=0.0,
                detail=f"{name} {'sent off' if off else 'back on the field'} "
                f"(by the referee console; no automatic referee in this run)",
            )
        )
