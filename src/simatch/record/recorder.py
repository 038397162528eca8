"""The recorder: every message of a run's bus into one MCAP file (layout in `simatch.record.layout`).

It listens on the bus, not inside the simulator, so it records an embedded run today and a distributed
run (a server's bus) the same way. Its message log (`simatch.record.messagelog`: in C where the extension is
built) is the bus callback of every recorded topic: it encodes each message to CDR on arrival (with the memo
of `simatch.msgs.cdr.Codec`: what teammates share and what a team's TeamStrategy repeats is encoded once) and
appends its record to the current chunk; every half simulated second the chunk goes to the writer process
(`simatch.record.writer`), which compresses and writes it while the simulation goes on; the log writes the
chunk's records straight into memory shared with that process (`McapWriter.buffer`). The 3D scene's game
updates are written by the log too (its pose template), from the model states it logs.

The hot path is one Python-to-C call per message, so that recording adds no Python frame or attribute access
per message to the run. Bus deliveries come from the thread that runs the bus (the in-process
bus calls synchronously; the Zenoh bus delivers from its owner's thread), so the hot path takes no lock.

What it records: every robot and team topic (``<team>/**``), the clock, model states (every physics step), ball
contacts, events, game state and operator commands, plus the two 3D-scene channels (the field again when the teams
change ends) and the simulated time as ROS 2's ``/clock`` (`layout.ros_clock`). Given a folder (`rosbag2`), the
recording is a rosbag2 folder: the MCAP file and the ``metadata.yaml`` that ``ros2 bag`` writes beside it. Link
states are recorded only on request (``links=True``): a listener makes the simulator compute every wheel's pose
each physics step, far more work than the physics step itself, and base and ball links are the model states
anyway.

Nothing a producer sends can stop the run: a message whose type is unknown or that does not encode is
counted (and its topic named in the ``simatch_end`` metadata), never raised into the bus.
"""

from __future__ import annotations

import datetime as _dt
import json
import logging
import sys
from collections.abc import Iterable
from pathlib import Path

from .. import msgs, version
from ..bus import topics
from ..config.loader import LoadedScene
from ..msgs.cdr import Codec
from . import environment, layout, rosbag2
from . import foxglove_msgs as fg
from .messagelog import CLOCK_STEP, CLOCK_TICK, fill_poses, new_log
from .scene3d import FIELD_TOPIC, GAME_RATE, GAME_TOPIC, GRID, TURN_GRID, SceneBuilder
from .writer import McapWriter, WriterError

log = logging.getLogger(__name__)

#: single-level topics recorded besides every ``<team>/...`` topic (link_states only on request)
WORLD_TOPICS = (
    topics.CLOCK,
    topics.MODEL_STATES,
    topics.STATE_FINGERPRINT,
    topics.COMPONENT_FINGERPRINTS,
    topics.BALL_CONTACTS,
    topics.EVENTS,
    topics.GAME_STATE,
    topics.OPERATOR,
    topics.WORLD_INPUTS,
)
TEAM_TOPICS = "*/*/**"  # <team>/<leaf> and <team>/<id>/<leaf> (and deeper)
#: topics whose messages carry the physics step and so set the log time (the clock also marks a control tick)
CLOCKS = {topics.MODEL_STATES: CLOCK_STEP, topics.CLOCK: CLOCK_STEP | CLOCK_TICK}
#: zstd level of the chunks: the smallest files for the writer process's time (docs/recording.md "Cost")
COMPRESSION_LEVEL = 3


class RecordError(Exception):
    """A recording that cannot be started (bad path, existing file) or written."""


