"""The lockstep protocol between the server and the team/robot processes: its keys and messages.

Data flows on the documented topics (OmniVisionInfo, receive_from_coach, TeamStrategy in; VelCmd, ActionCmd,
StrategyInfo out). On top of them, a few protocol keys (relative to the run, like every topic), whose
payloads are small JSON objects so that a client in any language can speak them:

    lockstep/scene         query   -> the scene offer: scene text, overrides, seed, mode (no registration)
    lockstep/join          query   -> register a process serving some robots: {"ok": true, "step", "phase"} or an
                                     error
    lockstep/tick/<phase>  server  -> {"step", "tick"}: every input of this control tick has been sent to the
                                     processes of that phase (`phase_of`); answer it
    <team>/lockstep/ack    client  -> {"proc", "tick", "sent", "got"}: this process has sent its commands for
                                     that tick (optional, its monotonic clock: ``got`` when the tick reached
                                     it, ``sent`` when its answer was ready; on one machine they split the
                                     round trip into its parts, see `Server.stats`)
    <team>/lockstep/bye    client  -> {"proc"}: this process leaves on purpose
    lockstep/end           server  -> {"reason"}: the run is over; every client exits
    <team>/lockstep/bundle client  -> a bundle (`simatch.bus.bundle`) of what a process sends for one tick:
                                     its commands, strategy infos and events, then its ack
    lockstep/feed/<team>/<phase>  server -> a bundle of what the team's processes of that phase hear, sent
                                     when their tick opens: what `feed_covers` names since their last
                                     tick, then the tick itself
    lockstep/alive/server, <team>/lockstep/alive/<proc>   liveliness tokens (vanish when a process dies)

Zenoh keeps the order of the samples of one session on one link, so an ``ack`` arrives after the commands
it closes, and ``tick`` after the perception and game command it opens.

**Phases.** In lockstep every process is of phase 0: all ticks open at the control tick's first physics
step, as embedded. In real time the processes of a team are spread over the physics steps of a control
period by the first robot they serve (`phase_of`; both teams alike, so neither is favoured): a process's
perception is taken, and its tick opened, at its own step, as the robots of the original ran on timers of
their own. On two cores ten robot processes woken at once queue for them (the last answers after all the
others' work); spread out, two at a time, each answers in its own time.

Bundles and feeds are how simatch's own processes talk (one sample per process and tick each way, not one
per message, since each sample means a put, a wake-up and a GIL hand-off); the scene offer says the server
speaks them (``"bundles": 1``). A client that does not use them sends and subscribes topic by topic, and the
server serves it that way: both kinds may play in one run.
"""

from __future__ import annotations

import json
import os
import socket
import uuid
from collections.abc import Mapping, Sequence
from typing import Any

from ..bus import topics
from ..config.loader import LoadedScene, scene_from_text
from ..config.schema import Scene

SCENE = "lockstep/scene"
JOIN = "lockstep/join"
TICKS = "lockstep/tick/*"
END = "lockstep/end"
SERVER_ALIVE = "lockstep/alive/server"
ACKS = "*/lockstep/ack"
BYES = "*/lockstep/bye"
ALIVE = "*/lockstep/alive/*"

#: how the server paces the run
LOCKSTEP, REALTIME = "lockstep", "realtime"


class ProtocolError(ValueError):
    """A protocol message that is not what the protocol says."""


def ack_topic(team: str) -> str:
    return f"{team}/lockstep/ack"


def bye_topic(team: str) -> str:
    return f"{team}/lockstep/bye"


def alive_topic(team: str, proc: str) -> str:
    return f"{team}/lockstep/alive/{proc}"


def bundle_topic(team: str) -> str:
    return f"{team}/lockstep/bundle"


def tick_topic(phase: int) -> str:
    return f"lockstep/tick/{int(phase)}"


def feed_topic(team: str, phase: int) -> str:
    return f"lockstep/feed/{team}/{int(phase)}"


