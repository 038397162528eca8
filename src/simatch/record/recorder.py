"""The recorder: every message of a run's bus into one MCAP file (layout in `simatch.record.layout`).

It listens on the bus, not inside the simulator, so it records an embedded run today and a distributed
run (a server's bus) the same way. Messages are encoded to CDR on arrival (`simatch.msgs.cdr.Codec`) and handed to
the MCAP writer of ``foxglove-sdk`` (Rust: chunking, indexes and streaming zstd compression); a
chunk is closed and written out at the end of every simulated second.

What it records: every robot and team topic (``<team>/**``), the clock, model states (every physics
step), ball contacts, events, game state and operator commands, plus the two 3D-scene channels. Link
states are recorded only on request (``links=True``): a listener makes the simulator compute every wheel's
pose each physics step, which costs several times a whole physics step, and base and ball links are the
model states anyway.

Nothing a producer sends can stop the run: a message whose type is unknown or that does not encode is
counted (and its topic named in the ``simatch_end`` metadata), never raised into the bus.
"""

from __future__ import annotations

import datetime as _dt
import json
import logging
import sys
import threading
from pathlib import Path
from typing import Any, Callable, Iterable

import foxglove
import numpy as np
from foxglove.mcap import MCAPCompression, MCAPWriteOptions

from .. import msgs
from ..bus import topics
from ..scene.loader import LoadedScene
from . import foxglove_msgs as fg
from . import layout
from ..msgs.cdr import Codec
from .scene3d import FIELD_TOPIC, GAME_RATE, GAME_TOPIC, SceneBuilder

log = logging.getLogger(__name__)

#: single-level topics recorded besides every ``<team>/...`` topic (link_states only on request)
WORLD_TOPICS = (topics.CLOCK, topics.MODEL_STATES, topics.BALL_CONTACTS, topics.EVENTS, topics.GAME_STATE,
                topics.OPERATOR)
TEAM_TOPICS = "*/*/**"      # <team>/<leaf> and <team>/<id>/<leaf> (and deeper)
#: zstd level of the chunks: 1 costs some 2.5 ms less per simulated second of 5v5 than the default (3) and
#: makes files about 1 % larger (measured); higher levels gain about 2 % for twice the time
COMPRESSION_LEVEL = 1


class RecordError(Exception):
    """A recording that cannot be started (bad path, existing file)."""


def simatch_version() -> str:
    from ..cli import _version

    return _version()


class _Channel:
    __slots__ = ("log", "encode", "count", "errors")

    def __init__(self, log: Callable, encode: Callable):
        self.log, self.encode, self.count, self.errors = log, encode, 0, 0


