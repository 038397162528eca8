"""The MCAP writer of recordings: message records packed on the simulation thread, chunks compressed and
written by a background thread.

Why not a library writer: ``foxglove-sdk``'s ``log`` costs about 2 us a message (some 4 ms per simulated
second of 5v5) and the ``mcap`` library's pure-Python writer builds a record object per message; a recorder
of two thousand messages per simulated second frames each message with its encoding, in one C call. The
rare records (header, schemas, channels, metadata, summary, footer) are written with the ``mcap`` library's
record classes, so the file follows the specification with no hand-made layout beyond the Message and
Chunk records.

How the work is split: the recorder's message log (`simatch.record.messagelog`) appends each message's
record (header and CDR bytes) to one buffer per chunk (no object per message); `end_chunk` hands a chunk's
records to the writer thread, which compresses them with zstd and writes the chunk. zstd and the file write
release the GIL, so on a machine with a free core that work overlaps the simulation.

Integrity: each chunk's zstd frame carries zstd's content checksum (XXH64 of the records, checked by every
zstd decoder, so by every MCAP reader), and the chunk's own CRC32 field is 0 ("not computed", as the MCAP
specification allows). Measured on a 5v5 match: the CRC32 of a megabyte of records per simulated second
cost 0.3 ms, the zstd checksum 0.1 ms; both catch any damaged byte (tests/record/test_nothing_lost.py).

At most one chunk is in the writer's hands: a process killed at any moment loses the chunk being filled and
at most the one being written.

What is written (see `simatch.record.layout`): magic, header, the metadata given, chunks (schemas and
channels inside the chunk of their first message, where the caller puts the records `schema` and `channel`
return, then messages in log-time order), and on `close` the
summary (schemas, channels, statistics, metadata indexes, summary offsets) and the footer. No message or
chunk indexes: those would add 16 bytes per message outside the compression (about 2 MB per recorded
5v5 minute); readers then read the file from start to end (rosbags, the ``mcap`` readers and Foxglove do).
"""

from __future__ import annotations

import logging
import queue
import struct
import threading
import zlib
from pathlib import Path

import zstandard
from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import (Channel, DataEnd, Footer, Header, Metadata, MetadataIndex, Schema, Statistics,
                          SummaryOffset)

log = logging.getLogger(__name__)

MAGIC = b"\x89MCAP0\r\n"
_CHUNK_HEADER = struct.Struct("<BQQQQI")
_ZSTD = struct.pack("<I", 4) + b"zstd"
_U64 = struct.Struct("<Q")


class WriterError(Exception):
    """The recording could not be written (its folder, the disk)."""