def feeds_of(team: str) -> str:
    """The key expression of every feed of ``team`` (what its credential may hear)."""
    return f"lockstep/feed/{team}/*"


def feed_covers(team: str, phase: int) -> list[str]:
    """What the feed of ``team``'s processes of ``phase`` carries: what its robot nodes and StrategyPub hear
    from the server (the same list on both sides: a client takes these topics from the feed only)."""
    return [
        topics.robot_topic(team, "*", topics.OMNI_VISION),
        topics.team_topic(team, topics.RECEIVE_FROM_COACH),
        topics.team_topic(team, topics.TEAM_STRATEGY),
        topics.GAME_STATE,
        tick_topic(phase),
    ]


def phases(spec: Scene, mode: str) -> int:
    """How many phases a control period has: one in lockstep, one per physics step in real time."""
    return round(spec.control.period / spec.physics.timestep) if mode == REALTIME else 1


def phase_of(spec: Scene, team: str, robots: Sequence[int], mode: str) -> int:
    """The phase of a process serving ``robots`` of ``team``: the physics step of the control period at
    which its perception is taken and its tick opens (see the module's text). Robot k of a team of n (in
    the scene's order) is at step k * steps // n: a whole-team process at 0, one robot per process spread
    evenly; both sides compute it from the scene, so a client knows its feed before it joins."""
    steps = phases(spec, mode)
    ids = spec.teams[team].robot_ids()
    first = min((ids.index(r) for r in robots if r in ids), default=0)
    return first * steps // max(len(ids), 1)


def team_of(topic: str) -> str:
    return topic.split("/", 1)[0]


def new_proc_id() -> str:
    """A process id unique on the network: host, pid and a random part (a restarted node gets a new one)."""
    host = "".join(c if c.isalnum() or c in "-_" else "-" for c in socket.gethostname())[:24] or "host"
    return f"{host}-{os.getpid()}-{uuid.uuid4().hex[:6]}"


def dumps(obj: Mapping[str, Any]) -> bytes:
    return json.dumps(obj, separators=(",", ":")).encode()


def ack(proc: str, tick: int, sent: float, got: float | None = None) -> bytes:
    """The ``ack`` of a tick: the bytes `dumps` would write, formatted directly (made on every tick of every
    process)."""
    more = "" if got is None else f',"got":{float(got)!r}'
    return f'{{"proc":{json.dumps(proc)},"tick":{int(tick)},"sent":{float(sent)!r}{more}}}'.encode()


def loads(payload: bytes, *required: str) -> dict:
    """A protocol message; ProtocolError if it is not a JSON object with the ``required`` keys."""
    try:
        obj = json.loads(payload)
    except (ValueError, UnicodeDecodeError) as exc:
        raise ProtocolError(f"not JSON: {exc}") from None
    if not isinstance(obj, dict):
        raise ProtocolError("not a JSON object")
    missing = [k for k in required if k not in obj]
    if missing:
        raise ProtocolError(f"missing {', '.join(missing)}")
    return obj


# --- the scene offer: what a team process needs to build its nodes exactly as the embedded run does ----------
def scene_offer(scene: LoadedScene, seed: int, run: str, mode: str) -> dict:
    return {
        "scene": {"text": scene.text, "source": scene.source, "overrides": scene.overrides},
        "seed": int(seed),
        "run": run,
        "mode": mode,
        "bundles": 1,
    }


def scene_from_offer(offer: Mapping[str, Any], local: Mapping[str, Any] | None = None) -> LoadedScene:
    """The server's scene, validated here as it was there, with ``local`` overrides on top (a team's own
    strategy and parameters)."""
    try:
        sc = offer["scene"]
        text, source, overrides = sc["text"], sc["source"], dict(sc["overrides"])
    except (KeyError, TypeError) as exc:
        raise ProtocolError(f"scene offer without {exc}") from None
    overrides.update(local or {})
    return scene_from_text(text, source, overrides)
