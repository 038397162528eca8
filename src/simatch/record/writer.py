"""The MCAP writer of recordings: message records packed on the simulation thread, chunks compressed and
written by a writer process.

Why not a library writer: ``foxglove-sdk``'s ``log`` costs about 2 us a message (some 4 ms per simulated
second of 5v5) and the ``mcap`` library's pure-Python writer builds a record object per message; a recorder
of two thousand messages per simulated second frames each message with its encoding, in one C call. The
rare records (header, schemas, channels, metadata, summary, footer) are written with the ``mcap`` library's
record classes, so the file follows the specification with no hand-made layout beyond the Message and
Chunk records.

How the work is split: the recorder's message log (`simatch.record.messagelog`) appends each message's
record (header and CDR bytes) to one buffer per chunk (no object per message); `end_chunk` hands a chunk's
records over a pipe to a **writer process** (`simatch.record.writer_process`), which compresses them with
zstd and writes the chunk. Why a process and not a thread: a writer thread needs the GIL a few times per chunk
(to take the job, after compressing, after each write), and every such hand-over stopped the simulation
thread; measured on a 5v5 match, the thread's hand-overs and compression cost the simulation thread
1.5 ms per simulated second (5 % of the match), the process costs it the copy into the pipe.

Integrity: each chunk's zstd frame carries zstd's content checksum (XXH64 of the records, checked by every
zstd decoder, so by every MCAP reader), and the chunk's own CRC32 field is 0 ("not computed", as the MCAP
specification allows). Measured on a 5v5 match: the CRC32 of a megabyte of records per simulated second
cost 0.3 ms, the zstd checksum 0.1 ms; both catch any damaged byte (tests/record/test_nothing_lost.py).

Nothing handed over is lost when the recording process is killed: the writer process writes every chunk it
was handed, then finalises the file itself (the `epitaph` metadata, the summary and the footer: it is told
every schema and channel and each chunk's message counts as they come), so a kill loses only the chunk
being filled, half a simulated second, and every MCAP reader reads the rest whole. At most two chunks are
in the writer's hands (it acknowledges each chunk once written; a third waits for that), so even a kill of
the writer process itself loses at most one simulated second more (that file is then not finalised:
`simatch recover` finalises it). The writer process ignores Ctrl-C and SIGTERM (it runs in a session of its own:
a Ctrl-C or a kill of the run's process group does not reach it) and ends when the recording process
closes the pipe or dies.

What is written (see `simatch.record.layout`): magic, header, the metadata given, chunks (schemas and
channels inside the chunk of their first message, where the caller puts the records `schema` and `channel`
return, then messages in log-time order), and on `close` the
summary (schemas, channels, statistics, metadata indexes, summary offsets) and the footer. No message or
chunk indexes: those would add 16 bytes per message outside the compression (about 2 MB per recorded
5v5 minute); readers then read the file from start to end (rosbags, the ``mcap`` readers and Foxglove do).
"""

from __future__ import annotations

import logging
import os
import pickle
import subprocess
import sys
from pathlib import Path

from mcap.data_stream import RecordBuilder
from mcap.records import Channel, Header, Metadata, Schema

from . import writer_process
from .writer_process import (
    ACK,
    CHUNK,
    COUNT,
    DECLARE,
    EPITAPH,
    FLUSH,
    FRAME,
    MAGIC,
    METADATA,
    RAW,
    SPAN,
    SUMMARY,
    write_all,
)

log = logging.getLogger(__name__)

#: chunks handed over and not yet written, at most: one being written and one in the pipe (the writer process
#: starts in some 30 ms, while a 5v5 match fills a chunk in 15: one would stop the run until it is up)
MAX_HANDED = 2
_PIPE_SIZE = 1 << 20  # a chunk (about half a megabyte) fits: handed over in one copy


class WriterError(Exception):
    """The recording could not be written (its folder, the disk, the writer process)."""


