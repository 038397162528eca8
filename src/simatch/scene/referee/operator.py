"""Operator takeover (manual mode, as the original referee's keys): the requests an operator may make, from
the Python API (methods of `MslReferee`) or from the bus (a RefereeCommand on ``referee_command``, e.g. from
the web referee console). Both become an `OperatorRequest`, checked here: a request that cannot be carried
out is refused with a message that says why, and never reaches the match.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...msgs.game_commands import MatchMode

OPS = ("pause", "resume", "command", "place_ball", "send_off", "return", "card", "goal", "auto")


class OperatorError(ValueError):
    """A request the referee refuses (it is logged as ``operator_refused`` when it came from the bus)."""


@dataclass(frozen=True)
class OperatorRequest:
    op: str
    team: str = ""
    robot: str = ""  # "team/id"
    command: MatchMode | None = None
    x: float | None = None
    y: float | None = None
    card: str = ""
    seconds: float | None = None
    on: bool = True
    source: str = "api"

    def describe(self) -> str:
        if self.op == "command":
            who = f" for {self.team}" if self.team else ""
            where = f" at ({self.x:.2f}, {self.y:.2f})" if self.x is not None else ""
            return f"command {self.command.name}{who}{where}"
        if self.op == "place_ball":
            return f"place the ball at ({self.x:.2f}, {self.y:.2f})"
        if self.op == "send_off":
            length = "until returned" if self.seconds is None else f"for {self.seconds:g} s"
            return f"send {self.robot} off {length}"
        if self.op == "return":
            return f"bring {self.robot} back"
        if self.op == "card":
            return f"{self.card} card for {self.robot}"
        if self.op == "goal":
            return f"award a goal to {self.team}"
        if self.op == "auto":
            return "automatic judging " + ("on" if self.on else "off (manual mode)")
        return self.op


def check(req: OperatorRequest, teams: list[str], robots: list[str], field) -> OperatorRequest:
    """``req`` if it can be carried out, else OperatorError saying why."""
    if req.op not in OPS:
        raise OperatorError(f"unknown operator request {req.op!r} (one of: {', '.join(OPS)})")
    if req.team and req.team not in teams:
        raise OperatorError(f"no team named {req.team!r} (teams: {', '.join(teams)})")
    if req.op in ("send_off", "return", "card") and req.robot not in robots:
        raise OperatorError(f"no robot named {req.robot!r} (robots: {', '.join(robots)})")
    if req.op == "goal" and not req.team:
        raise OperatorError("a goal needs the team it is for")
    if req.op == "card" and req.card not in ("yellow", "red"):
        raise OperatorError(f"a card is 'yellow' or 'red', not {req.card!r}")
    if req.op == "send_off" and req.seconds is not None and not (math.isfinite(req.seconds) and req.seconds > 0):
        raise OperatorError(f"send-off time {req.seconds!r} must be a positive number of seconds")
    for v in (req.x, req.y):
        if v is not None and not math.isfinite(v):
            raise OperatorError(f"position ({req.x!r}, {req.y!r}) is not a pair of finite numbers")
    if req.op == "place_ball":
        if req.x is None or req.y is None:
            raise OperatorError("place_ball needs x and y")
        if not field.in_field(req.x, req.y, field.margin - 0.2):
            raise OperatorError(f"({req.x:.2f}, {req.y:.2f}) is not on the floor of the field")
    if req.op == "command":
        cmd = req.command
        if cmd is None:
            raise OperatorError("command needs a game command")
        if cmd == MatchMode.TEST:
            raise OperatorError("TEST is a coach's command, not a referee's")
        if 1 <= cmd <= 12 and not req.team:
            raise OperatorError(f"{cmd.name} needs the team it is given to")
        if req.x is not None and not field.in_field(req.x, req.y):
            raise OperatorError(f"restart spot ({req.x:.2f}, {req.y:.2f}) is outside the field")
    return req


def from_message(msg) -> OperatorRequest:
    """The request a RefereeCommand message carries (checked later by `check`)."""
    op = str(msg.op).strip().lower()
    robot = f"{msg.team}/{int(msg.robot)}" if op in ("send_off", "return", "card") else ""
    cmd = None
    if op == "command":
        try:
            cmd = MatchMode(int(msg.command))
        except ValueError:
            raise OperatorError(f"no game command numbered {int(msg.command)}") from None
    has_xy = bool(msg.has_position) or op == "place_ball"
    return OperatorRequest(
        op=op,
        team=str(msg.team),
        robot=robot,
        command=cmd,
        x=float(msg.x) if has_xy else None,
        y=float(msg.y) if has_xy else None,
        card=str(msg.card).lower(),
        seconds=float(msg.seconds) if op == "send_off" and msg.seconds != 0 else None,
        on=bool(msg.on),
        source=str(msg.source) or "bus",
    )
