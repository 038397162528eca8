"""Reading a recording, whole or damaged.

A recording cut short (the recording process was killed) has no summary at its end; a damaged one has
chunks whose checksum fails. `Recording` reads any of them sequentially with the ``mcap`` library's
record reader: it uses what is intact, skips a damaged chunk (and says which, and the simulated time it
covered), stops at the point where the file breaks off, and keeps a plain-language list of every problem in
``problems`` so that the commands can tell the user.

    rec = Recording("match.mcap")
    rec.metadata["seed"], rec.duration, rec.topics()
    for topic, t_ns, data in rec.raw(topics={"model_states"}): ...
    for topic, t_ns, msg in rec.messages(): ...          # decoded (simatch types and the 3D scene)
"""

from __future__ import annotations

import json
import os
import struct
import tempfile
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

from mcap.exceptions import McapError
from mcap.records import Channel, Chunk, Footer, Message, Metadata, Schema, Statistics
from mcap.stream_reader import StreamReader, breakup_chunk

from .. import msgs
from ..config.loader import LoadedScene, SceneError, load_scene
from ..msgs.cdr import Codec
from . import foxglove_msgs as fg
from . import layout, rosbag2


class RecordingError(Exception):
    """A file that cannot be read as a recording at all."""


@dataclass
class ChannelInfo:
    id: int
    topic: str  # bus topic (no leading slash)
    schema: str  # message type name
    encoding: str
    definition: bytes = b""  # the ros2msg schema it was recorded with


@dataclass
class ChunkInfo:
    offset: int
    start: int  # log time of its first and last message [ns]
    end: int


