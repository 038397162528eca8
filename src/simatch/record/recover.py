"""Recovery (``simatch recover FILE [-o OUT]``): a finalised, indexed MCAP file of everything intact in a
recording that was never finalised, or is damaged.

A recording's writer process finalises the file itself when the recording process dies (see
`simatch.record.writer_process`); a file is left unfinalised only when the writer process died too (killed
with its process group, the machine lost power) or the disk filled up. simatch's own commands read such a
file up to where it is intact (`simatch.record.reader`), but other tools need its summary: the plain
``mcap`` reader fails on it (``RecordLengthLimitExceeded`` at the cut).

Recovery reads the file from its start, keeps every record that is intact — the header, the metadata, the
schemas and channels (wherever they are, inside chunks too), every chunk whose zstd checksum holds — and
writes a new file: the schemas and channels first, then each intact chunk as it was (its compressed bytes
unchanged) followed by its message indexes, the metadata, and a summary with chunk indexes and statistics:
the file is **indexed** as the ``mcap`` tools write it, so readers can seek in it. A chunk whose messages
name a channel that was lost (its definition was in a damaged chunk) is written again without those
messages. If the file had no ``simatch_end`` metadata, one says how it ended (``status: recovered ...``).

Without ``-o`` the file is replaced, atomically (written next to it, then renamed), and only if it needs
it; a file whose writer process is still at work (it holds a lock on it) is never touched.
"""

from __future__ import annotations

import json
import os
import struct
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from mcap.data_stream import RecordBuilder
from mcap.exceptions import McapError
from mcap.records import Channel, Chunk, ChunkIndex, Footer, Header, Message, MessageIndex, Metadata, Schema
from mcap.stream_reader import StreamReader, get_chunk_data_stream

from . import layout, rosbag2
from .reader import being_written
from .writer_process import MAGIC, summary_section

_OPCODE_MESSAGE = 0x05
_RECORD = struct.Struct("<BQ")
_MESSAGE_HEAD = struct.Struct("<HIQ")  # channel id, sequence, log time


class RecoverError(Exception):
    """A file that cannot be recovered (not an MCAP file, being written, the output exists)."""


@dataclass
class Recovered:
    source: str
    output: str
    chunks: int = 0
    messages: int = 0
    channels: int = 0
    start: float = 0.0  # simulated time of the first and last message kept [s]
    end: float = 0.0
    skipped: list[str] = field(default_factory=list)  # what was damaged and left out
    was_finalised: bool = False
    written: bool = True  # False: the file needed nothing (finalised and intact) and was left as it was
    metadata: str | None = None  # the rosbag2 folder's metadata.yaml written (a recording in a folder)

    def describe(self) -> str:
        tail = [f"wrote {self.metadata}"] if self.metadata else []
        if not self.written:
            return "\n".join([f"{self.source} is finalised and intact: nothing to recover", *tail])
        head = (
            f"recovered {self.source} -> {self.output}: {self.messages} messages on {self.channels} channels in "
            f"{self.chunks} chunks (t={self.start:.3f}..{self.end:.3f} s), finalised and indexed"
        )
        return "\n".join([head] + [f"left out: {s}" for s in self.skipped] + tail)

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def recover(
    path: str | Path, output: str | Path | None = None, progress: Callable[[float], None] | None = None
) -> Recovered:
    """Write a finalised, indexed copy of what is intact in ``path`` to ``output`` (None: replace ``path``
    if it needs it). ``progress(fraction)`` hears how far the reading got. ``path`` may be a rosbag2 folder
    (``simatch run --record DIR/``): its file is recovered in place and its ``metadata.yaml`` written again
    (missing when the run was killed before it could write it)."""
    folder = Path(path).is_dir()
    src = rosbag2.recording_in(path)
    if folder and src.is_dir():
        raise RecoverError(f"{src}: {rosbag2.NOT_ONE}")
    if not src.is_file():
        raise RecoverError(f"{src}: no such file")
    if being_written(src):
        raise RecoverError(
            f"{src} is being written by a running recorder (its writer process holds it): it will be finalised "
            f"when the recording ends"
        )
    in_place = output is None
    dst = src.with_name(src.name + ".recovering") if in_place else Path(output)
    if not in_place and dst.exists():
        raise RecoverError(f"{dst} already exists: remove it or choose another -o (nothing was overwritten)")
    if not in_place and dst.resolve() == src.resolve():
        raise RecoverError("-o names the file being recovered: leave -o out to replace it")
    scan = _Scan(src, progress)
    report = Recovered(str(src), str(src if in_place else dst), skipped=scan.skipped)
    report.was_finalised = scan.finalised
    if in_place and scan.finalised and not scan.skipped:
        report.written = False
    else:
        try:
            _write(scan, dst, report)
            if in_place:
                os.replace(dst, src)
        except BaseException:
            dst.unlink(missing_ok=True)
            raise
    if folder and in_place:
        try:
            report.metadata = str(rosbag2.complete(src.parent))
        except rosbag2.Rosbag2Error as exc:
            raise RecoverError(str(exc)) from None
    return report