class McapWriter:
    """Writes one MCAP file: rare records and summary itself, message records in the chunks it is given."""

    def __init__(self, path: str | Path, *, profile: str, library: str, compression_level: int = 1):
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # never overwrites a file
        except OSError as exc:
            raise WriterError(f"cannot write {path}: {exc.strerror or exc}") from None
        _lock(fd)  # held by the writer process's copy of the descriptor until it ends (a reader can tell)
        self.path = Path(path)
        self.error: str | None = None
        self._schemas: list[Schema] = []
        self._channels: list[Channel] = []
        self._counts: dict[int, int] = {}
        self._message_count = 0
        self._chunk_count = 0
        self._times: tuple[int, int] | None = None
        self._records = RecordBuilder()
        self._closed = False
        self._pending = 0  # acknowledgements still to come
        to_child, self._out = os.pipe()
        self._back, from_child = os.pipe()
        _widen(self._out)
        try:  # the file itself (it needs only zstd and mcap), -P: nothing of its folder on the path
            self._proc = subprocess.Popen(
                [
                    sys.executable,
                    "-P",
                    writer_process.__file__,
                    str(to_child),
                    str(from_child),
                    str(fd),
                    str(compression_level),
                ],
                pass_fds=(to_child, from_child, fd),
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                start_new_session=True,
            )
        except OSError as exc:
            for end in (self._out, self._back):
                os.close(end)
            os.unlink(path)  # the empty file made above: nothing recorded
            raise WriterError(f"cannot start the writer process: {exc}") from None
        finally:
            for end in (to_child, from_child, fd):
                os.close(end)
        Header(profile=profile, library=library).write(self._records)
        self._send(RAW, MAGIC + self._records.end())

    # --- on the caller's thread -------------------------------------------------------------------------------
    def schema(self, name: str, encoding: str, data: bytes) -> tuple[int, bytes]:
        """Register a schema: its id and its record, for the chunk of its channels' first message."""
        record = Schema(id=len(self._schemas) + 1, name=name, encoding=encoding, data=data)
        self._schemas.append(record)
        self._send(DECLARE, pickle.dumps(record))
        record.write(self._records)
        return record.id, self._records.end()

    def channel(self, topic: str, schema_id: int, message_encoding: str) -> tuple[int, bytes]:
        """Register a channel: its id and its record, for the chunk of its first message."""
        record = Channel(
            id=len(self._channels) + 1, topic=topic, message_encoding=message_encoding, schema_id=schema_id, metadata={}
        )
        self._channels.append(record)
        self._counts[record.id] = 0
        self._send(DECLARE, pickle.dumps(record))
        record.write(self._records)
        return record.id, self._records.end()

    def end_chunk(self, data: bytes, start_ns: int, end_ns: int, counts: dict[int, int]) -> None:
        """Hand one chunk's records (messages from ``start_ns`` to ``end_ns``; ``counts`` per channel id) to the
        writer process. Waits while `MAX_HANDED` chunks are still to be written."""
        if not data:
            return
        n = 0
        for cid, k in counts.items():
            self._counts[cid] = self._counts.get(cid, 0) + k
            n += k
        self._message_count += n
        self._chunk_count += 1
        self._times = (start_ns, end_ns) if self._times is None else (self._times[0], end_ns)
        self._acknowledged(MAX_HANDED - 1)
        head = SPAN.pack(start_ns, end_ns, len(counts)) + b"".join(COUNT.pack(c, k) for c, k in counts.items())
        if self._send(CHUNK, head, data):
            self._pending += 1

    def metadata(self, name: str, data: dict[str, str]) -> None:
        """A Metadata record, written after everything handed over before it."""
        Metadata(name=name, metadata=data).write(self._records)
        self._send(METADATA, pickle.dumps((name, self._records.end())))

    def epitaph(self, name: str, data: dict[str, str]) -> None:
        """The Metadata record that ends the file should this process die before `close` (the writer process
        adds ``sim_seconds`` and ``messages``: the time and message counts of what it wrote)."""
        self._send(EPITAPH, pickle.dumps((name, dict(data))))

    def flush(self) -> None:
        """Wait until everything handed over is on disk (in the operating system's hands)."""
        if self._send(FLUSH, b""):
            self._pending += 1
        self._acknowledged(0)

    def close(self) -> None:
        """Write the summary and the footer, and close the file. Raises WriterError if writing failed."""
        if self._closed:
            return
        self._closed = True
        first, last = self._times or (0, 0)
        self._send(
            SUMMARY,
            pickle.dumps(
                {
                    "schemas": self._schemas,
                    "channels": self._channels,
                    "counts": dict(self._counts),
                    "messages": self._message_count,
                    "chunks": self._chunk_count,
                    "first": first,
                    "last": last,
                }
            ),
        )
        os.close(self._out)
        status = b""
        try:
            while chunk := os.read(self._back, 4096):
                status += chunk
        finally:
            os.close(self._back)
            self._proc.wait()
        status = status[self._pending :].decode(errors="replace").strip()  # after the acknowledgements due
        if self.error is None and status != "ok":
            self.error = status or f"the writer process ended with status {self._proc.returncode}"
        if self.error is not None:
            raise WriterError(f"writing {self.path} failed: {self.error}")

    def _send(self, kind: int, *parts: bytes) -> bool:
        """One frame to the writer process (False, and the error noted, if it is gone)."""
        if self.error is not None:
            return False
        head = FRAME.pack(kind, sum(len(p) for p in parts))
        try:
            write_all(self._out, [head, *parts])
        except OSError as exc:  # the writer process died: keep the run going, say so at the end
            self._failed(f"the writer process is gone ({exc.strerror or exc})")
            return False
        return True

    def _acknowledged(self, left: int) -> None:
        """Wait until at most ``left`` chunks or flushes are unacknowledged."""
        while self._pending > left and self.error is None:
            got = os.read(self._back, self._pending - left)
            if not got:
                self._failed("the writer process ended unexpectedly")
                return
            self._pending -= got.count(ACK)

    def _failed(self, why: str) -> None:
        self.error = why
        self._pending = 0
        log.error("recording: writing %s failed (%s); the rest of the run is not recorded", self.path, why)


def _lock(fd: int) -> None:
    """An exclusive lock on the file for as long as a descriptor of this opening of it lives: the writer
    process's, once this process closes its own (`simatch.record.reader.being_written`)."""
    try:
        import fcntl

        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except (ImportError, OSError):  # not POSIX, or a file system without locks: readers cannot tell
        pass


def _widen(fd: int) -> None:
    try:
        import fcntl

        fcntl.fcntl(fd, fcntl.F_SETPIPE_SZ, _PIPE_SIZE)
    except (ImportError, AttributeError, OSError):  # not Linux, or a lower limit: smaller copies, the same bytes
        pass