class McapWriter:
    """Writes one MCAP file: rare records and summary itself, message records in the chunks it is given."""

    def __init__(self, path: str | Path, *, profile: str, library: str, compression_level: int = 1):
        try:
            self._file = open(path, "xb", buffering=0)          # never overwrites an existing file
        except OSError as exc:
            raise WriterError(f"cannot write {path}: {exc.strerror or exc}") from None
        self.path = Path(path)
        self.error: BaseException | None = None
        self._level = compression_level
        self._pos = 0                        # bytes written (by the writer thread)
        self._schemas: list[Schema] = []
        self._channels: list[Channel] = []
        self._metadata_index: list[MetadataIndex] = []
        self._counts: dict[int, int] = {}
        self._message_count = 0
        self._chunk_count = 0
        self._times: tuple[int, int] | None = None
        self._records = RecordBuilder()
        self._closed = False
        self._jobs: queue.SimpleQueue = queue.SimpleQueue()
        self._slot = threading.Semaphore(1)                 # one chunk at most in the writer thread's hands
        self._thread = threading.Thread(target=self._work, name=f"mcap-writer {self.path.name}", daemon=True)
        self._thread.start()
        Header(profile=profile, library=library).write(self._records)
        self._jobs.put(("raw", MAGIC + self._records.end()))

    # --- on the caller's thread -------------------------------------------------------------------------------
    def schema(self, name: str, encoding: str, data: bytes) -> tuple[int, bytes]:
        """Register a schema: its id and its record, for the chunk of its channels' first message."""
        record = Schema(id=len(self._schemas) + 1, name=name, encoding=encoding, data=data)
        self._schemas.append(record)
        record.write(self._records)
        return record.id, self._records.end()

    def channel(self, topic: str, schema_id: int, message_encoding: str) -> tuple[int, bytes]:
        """Register a channel: its id and its record, for the chunk of its first message."""
        record = Channel(id=len(self._channels) + 1, topic=topic, message_encoding=message_encoding,
                         schema_id=schema_id, metadata={})
        self._channels.append(record)
        self._counts[record.id] = 0
        record.write(self._records)
        return record.id, self._records.end()

    def end_chunk(self, data: bytes, start_ns: int, end_ns: int, counts: dict[int, int]) -> None:
        """Hand one chunk's records (messages from ``start_ns`` to ``end_ns``; ``counts`` per channel id) to the
        writer thread. Waits while the previous chunk is still being written."""
        if not data:
            return
        n = 0
        for cid, k in counts.items():
            self._counts[cid] = self._counts.get(cid, 0) + k
            n += k
        self._message_count += n
        self._chunk_count += 1
        self._times = (start_ns, end_ns) if self._times is None else (self._times[0], end_ns)
        self._slot.acquire()
        self._jobs.put(("chunk", data, start_ns, end_ns))

    def metadata(self, name: str, data: dict[str, str]) -> None:
        """A Metadata record, written after everything handed over before it."""
        Metadata(name=name, metadata=data).write(self._records)
        self._jobs.put(("metadata", name, self._records.end()))

    def flush(self) -> None:
        """Wait until everything handed over is on disk (in the operating system's hands)."""
        done = threading.Event()
        self._jobs.put(("event", done))
        while not done.wait(0.5):
            if not self._thread.is_alive():
                break

    def close(self) -> None:
        """Write the summary and the footer, and close the file. Raises WriterError if writing failed."""
        if self._closed:
            return
        self._closed = True
        self._jobs.put(("summary",))
        self._jobs.put(None)
        self._thread.join()
        self._file.close()
        if self.error is not None:
            raise WriterError(f"writing {self.path} failed: {self.error}")

    # --- the writer thread ---------------------------------------------------------------------------------
    def _work(self) -> None:
        compressor = zstandard.ZstdCompressor(level=self._level, write_checksum=True)
        while True:
            job = self._jobs.get()
            if job is None:
                return
            try:
                if self.error is None:
                    self._do(job, compressor)
            except BaseException as exc:          # the disk, mostly: stop writing, keep the run going
                self.error = exc
                log.error("recording: writing %s failed (%s); the rest of the run is not recorded", self.path, exc)
            finally:
                if job[0] == "chunk":
                    self._slot.release()
                elif job[0] == "event":
                    job[1].set()

    def _write(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            n = self._file.write(view)
            view = view[n:]
        self._pos += len(data)

    def _do(self, job, compressor) -> None:
        kind = job[0]
        if kind == "raw":
            self._write(job[1])
        elif kind == "chunk":
            _, data, start_ns, end_ns = job
            packed = compressor.compress(data)
            length = 8 + 8 + 8 + 4 + len(_ZSTD) + 8 + len(packed)
            head = _CHUNK_HEADER.pack(Opcode.CHUNK, length, start_ns, end_ns, len(data), 0)   # CRC: zstd's
            self._write(head + _ZSTD + _U64.pack(len(packed)))
            self._write(packed)
        elif kind == "metadata":
            _, name, record = job
            self._metadata_index.append(MetadataIndex(offset=self._pos, length=len(record), name=name))
            self._write(record)
        elif kind == "summary":
            self._write(self._summary())

    def _summary(self) -> bytes:
        builder = RecordBuilder()
        DataEnd(data_section_crc=0).write(builder)
        data_end = builder.end()
        start = self._pos + len(data_end)
        offsets: list[SummaryOffset] = []

        def group(opcode, records) -> None:
            at = builder.count
            for record in records:
                record.write(builder)
            if builder.count > at:
                offsets.append(SummaryOffset(group_opcode=opcode, group_start=start + at,
                                             group_length=builder.count - at))

        first, last = self._times or (0, 0)
        group(Opcode.SCHEMA, self._schemas)
        group(Opcode.CHANNEL, self._channels)
        group(Opcode.STATISTICS, [Statistics(
            message_count=self._message_count, schema_count=len(self._schemas),
            channel_count=len(self._channels), attachment_count=0, metadata_count=len(self._metadata_index),
            chunk_count=self._chunk_count, message_start_time=first, message_end_time=last,
            channel_message_counts=dict(self._counts))])
        group(Opcode.METADATA_INDEX, self._metadata_index)
        offset_start = start + builder.count
        for record in offsets:
            record.write(builder)
        summary = builder.end()
        crc = zlib.crc32(summary)
        crc = zlib.crc32(struct.pack("<BQQQ", Opcode.FOOTER, 20, start, offset_start), crc)
        Footer(summary_start=start, summary_offset_start=offset_start, summary_crc=crc).write(builder)
        return data_end + summary + builder.end() + MAGIC