class Recording:
    """A recording file. ``metadata`` is its ``simatch`` record (empty for a foreign MCAP file), ``end`` its
    ``simatch_end`` record (None if the file was not finalised), ``problems`` what was found wrong."""

    def __init__(self, path: str | Path):
        self.path = rosbag2.recording_in(path)  # a rosbag2 folder (``--record DIR/``): its file
        self.metadata: dict = {}
        self.end: dict | None = None
        self.channels: dict[int, ChannelInfo] = {}
        self.chunks: list[ChunkInfo] = []
        self.finalised = False
        self.statistics: Statistics | None = None  # the summary's counts (a finalised file)
        self.problems: list[str] = []
        self._schemas: dict[int, tuple[str, bytes]] = {}
        self._checked: dict[str, bool] = {}
        self._codecs: dict[int, Codec] = {}
        self._reported: set[str] = set()
        if self.path.is_dir():
            raise RecordingError(f"{self.path}: {rosbag2.NOT_ONE}")
        if not self.path.is_file():
            raise RecordingError(f"{self.path}: no such recording")
        self._scan()

    # --- the whole-file scan (headers only, no decompression) ----------------------------------------------
    def _records(self, emit_chunks: bool = True) -> Iterator[tuple[int, object]]:
        """(byte offset, record) in file order; a problem that ends the file is noted, never raised."""
        with open(self.path, "rb") as f:
            reader = StreamReader(f, emit_chunks=emit_chunks, record_size_limit=1 << 32)
            stream = reader._stream
            it = reader.records
            while True:
                offset = stream.count
                try:
                    record = next(it)
                except StopIteration:
                    return
                except (McapError, EOFError, struct.error, ValueError, UnicodeDecodeError, MemoryError) as exc:
                    if offset == 0:
                        if being_written(self.path):
                            raise RecordingError(
                                f"{self.path} is being written right now and holds nothing yet"
                            ) from None
                        raise RecordingError(f"{self.path} is not an MCAP recording ({_describe(exc)})") from None
                    if being_written(self.path):
                        self._problem(
                            "end",
                            f"{self.path.name} is being written right now (a recorder is running): it is read up "
                            f"to where it is written so far",
                        )
                    self._problem(
                        "end",
                        f"{self.path.name} breaks off at byte {offset} of "
                        f"{self.path.stat().st_size} ({_describe(exc)}): it was not finalised "
                        f"(the recording process and its writer process were stopped); what comes before "
                        f"is read; other tools need it finalised: `simatch recover {self.path}` does that",
                    )
                    return
                yield offset, record

    def _scan(self) -> None:
        for offset, record in self._records():
            if isinstance(record, Schema):
                self._schemas[record.id] = (record.name, record.data)
            elif isinstance(record, Channel):
                self._add_channel(record)
            elif isinstance(record, Chunk):
                self.chunks.append(ChunkInfo(offset, record.message_start_time, record.message_end_time))
            elif isinstance(record, Message):
                self.chunks.append(ChunkInfo(offset, record.log_time, record.log_time))
            elif isinstance(record, Metadata):
                if record.name == layout.META_START:
                    self.metadata = dict(record.metadata)
                elif record.name == layout.META_END:
                    self.end = dict(record.metadata)
            elif isinstance(record, Statistics):
                self.statistics = record
            elif isinstance(record, Footer):
                self.finalised = True
        status = (self.end or {}).get("status", "")
        if status.startswith(("killed", "recovered")):
            self._problem(
                "killed",
                f"{self.path.name} ends at t={_seconds(self.end):.3f} s, before the run did (the recording "
                f"process was killed; {'its writer process' if status.startswith('killed') else 'simatch recover'} "
                f"finalised the file)",
            )
        if not self.finalised:
            if being_written(self.path):
                self._problem(
                    "end",
                    f"{self.path.name} is being written right now (a recorder is running): it is read up to "
                    f"where it is written so far",
                )
            self._problem(
                "end",
                f"{self.path.name} was not finalised (the recording process and its writer process stopped "
                f"before closing it): it is read up to where it is intact; other tools need it finalised: "
                f"`simatch recover {self.path}` does that",
            )
            self._scan_chunks()  # no summary: channels are known only from inside the chunks

    def _scan_chunks(self) -> None:
        for offset, record in self._records():
            if isinstance(record, Chunk):
                for item in self._open_chunk(offset, record) or ():
                    if isinstance(item, Schema):
                        self._schemas[item.id] = (item.name, item.data)
                    elif isinstance(item, Channel):
                        self._add_channel(item)

    def _open_chunk(self, offset: int, record: Chunk) -> list | None:
        """The records inside a chunk, or None if it is damaged (noted in `problems`)."""
        try:
            return breakup_chunk(record, validate_crc=True)
        except Exception as exc:  # checksum mismatch, broken compression, broken records
            self._problem(
                f"chunk{offset}",
                f"{self.path.name}: the chunk at byte {offset} "
                f"(t={record.message_start_time / layout.NS:.3f}..{record.message_end_time / layout.NS:.3f} s) "
                f"is damaged ({_describe(exc)}): its messages are skipped",
            )
            return None

    def _add_channel(self, record: Channel) -> None:
        if record.id not in self.channels:
            name, data = self._schemas.get(record.schema_id, ("", b""))
            self.channels[record.id] = ChannelInfo(
                record.id, layout.bus_topic(record.topic, name), name, record.message_encoding, data
            )

    def _problem(self, key: str, text: str) -> None:
        if key not in self._reported:
            self._reported.add(key)
            self.problems.append(text)

    # --- what is in it --------------------------------------------------------------------------------------
    @property
    def start_ns(self) -> int:
        return min((c.start for c in self.chunks), default=0)

    @property
    def end_ns(self) -> int:
        return max((c.end for c in self.chunks), default=0)

    @property
    def duration(self) -> float:
        """Simulated seconds from the first to the last recorded message."""
        return (self.end_ns - self.start_ns) / layout.NS

    @property
    def is_simatch(self) -> bool:
        return self.metadata.get("format") == layout.FORMAT

    def topics(self) -> dict[str, str]:
        """Recorded bus topic -> message type."""
        return {c.topic: c.schema for c in self.channels.values()}

    def message_counts(self) -> dict[str, int] | None:
        """Messages per recorded topic, every channel's (the 3D scene's too), from the file's summary; None for a
        file that was not finalised (it has no summary)."""
        if self.statistics is None:
            return None
        counts = self.statistics.channel_message_counts
        return {c.topic: counts.get(cid, 0) for cid, c in self.channels.items()}

    def overrides(self) -> dict:
        try:
            found = json.loads(self.metadata.get("overrides", "{}"))
        except ValueError as exc:
            raise RecordingError(f"{self.path}: the recorded overrides do not read: {exc}") from None
        if not isinstance(found, dict):
            raise RecordingError(f"{self.path}: the recorded overrides are not a table")
        return found

    def scene(self) -> LoadedScene:
        """The recorded scene: the file's text as it was, with the recorded overrides, validated again."""
        meta = self.metadata
        text = meta.get("scene_text")
        if not text:
            raise RecordingError(f"{self.path}: no scene in the recording's metadata: not a simatch recording")
        with tempfile.TemporaryDirectory(prefix="simatch-recorded-scene-") as tmp:
            path = Path(tmp) / f"{meta.get('scene_name') or 'scene'}.toml"
            path.write_text(text, encoding="utf-8")
            try:
                loaded = load_scene(str(path), self.overrides())
            except SceneError as exc:
                raise RecordingError(f"{self.path}: the recorded scene does not load: {exc}") from None
        loaded.source = meta.get("scene_source", loaded.source)
        return loaded

    # --- messages -------------------------------------------------------------------------------------------
    def raw(self, topics: Iterable[str] | None = None, start_ns: int = 0) -> Iterator[tuple[str, int, bytes]]:
        """(bus topic, log time [ns], CDR bytes) in recorded order, from ``start_ns`` on; a damaged chunk is
        skipped (and noted in `problems`)."""
        wanted = set(topics) if topics is not None else None
        ids: dict[int, str | None] = {}

        def topic_of(cid: int) -> str | None:
            found = ids.get(cid, False)
            if found is False:
                info = self.channels.get(cid)
                found = info.topic if info and (wanted is None or info.topic in wanted) else None
                ids[cid] = found
            return found

        for offset, record in self._records():
            if isinstance(record, Chunk):
                if record.message_end_time < start_ns:
                    continue
                inner = self._open_chunk(offset, record)
                if inner is None:
                    continue
                for item in inner:
                    if isinstance(item, Message):
                        if item.log_time >= start_ns:
                            topic = topic_of(item.channel_id)
                            if topic is not None:
                                yield topic, item.log_time, item.data
                    elif isinstance(item, Schema):
                        self._schemas[item.id] = (item.name, item.data)
                    elif isinstance(item, Channel):
                        self._add_channel(item)
                        ids.pop(item.id, None)
            elif isinstance(record, Message) and record.log_time >= start_ns:
                topic = topic_of(record.channel_id)
                if topic is not None:
                    yield topic, record.log_time, record.data

    def messages(self, topics: Iterable[str] | None = None, start_ns: int = 0) -> Iterator[tuple[str, int, object]]:
        """Like `raw`, decoded; messages of a type this simatch does not know are skipped (and noted)."""
        types: dict[str, str] = {}
        for topic, t, data in self.raw(topics, start_ns):
            typename = types.get(topic)
            if typename is None:
                typename = types[topic] = self.topics().get(topic, "")
            msg = self.decode(typename, data, topic)
            if msg is not None:
                yield topic, t, msg

    def typestore_for(self, typename: str):
        """The type store that decodes ``typename`` as it was recorded, or None (noted in `problems`): a type
        this simatch does not know, or whose definition differs from the one in the recording."""
        ok = self._checked.get(typename)
        if ok is None:
            store = (
                msgs.typestore
                if typename in msgs.typestore.fielddefs
                else (fg.typestore if typename in fg.typestore.fielddefs else None)
            )
            recorded = next((c.definition for c in self.channels.values() if c.schema == typename), b"")
            if store is None:
                self._problem(
                    f"type{typename}",
                    f"{self.path.name}: type {typename!r} is unknown to this simatch: its messages are skipped",
                )
            elif recorded and recorded.decode(errors="replace") != layout.schema_text(store, typename):
                self._problem(
                    f"type{typename}",
                    f"{self.path.name}: {typename} was recorded with another "
                    f"definition than this simatch's (another version?): its "
                    f"messages are skipped",
                )
                store = None
            ok = self._checked[typename] = store
        return ok

    def decode(self, typename: str, data: bytes, topic: str = ""):
        store = self.typestore_for(typename)
        if store is None:
            return None
        try:
            codec = self._codecs.get(id(store))
            if codec is None:
                codec = self._codecs[id(store)] = Codec(store)
            return codec.decode(typename, data)
        except Exception as exc:
            self._problem(
                f"decode{topic}",
                f"{self.path.name}: a message on {topic} does not decode as "
                f"{typename} ({_describe(exc)}): such messages are skipped",
            )
            return None


def being_written(path: str | Path) -> bool:
    """Whether a recorder's writer process is writing ``path`` right now (it holds a lock on it)."""
    try:
        import fcntl
    except ImportError:  # not POSIX: nobody can tell
        return False
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        return False
    except OSError:
        return True
    finally:
        os.close(fd)


def _seconds(end: dict) -> float:
    try:
        return float(end.get("sim_seconds", "0"))
    except ValueError:
        return 0.0


def _describe(exc: Exception) -> str:
    text = str(exc).strip()
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__
