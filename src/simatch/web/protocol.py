"""The WebSocket protocol between the pages and the server: JSON objects with a ``type``.

Server to page: ``hello`` (once: the field, the teams, what this page may do), ``frame`` (about 30 a
second), ``events`` (new entries of the event log), ``ack`` / ``error`` (the answer to a message that
carried an ``id``; an error always gets an answer). Page to server: the messages modelled below.

Every message a page sends is validated here before anything acts on it: a malformed or forbidden
message gets an ``error`` answer naming what is wrong, and changes nothing. Positions are in the world
frame (metres); the server turns them into a team's frame where the scene interface wants that.
"""

from __future__ import annotations

import json
import math
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, ValidationError, field_validator

from ..msgs.game_commands import MatchMode

MAX_MESSAGE_BYTES = 16384


class ProtocolError(ValueError):
    """A message that cannot be carried out; its text is sent back to the page."""


class _Msg(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    id: int | str | None = Field(None, description="echoed in the answer")


def _command(value) -> MatchMode:
    if isinstance(value, bool):
        raise ValueError("a game command is a name (e.g. STOPROBOT) or its number")
    if isinstance(value, str):
        try:
            return MatchMode[value.strip().upper()]
        except KeyError:
            raise ValueError(
                f"unknown game command {value!r} (expected one of {', '.join(m.name for m in MatchMode)})"
            ) from None
    try:
        return MatchMode(value)
    except ValueError:
        raise ValueError(f"unknown game command number {value!r}") from None


class Command(_Msg):
    """A game command. From a coach page: from its team's point of view, for its team only. From the
    referee console: from ``team``'s point of view (default: the first team), for both teams."""

    type: Literal["command"]
    cmd: int | str
    team: str | None = None

    @field_validator("cmd", mode="before")
    @classmethod
    def _cmd(cls, v):
        return _command(v)


class Limits(_Msg):
    """The speed and turn-rate limits a coach allows its robots (the original coach: 4.5 m/s, 10 rad/s)."""

    type: Literal["limits"]
    max_vel: float = Field(gt=0.0, le=10.0, description="[m/s]")
    max_w: float = Field(gt=0.0, le=30.0, description="[rad/s]")


class Test(_Msg):
    """A test command for one robot of the coach's team (CoachInfo in TEST mode)."""

    type: Literal["test"]
    mode: Literal["move", "pass", "shoot", "catch", "stop"]
    robot: int = Field(0, ge=0, le=99)
    x: float = Field(0.0, ge=-100.0, le=100.0, description="target point, world frame [m]")
    y: float = Field(0.0, ge=-100.0, le=100.0)
    heading: float = Field(0.0, ge=-2 * math.pi, le=2 * math.pi, description="world frame [rad]")
    receiver: int = Field(0, ge=0, le=99, description="for a pass")
    kick: float = Field(5.0, ge=0.0, le=30.0, description="kick speed [m/s]")
    dribble: bool = False
    avoid: bool = False


class PlaceBall(_Msg):
    type: Literal["place_ball"]
    x: float = Field(ge=-100.0, le=100.0)
    y: float = Field(ge=-100.0, le=100.0)


class SendOff(_Msg):
    """Send a robot off (``off``: true) or bring it back. With a referee, ``seconds`` limits the time off
    (default: until brought back)."""

    type: Literal["send_off"]
    robot: str = Field(min_length=3, max_length=64, description="TEAM/ID, e.g. cyan/3")
    off: bool = True
    seconds: float | None = Field(None, gt=0.0, le=86400.0)


class Pause(_Msg):
    """Halt the game (with a referee: its pause, the clock stands still; without: STOP to every team)."""

    type: Literal["pause"]


class Resume(_Msg):
    """Carry on where the referee's pause halted the game (a run with a referee)."""

    type: Literal["resume"]


class Card(_Msg):
    type: Literal["card"]
    robot: str = Field(min_length=3, max_length=64, description="TEAM/ID")
    card: Literal["yellow", "red"]


class AwardGoal(_Msg):
    """A goal the operator awards (a correction the referee logs as such)."""

    type: Literal["award_goal"]
    team: str = Field(min_length=1, max_length=64)


class AutoReferee(_Msg):
    type: Literal["auto_referee"]
    on: bool


class Timeline(_Msg):
    """A page's own timeline (the replay page, the 3D view): play, pause, seek (simulated seconds), speed, and
    ``live``: back to the moment the live pages show."""

    type: Literal["timeline"]
    action: Literal["play", "pause", "seek", "speed", "live"]
    value: float = Field(0.0, ge=-1e9, le=1e9)


ClientMessage = Annotated[
    Command | Limits | Test | PlaceBall | SendOff | Pause | Resume | Card | AwardGoal | AutoReferee | Timeline,
    Field(discriminator="type"),
]
_adapter = TypeAdapter(ClientMessage)

#: what each page may send
ALLOWED = {
    "coach": {"command", "limits", "test"},
    "referee": {"command", "limits", "place_ball", "send_off", "pause", "resume", "card", "award_goal", "auto_referee"},
    "replay": {"timeline"},
    "view3d": {"timeline"},
}


def parse(text: str | bytes, role: str) -> ClientMessage:
    """The validated message in ``text`` sent by a page of ``role``; ProtocolError otherwise."""
    if len(text) > MAX_MESSAGE_BYTES:
        raise ProtocolError(f"message too long ({len(text)} bytes, at most {MAX_MESSAGE_BYTES})")
    try:
        data = json.loads(text)
    except (ValueError, UnicodeDecodeError) as exc:
        raise ProtocolError(f"not JSON: {exc}") from None
    if not isinstance(data, dict):
        raise ProtocolError("a message is a JSON object with a 'type'")
    kind = data.get("type")
    if (
        isinstance(kind, str)
        and kind in ALLOWED.get("coach", set()) | ALLOWED["referee"] | ALLOWED["replay"]
        and kind not in ALLOWED.get(role, set())
    ):
        raise ProtocolError(f"a {role} page may not send '{kind}' messages")
    try:
        return _adapter.validate_python(data)
    except ValidationError as exc:
        raise ProtocolError(_explain(exc)) from None


def authorize(message, role: str, team: str) -> None:
    """A coach page commands its own team only: refuse, before anything acts, a message naming another."""
    other = getattr(message, "team", None)
    if role == "coach" and other is not None and other != team:
        raise ProtocolError(f"this page commands {team} only, not {other}")


def _explain(exc: ValidationError) -> str:
    parts = []
    for err in exc.errors()[:3]:
        where = ".".join(str(p) for p in err["loc"] if not isinstance(p, int) or len(err["loc"]) == 1)
        parts.append(f"{where}: {err['msg']}" if where else err["msg"])
    return "; ".join(parts)


def message_id(text: str | bytes):
    """The ``id`` of a message, if it can be read (so that even a refused message gets its answer)."""
    try:
        data = json.loads(text)
    except (ValueError, UnicodeDecodeError):
        return None
    value = data.get("id") if isinstance(data, dict) else None
    return value if isinstance(value, (int, str)) and not isinstance(value, bool) else None