class Recorder:
    """Records a bus into ``path`` until `close` (or the end of a ``with`` block).

    ``scene``, ``seed`` and ``dt`` describe the run (they go into the metadata, so that the run can be
    reproduced, and draw the 3D scene); ``first_step`` is the physics step the run is at when recording
    starts (0: from the beginning, which `simatch replay --verify` needs)."""

    def __init__(self, bus, path: str | Path, *, scene: LoadedScene, seed: int, dt: float, first_step: int = 0,
                 command_line: Iterable[str] | None = None, links: bool = False,
                 extra_topics: Iterable[str] = (), compression_level: int = COMPRESSION_LEVEL):
        self.path = Path(path)
        _check_path(self.path)
        self.bus = bus
        self.scene = scene
        self.dt_ns = layout.ns(dt)
        self.status = "recording"
        self._ctx = foxglove.Context()
        opts = MCAPWriteOptions(profile=layout.PROFILE, compression=MCAPCompression.Zstd, chunk_size=1 << 30,
                                compression_level=compression_level, compression_threads=0)
        try:
            self._writer = foxglove.open_mcap(str(self.path), context=self._ctx, writer_options=opts)
        except Exception as exc:      # the SDK reports I/O problems as its own error types
            raise RecordError(f"cannot write the recording {self.path}: {exc}") from None
        self._codec = Codec(msgs.typestore, memo=True)
        self._lock = threading.Lock()
        self._schemas: dict[str, Any] = {}
        self._channels: dict[str, _Channel | None] = {}
        self._skipped: dict[str, str] = {}
        self._now = first_step * self.dt_ns
        self._next_flush = (self._now // layout.NS + 1) * layout.NS
        self.first_step = first_step
        self._writer.write_metadata(layout.META_START, {
            "format": layout.FORMAT, "format_version": layout.FORMAT_VERSION, "simatch_version": simatch_version(),
            "scene_name": scene.name, "scene_source": scene.source, "scene_text": scene.text,
            "overrides": json.dumps(scene.overrides), "seed": str(int(seed)), "run": str(getattr(bus, "run", "")),
            "dt": repr(float(dt)), "control_period": repr(float(scene.spec.control.period)),
            "first_step": str(first_step), "links": json.dumps(bool(links)),
            "command_line": json.dumps(list(command_line) if command_line is not None else sys.argv),
            "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        })
        self._scene3d = SceneBuilder(scene.spec)
        self._game_every = max(1, round(1.0 / (GAME_RATE * dt)))
        self._game = self._raw_channel(GAME_TOPIC)
        self._raw_channel(FIELD_TOPIC).log(self._scene3d.field_update(), self._now, None)
        self._writer.flush()
        on = self._on_message
        self._subs = [bus.subscribe_all(topics.MODEL_STATES, self._on_model_states),
                      bus.subscribe_all(topics.CLOCK, self._on_clock)]
        wanted = [t for t in WORLD_TOPICS if t not in (topics.MODEL_STATES, topics.CLOCK)]
        wanted += [TEAM_TOPICS] + ([topics.LINK_STATES] if links else []) + list(extra_topics)
        self._subs += [bus.subscribe_all(pattern, on) for pattern in wanted]

    # --- channels --------------------------------------------------------------------------------------------
    def _schema(self, typestore, typename: str):
        found = self._schemas.get(typename)
        if found is None:
            found = foxglove.Schema(name=typename, encoding=layout.SCHEMA_ENCODING,
                                    data=layout.schema_text(typestore, typename).encode())
            self._schemas[typename] = found
        return found

    def _raw_channel(self, channel_topic: str, typestore=None, typename: str | None = None):
        typestore = typestore or fg.typestore
        typename = typename or fg.SCENE_UPDATE
        ch = foxglove.Channel(channel_topic, schema=self._schema(typestore, typename),
                              message_encoding=layout.MESSAGE_ENCODING, context=self._ctx)
        return ch.base

    def _open(self, topic: str, msg) -> _Channel | None:
        typename = getattr(msg, "__msgtype__", None)
        if typename is None or typename not in msgs.typestore.fielddefs:
            self._skip(topic, f"type {typename or type(msg).__name__} is not a simatch message type")
            return None
        ch = _Channel(self._raw_channel(layout.channel_topic(topic), msgs.typestore, typename).log,
                      self._codec.encoder(typename))
        self._channels[topic] = ch
        return ch

    def _skip(self, topic: str, why: str) -> None:
        self._channels[topic] = None
        self._skipped[topic] = why
        log.warning("recording: not recording topic %s: %s", topic, why)

    # --- bus callbacks (hot path) --------------------------------------------------------------------------
    def _on_message(self, topic: str, msg) -> None:
        with self._lock:          # uncontended in process; a transport may call from several threads
            ch = self._channels.get(topic, False)
            if ch is False:
                ch = self._open(topic, msg)
            if ch is None:
                return
            try:
                data = ch.encode(msg)
            except Exception as exc:      # a malformed message from a producer: counted, never raised
                ch.errors += 1
                if ch.errors == 1:
                    log.warning("recording: a message on %s does not encode (%s); such messages are skipped",
                                topic, exc)
                return
            ch.log(data, self._now, None)
            ch.count += 1

    def _advance(self, step: int) -> None:
        now = step * self.dt_ns
        if now != self._now:
            self._now = now
            self._codec.forget()
            if now >= self._next_flush:
                self._writer.flush()          # the second that just ended goes to disk as one chunk
                self._next_flush = (now // layout.NS + 1) * layout.NS

    def _track(self, msg) -> int | None:
        """The physics step a clock or model-states message opens: the recording's time follows it."""
        with self._lock:
            step = _step_of(msg)
            if step is not None:
                self._advance(step)
        return step

    def _on_clock(self, topic: str, msg) -> None:
        self._track(msg)
        self._on_message(topic, msg)

    def _on_model_states(self, topic: str, msg) -> None:
        step = self._track(msg)
        self._on_message(topic, msg)
        if step is not None and step % self._game_every == 0:
            try:
                pose = np.asarray(msg.pose, dtype=float).reshape(-1, 7)
                self._game.log(self._scene3d.game_update(msg.name, pose), self._now, None)
            except Exception as exc:
                log.warning("recording: no 3D scene update at step %d: %s", step, exc)

    # --- end ---------------------------------------------------------------------------------------------------
    @property
    def sim_seconds(self) -> float:
        return self._now / layout.NS

    def counts(self) -> dict[str, int]:
        return {t: ch.count for t, ch in self._channels.items() if ch is not None}

    def close(self, status: str = "complete", summary: dict | None = None) -> None:
        """Stop listening and finalise the file (summary, indexes, ``simatch_end`` metadata)."""
        if self.status != "recording":
            return
        self.status = status
        for sub in self._subs:
            sub.close()
        self._subs.clear()
        errors = {t: ch.errors for t, ch in self._channels.items() if ch is not None and ch.errors}
        end = {"status": status, "sim_seconds": repr(self.sim_seconds),
               "messages": json.dumps(self.counts(), sort_keys=True),
               "skipped_topics": json.dumps(self._skipped, sort_keys=True),
               "encode_errors": json.dumps(errors, sort_keys=True)}
        for key, value in (summary or {}).items():
            end[key] = value if isinstance(value, str) else json.dumps(value)
        with self._lock:
            try:
                self._writer.write_metadata(layout.META_END, end)
            finally:
                self._writer.close()

    def __enter__(self) -> "Recorder":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close("complete")
        elif issubclass(exc_type, KeyboardInterrupt):
            self.close("interrupted")
        else:
            self.close(f"failed: {exc_type.__name__}: {exc}")

    # --- a Simulation ----------------------------------------------------------------------------------------
    @classmethod
    def for_run(cls, sim, path: str | Path, *, command_line: Iterable[str] | None = None, links: bool = False,
                **options) -> "RunRecorder":
        """A recorder of ``sim`` (a `simatch.Simulation`); attach it before the first step so that the
        recording can be re-simulated. Closing it adds the run's state digest to the metadata."""
        return RunRecorder(sim, path, command_line=command_line, links=links, **options)


class RunRecorder(Recorder):
    def __init__(self, sim, path, **options):
        self.sim = sim
        super().__init__(sim.bus, path, scene=sim.scene, seed=sim.seed, dt=sim.dt,
                         first_step=sim.simulator.step_index, **options)

    def close(self, status: str = "complete", summary: dict | None = None) -> None:
        if self.status != "recording":
            return
        out = {"state_digest": self.sim.state_digest(), "run_sim_seconds": repr(self.sim.time),
               "events": len(self.sim.events)}
        out.update(summary or {})
        super().close(status, out)


def _step_of(msg) -> int | None:
    try:
        return int(msg.step)
    except (AttributeError, TypeError, ValueError):
        return None


def _check_path(path: Path) -> None:
    if path.exists():
        raise RecordError(f"{path} already exists: remove it or record to another file (nothing was overwritten)")
    if not path.parent.is_dir():
        raise RecordError(f"cannot record to {path}: folder {path.parent} does not exist")
