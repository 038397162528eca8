"""Operator takeover, the referee's side: the Python API an operator calls (``sim.judge.pause()``, ...), the
requests that come on the bus, and what each does to the match. Requests are checked in `operator.py`;
every one is logged as an ``operator`` event naming who made it, before it takes effect.

Every request is also published as an `OperatorCommand` on the ``operator`` topic (when somebody, e.g. a
recorder, listens), so that ``simatch replay --verify`` can make it again at the same point of the run:
an API call as ``judge.<method>``, a request from the bus as ``judge.request`` with the RefereeCommand's
fields, stamped with the step at whose referee tick it is carried out.
"""

from __future__ import annotations

import json
from dataclasses import replace

from ... import msgs
from ...bus import topics
from ...msgs.game_commands import MatchMode, is_ours, parse, restart_kind
from .operator import OperatorError, OperatorRequest, check, from_message
from .restarts import Restart
from .state import Phase, TransitionError


class OperatorTakeover:
    """Mixed into `MslReferee`: pause, any command, the ball, cards, sending off, automatic judging."""

    #: the topic on which it takes an operator's requests (RefereeCommand), e.g. from the web referee console
    operator_topic = topics.REFEREE_COMMAND
    #: the methods a recorded operator command may name (``judge.<method>``), for ``simatch replay --verify``
    operator_calls = (
        "pause",
        "resume",
        "command",
        "place_ball",
        "send_off",
        "return_robot",
        "card",
        "award_goal",
        "set_auto",
        "request",
    )

    def pause(self, source: str = "api") -> None:
        """Halt the game: robots STOP, the clock stands still, until `resume`."""
        self.operate(OperatorRequest("pause", source=source))
        self._record("pause", source=source)

    def resume(self, source: str = "api") -> None:
        self.operate(OperatorRequest("resume", source=source))
        self._record("resume", source=source)

    def command(
        self, cmd: int | str, team: str = "", spot: tuple[float, float] | None = None, source: str = "api"
    ) -> None:
        """Give any game command, from ``team``'s point of view (``"OUR_FREEKICK"``, 11, ``"opp corner"``).
        A set piece is prepared and, with automatic judging on, started when the robots are in position."""
        mode = parse(cmd) if isinstance(cmd, str) else MatchMode(cmd)
        x, y = spot if spot is not None else (None, None)
        self.operate(OperatorRequest("command", team=team, command=mode, x=x, y=y, source=source))
        self._record("command", cmd=int(mode), team=team, spot=None if spot is None else [x, y], source=source)

    def place_ball(self, x: float, y: float, source: str = "api") -> None:
        self.operate(OperatorRequest("place_ball", x=float(x), y=float(y), source=source))
        self._record("place_ball", x=float(x), y=float(y), source=source)

    def send_off(self, robot: str, seconds: float | None = None, source: str = "api") -> None:
        """Send ``robot`` (e.g. ``"cyan/3"``) off for ``seconds`` (None: until `return_robot`)."""
        self.operate(OperatorRequest("send_off", robot=robot, seconds=seconds, source=source))
        self._record("send_off", robot=robot, seconds=seconds, source=source)

    def return_robot(self, robot: str, source: str = "api") -> None:
        self.operate(OperatorRequest("return", robot=robot, source=source))
        self._record("return_robot", robot=robot, source=source)

    def card(self, robot: str, colour: str, source: str = "api") -> None:
        self.operate(OperatorRequest("card", robot=robot, card=colour, source=source))
        self._record("card", robot=robot, colour=colour, source=source)

    def award_goal(self, team: str, source: str = "api") -> None:
        self.operate(OperatorRequest("goal", team=team, source=source))
        self._record("award_goal", team=team, source=source)

    def set_auto(self, on: bool, source: str = "api") -> None:
        """Automatic judging on, or off (manual mode: the referee only proposes, the operator commands)."""
        self.operate(OperatorRequest("auto", on=bool(on), source=source))
        self._record("set_auto", on=bool(on), source=source)

    def request(self, **fields) -> None:
        """Take a request as if it came on the bus (RefereeCommand fields): carried out at the next tick.
        This is how ``simatch replay --verify`` makes a recorded bus request again."""
        self._ops.append(msgs.new(msgs.RefereeCommand, **fields))

    def _on_operator(self, msg) -> None:
        """A RefereeCommand from the bus: queued for the next tick (and recorded as ``judge.request``)."""
        self._ops.append(msg)
        pub = getattr(self, "pub_operator", None)
        if pub is not None and pub.active:
            fields = {
                k: getattr(msg, k)
                for k in msgs.RefereeCommand.__dataclass_fields__
                if k != "stamp" and not k.startswith("__")
            }
            step = self.ctx.step()
            if self._ticked == step:  # after this step's tick: carried out at the next one
                step += 1
            self._publish_operator("request", step, _plain(fields))

    def _record(self, method: str, **args) -> None:
        """Publish an API request that was carried out (when anybody listens), made between two steps or by a
        node that ticks after the referee within a step."""
        pub = getattr(self, "pub_operator", None)
        if pub is not None and pub.active:
            step = self.ctx.step()
            self._publish_operator(method, step, args, during_step=self._ticked == step)

    def _publish_operator(self, method: str, step: int, args: dict, during_step: bool = False) -> None:
        self.pub_operator.put(
            msgs.OperatorCommand(
                stamp=self.ctx.now(),
                step=step,
                during_step=during_step,
                call=f"judge.{method}",
                target="",
                args=json.dumps(args),
            )
        )

    @property
    def auto(self) -> bool:
        return self.m.game.auto

    def operate(self, req: OperatorRequest) -> None:
        """Carry out an operator's request now (OperatorError if it cannot be)."""
        m = self.m
        req = check(req, self.teams, m.obs.names, m.obs.field)
        if not self._begun:
            raise OperatorError("the referee has not started yet: step the simulation once first")
        if m.game.ended:
            raise OperatorError("the match is over")
        if req.op == "return" and m.obs.index[req.robot] not in self.discipline.off_until:
            raise OperatorError(f"{req.robot} is not sent off")
        now = self.ctx.now()
        self._log(
            now,
            "operator",
            team=req.team or (req.robot.split("/")[0] if req.robot else ""),
            value=float(req.command) if req.command is not None else 0.0,
            detail=f"{req.describe()} (by {req.source})",
        )
        getattr(self, "_op_" + req.op)(now, req)
        self._publish(now, force=True)

    def _operator_queue(self, now: float) -> None:
        while self._ops:
            msg = self._ops.popleft()
            try:
                self.operate(from_message(msg))
            except (OperatorError, TransitionError, ValueError, TypeError, AttributeError) as exc:
                self._log(now, "operator_refused", detail=f"{exc} (from {getattr(msg, 'source', '') or 'bus'})")

    def _op_pause(self, now: float, req: OperatorRequest) -> None:
        g = self.m.game
        if g.phase in (Phase.PAUSED, Phase.ENDED):
            return
        steps = g.phase_steps
        g.paused_phase = g.phase
        g.go(Phase.PAUSED)
        g.phase_steps = steps
        self._send(now, MatchMode.STOPROBOT, "", "the operator paused the game")

    def _op_resume(self, now: float, req: OperatorRequest) -> None:
        g = self.m.game
        if g.phase is not Phase.PAUSED:
            return
        back = g.paused_phase or Phase.STOPPED
        steps = g.phase_steps
        g.go(back)
        g.phase_steps = steps
        g.paused_phase = None
        if back in (Phase.TAKING, Phase.PLAY):
            self._send(now, MatchMode.STARTROBOT, "", "the operator resumed the game")
        elif back is Phase.PREPARE:
            r = g.restart
            self._send(
                now, r.command_for(r.team) if r.team else MatchMode.DROPBALL, r.team, "the operator resumed the game"
            )
        else:
            self._send(now, MatchMode.STOPROBOT, "", "the operator resumed the game (the ball is dead)")

    def _op_command(self, now: float, req: OperatorRequest) -> None:
        m = self.m
        g, obs = m.game, m.obs
        cmd = req.command
        if g.phase is Phase.PAUSED:
            g.paused_phase = None
        if cmd in (MatchMode.STOPROBOT, MatchMode.PARKINGROBOT):
            g.go(Phase.STOPPED)
            g.hold = True
            m.touches.disarm()  # a set piece being taken is interrupted: it has no taker any more
            g.next_restart = None
            self._send(
                now,
                cmd,
                "",
                "the operator stopped the game" if cmd == MatchMode.STOPROBOT else "the operator parks the robots",
            )
        elif cmd == MatchMode.STARTROBOT:
            if g.phase is Phase.PREPARE:
                self._start(now)
            elif g.phase in (Phase.TAKING, Phase.PLAY):
                self._send(now, cmd, "", "the operator confirmed play")
            else:
                m.touches.on_restart()
                for rule in self.rules:
                    rule.on_restart()
                g.restart = None
                g.next_restart = None
                g.hold = False
                g.go(Phase.PLAY)
                self._send(now, cmd, "", "the operator started play (the ball is in play)")
        else:
            kind = restart_kind(cmd)
            taker = "" if kind == "dropped_ball" else (req.team if is_ours(cmd) else obs.other(req.team))
            if kind == "kickoff":
                r = m.spots.kickoff(taker)
            elif kind == "penalty":
                r = m.spots.penalty(taker, obs.own_goal_side(obs.other(taker)))
            elif req.x is not None:
                r = Restart(kind, taker, req.x, req.y)
            else:
                r = Restart(kind, taker, obs.bx, obs.by)
            if g.phase is not Phase.STOPPED:
                g.go(Phase.STOPPED)
            self._call_restart(now, r, "the operator called it")

    def _op_place_ball(self, now: float, req: OperatorRequest) -> None:
        g = self.m.game
        self._place_ball(req.x, req.y)
        if g.phase is Phase.PREPARE and g.restart is not None:
            g.restart = replace(g.restart, x=req.x, y=req.y)
        self._log(now, "ball_placed", x=req.x, y=req.y, detail="the operator placed the ball")

    def _op_send_off(self, now: float, req: OperatorRequest) -> None:
        i = self.m.obs.index[req.robot]
        self.discipline.send_off(i, now, req.seconds, "the operator sent it off")

    def _op_return(self, now: float, req: OperatorRequest) -> None:
        self.discipline.bring_back(self.m.obs.index[req.robot], "the operator brought it back")

    def _op_card(self, now: float, req: OperatorRequest) -> None:
        self.discipline.card(self.m.obs.index[req.robot], req.card, now, "shown by the operator")

    def _op_goal(self, now: float, req: OperatorRequest) -> None:
        g = self.m.game
        g.score[req.team] += 1
        g.version += 1
        self.goals.append({"t": round(now, 6), "team": req.team, "robot": ""})
        self._log(now, "goal", team=req.team, detail=f"goal for {req.team}, awarded by the operator")

    def _op_auto(self, now: float, req: OperatorRequest) -> None:
        g = self.m.game
        g.auto = req.on
        g.version += 1


def _plain(fields: dict) -> dict:
    """Message fields as JSON values (numpy scalars and bytes become numbers and text)."""
    out = {}
    for k, v in fields.items():
        if hasattr(v, "item"):
            v = v.item()
        out[k] = v
    return out