def _run_metadata(
    bus, scene: LoadedScene, seed: int, dt: float, first_step: int, command_line, *, links: bool, world_inputs: bool
) -> dict[str, str]:
    """The metadata that describes the run at the start of a recording (what reproducing it needs)."""
    return {
        "format": layout.FORMAT,
        "format_version": layout.FORMAT_VERSION,
        "simatch_version": version(),
        "scene_name": scene.name,
        "scene_source": scene.source,
        "scene_text": scene.text,
        "overrides": json.dumps(scene.overrides),
        "seed": str(int(seed)),
        "run": str(getattr(bus, "run", "")),
        "dt": repr(float(dt)),
        "control_period": repr(float(scene.spec.control.period)),
        "first_step": str(first_step),
        "links": json.dumps(bool(links)),
        "world_inputs": "1" if world_inputs and first_step == 0 else "0",
        "fingerprint": _fingerprint_kind(),
        "command_line": json.dumps(list(command_line) if command_line is not None else sys.argv),
        "created": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "environment": json.dumps(environment.describe()),
    }


class _Channel:
    __slots__ = ("id", "typename", "errors")

    def __init__(self, cid: int, typename: str):
        self.id, self.typename, self.errors = cid, typename, 0


class Recorder:
    """Records a bus into ``path`` until `close` (or the end of a ``with`` block).

    ``scene``, ``seed`` and ``dt`` describe the run (they go into the metadata, so that the run can be
    reproduced, and draw the 3D scene); ``first_step`` is the physics step the run is at when recording
    starts (0: from the beginning, which `simatch replay --verify` needs).
    ``world_inputs``: the bus carries every input of the world from the start (a `Simulation`'s does: see
    `simatch.sim.inputs`), so the run can be re-simulated from them (noted in the metadata)."""

    def __init__(
        self,
        bus,
        path: str | Path,
        *,
        scene: LoadedScene,
        seed: int,
        dt: float,
        first_step: int = 0,
        command_line: Iterable[str] | None = None,
        links: bool = False,
        extra_topics: Iterable[str] = (),
        compression_level: int = COMPRESSION_LEVEL,
        world_inputs: bool = False,
        rosbag2_folder: bool = False,
    ):
        self.path = Path(path)
        _check_path(self.path)
        #: write the rosbag2 ``metadata.yaml`` beside the file when it is finalised (`rosbag2`)
        self.rosbag2_folder = rosbag2_folder
        self.bus = bus
        self.scene = scene
        self.dt_ns = layout.ns(dt)
        self.status = "recording"
        try:
            self._writer = McapWriter(
                self.path, profile=layout.PROFILE, library=f"simatch {version()}", compression_level=compression_level
            )
        except WriterError as exc:
            raise RecordError(f"cannot write the recording: {exc}") from None
        self._log = new_log(self._fallback)
        self._log.into(self._writer.buffer())  # the chunk's records straight into memory shared with the writer
        self._codec = Codec(msgs.typestore)  # for what the log does not take as it is
        self._schemas: dict[str, int] = {}
        self._channel_info: dict[int, tuple[str, str, object]] = {}  # channel id -> (channel, type, store)
        self._channels: dict[str, _Channel | None] = {}
        self._skipped: dict[str, str] = {}
        self._log.now = first_step * self.dt_ns
        self._log.timing(self.dt_ns, layout.CHUNK_NS, self._end_chunk)
        self._chunk_end = self._log.now  # log time of the last message handed over
        self.first_step = first_step
        self._writer.metadata(
            layout.META_START,
            _run_metadata(bus, scene, seed, dt, first_step, command_line, links=links, world_inputs=world_inputs),
        )
        self._writer.epitaph(
            layout.META_END,
            {
                "status": "killed: the recording process ended without closing the recording (the writer process "
                "finalised it)"
            },
        )
        self._scene3d = SceneBuilder(scene.spec)
        self._game_every = max(1, round(1.0 / (GAME_RATE * dt)))
        self._game = self._raw_channel(GAME_TOPIC, fg.typestore, fg.SCENE_UPDATE)
        self._field = self._raw_channel(FIELD_TOPIC, fg.typestore, fg.SCENE_UPDATE)
        self._log.record(self._field, self._scene3d.field_update())
        self._attacks: tuple = ()  # the teams' ends the field was last drawn with (they change at half time)
        # the 3D scene's game updates: the log writes the poses of the model states into the update's template
        self._log.poses(topics.MODEL_STATES, self._game, self._game_every, self._scene_update)
        wanted = list(WORLD_TOPICS) + [TEAM_TOPICS] + ([topics.LINK_STATES] if links else []) + list(extra_topics)
        self._subs = [bus.subscribe_all(pattern, self._log) for pattern in wanted]
        # ROS 2's clock, written by the log after each clock message (at the time of that message's step)
        self._log.ros_clock(topics.CLOCK, self._raw_channel(layout.ROS_CLOCK, msgs.typestore, layout.ROS_CLOCK_TYPE))
        self._subs.append(bus.subscribe(topics.GAME_STATE, msgs.GameState, self._on_game))

    # --- channels --------------------------------------------------------------------------------------------
    def _raw_channel(self, channel_topic: str, typestore, typename: str) -> int:
        """A new channel (and its schema if new); their records go into the current chunk."""
        sid = self._schemas.get(typename)
        if sid is None:
            sid, record = self._writer.schema(
                typename, layout.SCHEMA_ENCODING, layout.schema_text(typestore, typename).encode()
            )
            self._schemas[typename] = sid
            self._log.append(record)
        cid, record = self._writer.channel(channel_topic, sid, layout.MESSAGE_ENCODING)
        self._log.append(record)
        self._channel_info[cid] = (channel_topic, typename, typestore)
        return cid

    def _open(self, topic: str, msg) -> _Channel | None:
        typename = getattr(msg, "__msgtype__", None)
        if typename is None or typename not in msgs.typestore.fielddefs:
            self._skip(topic, f"type {typename or type(msg).__name__} is not a simatch message type")
            return None
        ch = self._channels[topic] = _Channel(
            self._raw_channel(layout.channel_topic(topic), msgs.typestore, typename), typename
        )
        self._log.add(topic, ch.id, typename, CLOCKS.get(topic, 0))
        return ch

    def _skip(self, topic: str, why: str) -> None:
        self._channels[topic] = None
        self._skipped[topic] = why
        log.warning("recording: not recording topic %s: %s", topic, why)

    def _fallback(self, topic: str, msg) -> None:
        """What the message log does not take: the first message of a topic (the channel is opened and the
        message given to the log again), or a message its encoder does not take as it is (a list where an array
        is expected, a malformed message: the pure-Python encoder converts it or says what is wrong)."""
        ch = self._channels.get(topic, False)
        if ch is False:
            if self._open(topic, msg) is not None:
                self._log(topic, msg)
            return
        if ch is None:
            return
        try:
            data = self._codec.encode(msg, ch.typename)
        except Exception as exc:  # a malformed message from a producer: counted, never raised
            ch.errors += 1
            if ch.errors == 1:
                log.warning("recording: a message on %s does not encode (%s); such messages are skipped", topic, exc)
            return
        self._log.record(ch.id, data)

    # --- chunks and the 3D scene ----------------------------------------------------------------------------
    def _end_chunk(self) -> None:
        """What was recorded since the last chunk goes to the writer process as one chunk (the message log calls
        this when the time moves into a new chunk)."""
        data, counts, first, last = self._log.take()
        if data:
            if first < 0:  # only schema and channel records
                first = last = self._chunk_end
            self._writer.end_chunk(data, first, last, counts)
            self._chunk_end = last
        self._log.into(self._writer.buffer())
        self._log.forget()

    def _scene_update(self, msg) -> None:
        """The game update of model states that the log's pose template does not take as they are: the first
        ones (the template is made for their models), other models, poses in another form."""
        try:
            names = list(msg.name)
            template, slots = self._scene3d.template(names)
            self._log.pose_template(names, template, slots, GRID, TURN_GRID)
            self._log.record(self._game, fill_poses(template, slots, msg.pose, GRID, TURN_GRID))
        except Exception as exc:
            log.warning("recording: no 3D scene update at step %s: %s", getattr(msg, "step", "?"), exc)

    def _on_game(self, msg) -> None:
        """The field again when the teams change ends (its goals take the colours of their new defenders)."""
        attacks = tuple(zip(msg.teams, msg.attacks))
        if not attacks or attacks == self._attacks:
            return
        first = not self._attacks
        self._attacks = attacks
        signs = {team: -1 if side == "-x" else 1 for team, side in attacks}
        if first and all(self.scene.spec.team_sign(t) == s for t, s in signs.items() if t in self.scene.spec.teams):
            return  # as drawn at the start
        try:
            self._log.record(self._field, self._scene3d.field_update(signs))
        except Exception as exc:  # never raised into the bus
            log.warning("recording: no 3D field update for the change of ends: %s", exc)

    # --- end ---------------------------------------------------------------------------------------------------
    @property
    def sim_seconds(self) -> float:
        return self._log.now / layout.NS

    def channel_counts(self) -> list[tuple[str, str, str, int]]:
        """(channel, type, RIHS01 hash, messages) of every channel, in the chunks handed to the writer."""
        totals = self._writer.counts()
        return [
            (topic, typename, store.hash_rihs01(typename), totals.get(cid, 0))
            for cid, (topic, typename, store) in sorted(self._channel_info.items())
        ]

    def counts(self) -> dict[str, int]:
        """Messages recorded per bus topic, in the chunks handed to the writer (all of them once closed)."""
        totals = self._writer.counts()
        return {t: totals.get(ch.id, 0) for t, ch in self._channels.items() if ch is not None}

    def close(self, status: str = "complete", summary: dict | None = None) -> None:
        """Stop listening and finalise the file (summary, indexes, ``simatch_end`` metadata)."""
        if self.status != "recording":
            return
        self.status = status
        for sub in self._subs:
            sub.close()
        self._subs.clear()
        try:
            self._end_chunk()
            self._log.into(None)
            errors = {t: ch.errors for t, ch in self._channels.items() if ch is not None and ch.errors}
            end = {
                "status": status,
                "sim_seconds": repr(self.sim_seconds),
                "messages": json.dumps(self.counts(), sort_keys=True),
                "skipped_topics": json.dumps(self._skipped, sort_keys=True),
                "encode_errors": json.dumps(errors, sort_keys=True),
            }
            for key, value in (summary or {}).items():
                end[key] = value if isinstance(value, str) else json.dumps(value)
            self._writer.metadata(layout.META_END, end)
        finally:
            try:
                self._writer.close()
            except WriterError as exc:
                raise RecordError(str(exc)) from None
        if self.rosbag2_folder:
            first = self.first_step * self.dt_ns
            rosbag2.write_metadata(self.path.parent, self.path.name, self.channel_counts(), first, self._log.now)

    def __enter__(self) -> Recorder:
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
    def for_run(
        cls, sim, path: str | Path, *, command_line: Iterable[str] | None = None, links: bool = False, **options
    ) -> RunRecorder:
        """A recorder of ``sim`` (a `simatch.Simulation`); attach it before the first step so that the
        recording can be re-simulated. Closing it adds the run's state digest to the metadata."""
        return RunRecorder(sim, path, command_line=command_line, links=links, **options)


class RunRecorder(Recorder):
    def __init__(self, sim, path, **options):
        self.sim = sim
        super().__init__(
            sim.bus,
            path,
            scene=sim.scene,
            seed=sim.seed,
            dt=sim.dt,
            first_step=sim.simulator.step_index,
            world_inputs=sim.simulator.inputs is not None,
            **options,
        )

    def close(self, status: str = "complete", summary: dict | None = None) -> None:
        if self.status != "recording":
            return
        out = {
            "state_digest": self.sim.state_digest(),
            "run_sim_seconds": repr(self.sim.time),
            "events": len(self.sim.events),
        }
        out.update(summary or {})
        super().close(status, out)


def _fingerprint_kind() -> str:
    """How the simulator of this simatch takes the StateFingerprint messages recorded (`simatch replay --verify`
    takes them the same way; a recording without this entry took SHA-256's)."""
    from ..sim.simulator import FINGERPRINT  # (the simulator's module: loaded by every run that records)

    return FINGERPRINT


def _check_path(path: Path) -> None:
    if path.exists():
        raise RecordError(f"{path} already exists: remove it or record to another file (nothing was overwritten)")
    if not path.parent.is_dir():
        raise RecordError(f"cannot record to {path}: folder {path.parent} does not exist")