class _Scan:
    """Everything intact in a file, read once from its start."""

    def __init__(self, path: Path, progress):
        self.path = path
        self.header: Header | None = None
        self.schemas: dict[int, Schema] = {}
        self.channels: dict[int, Channel] = {}
        self.metadata: list[Metadata] = []
        self.chunks: list[tuple[Chunk, bytes]] = []  # (record, uncompressed records)
        self.loose: list[Message] = []  # messages outside chunks (simatch writes none; other writers may)
        self.skipped: list[str] = []
        self.finalised = False
        size = max(1, path.stat().st_size)
        with open(path, "rb") as f:
            reader = StreamReader(f, emit_chunks=True, record_size_limit=1 << 32)
            stream, it = reader._stream, reader.records
            n = 0
            while True:
                offset = stream.count
                try:
                    record = next(it)
                except StopIteration:
                    break
                except (McapError, EOFError, struct.error, ValueError, UnicodeDecodeError, MemoryError) as exc:
                    if offset == 0:
                        raise RecoverError(f"{path} is not an MCAP file ({type(exc).__name__}: {exc})") from None
                    self.skipped.append(f"everything from byte {offset} of {size} on (the file breaks off there)")
                    break
                self._take(offset, record)
                n += 1
                if progress is not None and n % 64 == 0:
                    progress(offset / size)
        if self.header is None:
            raise RecoverError(f"{path} is not an MCAP file (no header)")

    def _take(self, offset: int, record) -> None:
        if isinstance(record, Header):
            self.header = record
        elif isinstance(record, Schema):
            self.schemas.setdefault(record.id, record)
        elif isinstance(record, Channel):
            self.channels.setdefault(record.id, record)
        elif isinstance(record, Metadata):
            self.metadata.append(record)
        elif isinstance(record, Message):
            self.loose.append(record)
        elif isinstance(record, Footer):
            self.finalised = True
        elif isinstance(record, Chunk):
            try:
                stream, _ = get_chunk_data_stream(record, validate_crc=True)
                data = bytes(stream.read(record.uncompressed_size))
                if len(data) != record.uncompressed_size:
                    raise ValueError("shorter than it says")
                for item in _inner(data):  # schemas and channels defined inside (checked: records whole)
                    if isinstance(item, Schema):
                        self.schemas.setdefault(item.id, item)
                    elif isinstance(item, Channel):
                        self.channels.setdefault(item.id, item)
            except Exception as exc:
                self.skipped.append(
                    f"the chunk at byte {offset} (t={record.message_start_time / layout.NS:.3f}.."
                    f"{record.message_end_time / layout.NS:.3f} s) is damaged ({type(exc).__name__}: {exc})"
                )
                return
            self.chunks.append((record, data))


def _inner(data: bytes):
    """The records inside a chunk's uncompressed data."""
    from mcap.stream_reader import breakup_chunk

    return breakup_chunk(
        Chunk(
            compression="",
            data=data,
            message_start_time=0,
            message_end_time=0,
            uncompressed_crc=0,
            uncompressed_size=len(data),
        ),
        validate_crc=False,
    )


def _messages(data: bytes) -> list[tuple[int, int, int]]:
    """(channel id, log time, offset) of every message record in a chunk's uncompressed data."""
    out = []
    at, end = 0, len(data)
    while at + _RECORD.size <= end:
        opcode, length = _RECORD.unpack_from(data, at)
        if opcode == _OPCODE_MESSAGE:
            cid, _, log_time = _MESSAGE_HEAD.unpack_from(data, at + _RECORD.size)
            out.append((cid, log_time, at))
        at += _RECORD.size + length
    return out


class _Out:
    """The recovered file as it is written: where the next record starts."""

    def __init__(self, f):
        self.f, self.pos = f, 0

    def put(self, data: bytes) -> None:
        self.f.write(data)
        self.pos += len(data)


def _drop_lost(record: Chunk, data: bytes, known: set[int], b: RecordBuilder, compressor, report: Recovered):
    """The chunk and its messages (`_messages`), again without the messages of channels whose definition was lost
    (reported); None if none is left."""
    found = _messages(data)
    lost = [m for m in found if m[0] not in known]
    if not lost:
        return record, found
    ids = sorted({m[0] for m in lost})
    report.skipped.append(
        f"{len(lost)} message(s) at t={record.message_start_time / layout.NS:.3f}.."
        f"{record.message_end_time / layout.NS:.3f} s of {len(ids)} channel(s) (ids "
        f"{', '.join(map(str, ids[:5]))}{', ...' if len(ids) > 5 else ''}) whose definition was lost"
    )
    for item in _inner(data):
        if not (isinstance(item, Message) and item.channel_id not in known):
            item.write(b)
    data = b.end()
    found = _messages(data)
    if not found:
        return None
    record = Chunk(
        compression="zstd",
        data=compressor.compress(data),
        message_start_time=min(m[1] for m in found),
        message_end_time=max(m[1] for m in found),
        uncompressed_crc=0,
        uncompressed_size=len(data),
    )
    return record, found


def _put_chunk(out: _Out, b: RecordBuilder, record: Chunk, found: list, counts: dict[int, int]) -> ChunkIndex:
    """Write a chunk and its message indexes; count its messages by channel; its entry of the chunk index."""
    start = out.pos
    record.write(b)
    out.put(b.end())
    chunk_length = out.pos - start
    by_channel: dict[int, list[tuple[int, int]]] = {}
    for cid, log_time, offset in found:
        by_channel.setdefault(cid, []).append((log_time, offset))
        counts[cid] = counts.get(cid, 0) + 1
    offsets = {}
    index_start = out.pos
    for cid in sorted(by_channel):
        offsets[cid] = out.pos
        MessageIndex(channel_id=cid, records=by_channel[cid]).write(b)
        out.put(b.end())
    return ChunkIndex(
        message_start_time=record.message_start_time,
        message_end_time=record.message_end_time,
        chunk_start_offset=start,
        chunk_length=chunk_length,
        message_index_offsets=offsets,
        message_index_length=out.pos - index_start,
        compression=record.compression,
        compressed_size=len(record.data),
        uncompressed_size=record.uncompressed_size,
    )


def _end_metadata(scan: _Scan, counts: dict[int, int], last: int) -> Metadata:
    """The end metadata of a recording that was never finalised, as far as the recovered file tells."""
    topics = {c.id: layout.bus_topic(c.topic) for c in scan.channels.values()}
    return Metadata(
        name=layout.META_END,
        metadata={
            "status": "recovered: the recording was never finalised (its writer process stopped too); "
            "simatch recover kept what was intact",
            "sim_seconds": repr(last / layout.NS),
            "messages": json.dumps({topics[c]: n for c, n in sorted(counts.items()) if c in topics}),
        },
    )


def _write(scan: _Scan, dst: Path, report: Recovered) -> None:
    import zstandard

    b = RecordBuilder()
    scan.header.write(b)
    first_meta = [m for m in scan.metadata if m.name == layout.META_START]
    rest_meta = [m for m in scan.metadata if m.name != layout.META_START]
    metadata_index: list = []
    counts: dict[int, int] = {}
    chunk_indexes: list[ChunkIndex] = []
    first = last = None
    with open(dst, "xb") as f:
        out = _Out(f)
        out.put(MAGIC + b.end())
        for m in first_meta:
            m.write(b)
            record = b.end()
            metadata_index.append((out.pos, len(record), m.name))
            out.put(record)
        for s in sorted(scan.schemas.values(), key=lambda r: r.id):
            s.write(b)
        for c in sorted(scan.channels.values(), key=lambda r: r.id):
            if c.schema_id == 0 or c.schema_id in scan.schemas:
                c.write(b)
        out.put(b.end())
        known = {c.id for c in scan.channels.values() if c.schema_id == 0 or c.schema_id in scan.schemas}
        compressor = zstandard.ZstdCompressor(level=3, write_checksum=True)
        for record, data in scan.chunks:
            kept = _drop_lost(record, data, known, b, compressor, report)
            if kept is None:
                continue
            record, found = kept
            chunk_indexes.append(_put_chunk(out, b, record, found, counts))
            if found:
                first = record.message_start_time if first is None else min(first, record.message_start_time)
                last = record.message_end_time if last is None else max(last, record.message_end_time)
            report.chunks += 1
        for m in scan.loose:  # outside chunks (not simatch's own), kept as they were
            if m.channel_id in known:
                m.write(b)
                counts[m.channel_id] = counts.get(m.channel_id, 0) + 1
                first = m.log_time if first is None else min(first, m.log_time)
                last = m.log_time if last is None else max(last, m.log_time)
        out.put(b.end())
        first, last = first or 0, last or 0
        if not any(m.name == layout.META_END for m in rest_meta) and first_meta:
            rest_meta.append(_end_metadata(scan, counts, last))
        for m in rest_meta:
            m.write(b)
            record_bytes = b.end()
            metadata_index.append((out.pos, len(record_bytes), m.name))
            out.put(record_bytes)
        summary = {
            "schemas": sorted(scan.schemas.values(), key=lambda r: r.id),
            "channels": sorted((c for c in scan.channels.values() if c.id in known), key=lambda r: r.id),
            "counts": counts,
            "messages": sum(counts.values()),
            "chunks": len(chunk_indexes),
            "first": first,
            "last": last,
        }
        out.put(summary_section(out.pos, summary, metadata_index, chunk_indexes))
        f.flush()
        os.fsync(f.fileno())
    report.messages = sum(counts.values())
    report.channels = len(counts)
    report.start, report.end = first / layout.NS, last / layout.NS
