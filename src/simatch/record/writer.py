"""The MCAP writer of recordings: message records packed on the simulation thread, chunks compressed and
written by a writer process.

Why not a library writer: ``foxglove-sdk``'s ``log`` is a call per message and the ``mcap`` library's
pure-Python writer builds a record object per message; the recorder frames each message with its encoding,
in one C call (docs/recording.md compares them). The
rare records (header, schemas, channels, metadata, summary, footer) are written with the ``mcap`` library's
record classes, so the file follows the specification with no hand-made layout beyond the Message and
Chunk records.

How the work is split: the recorder's message log (`simatch.record.messagelog`) appends each message's
record (header and CDR bytes) to one buffer per chunk (no object per message); `end_chunk` hands a chunk's
records to a **writer process** (`simatch.record.writer_process`), which compresses them with zstd and
writes the chunk. Why a process and not a thread: a writer thread needs the GIL a few times per chunk
(to take the job, after compressing, after each write), and every such hand-over stops the simulation
thread.

**Shared memory.** The chunk buffers are memory shared with the writer process: one anonymous memory file
(``memfd_create``: no name in ``/dev/shm`` or anywhere, gone with the last process that maps it, however the
processes end) of `SLOTS` slots, mapped by both. `buffer` lends the message log a free slot (``log.into``),
the log writes the chunk's records straight into it, and the pipe carries only "chunk in slot i, n bytes"
and the acknowledgement that frees the slot once the chunk is written: the simulation thread neither copies
a chunk into the kernel nor waits for the writer process to read the pipe empty. A chunk that outgrows its
slot (the log then moves it to memory of its own), and every chunk where there is no ``memfd_create`` (not
Linux) or it fails, goes through the pipe.

Integrity: each chunk's zstd frame carries zstd's content checksum (XXH64 of the records, checked by every
zstd decoder, so by every MCAP reader), and the chunk's own CRC32 field is 0 ("not computed", as the MCAP
specification allows): the cheaper of the two, and either catches any damaged byte
(tests/record/test_nothing_lost.py).

Nothing handed over is lost when the recording process is killed: the writer process writes every chunk it
was handed (its mapping of the shared memory outlives the recording process), then finalises the file
itself (the `epitaph` metadata, the summary and the footer: it is told every schema and channel and each
chunk's message counts as they come), so a kill loses only the chunk being filled, half a simulated second,
and every MCAP reader reads the rest whole. At most `MAX_HANDED` (two) chunks are
in the writer's hands (it acknowledges each chunk once written; a third waits for that), so even a kill of
the writer process itself loses at most one simulated second more (three in the run's first seconds, while it
starts: `MAX_HANDED_STARTING`) (that file is then not finalised:
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

import importlib.util
import logging
import mmap
import os
import pickle
import select
import struct
import subprocess
import sys
from collections import deque
from itertools import chain
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
    SHARED,
    SLOT,
    SPAN,
    SUMMARY,
    write_all,
)

log = logging.getLogger(__name__)

#: chunks handed over and not yet written, at most, once the writer process runs: one being written and one in the
#: pipe (it writes a chunk far faster than a run fills one)
MAX_HANDED = 2
#: ... and while it starts, until it has written a chunk and caught up: the run does not wait for it to start
MAX_HANDED_STARTING = 6
#: shared chunk buffers: one being filled, the others handed over
SLOTS = MAX_HANDED_STARTING + 1
#: bytes of a slot: a chunk of the match is some 370 kB, with link states about 1 MB; only the pages written
#: take memory, and a larger chunk goes through the pipe
SLOT_SIZE = 8 << 20
_PIPE_SIZE = 1 << 20  # a chunk that goes through the pipe (about half a megabyte) fits: handed over in one copy


class WriterError(Exception):
    """The recording could not be written (its folder, the disk, the writer process)."""


class McapWriter:
    """Writes one MCAP file: rare records and summary itself, message records in the chunks it is given."""

    def __init__(
        self,
        path: str | Path,
        *,
        profile: str,
        library: str,
        compression_level: int = 1,
        shared: bool = True,
        slot_size: int | None = None,
    ):
        """``shared``: hand the chunks over in shared memory where the system has it (`SLOTS` of
        ``slot_size`` bytes, default `SLOT_SIZE`), else through the pipe."""
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # never overwrites a file
        except OSError as exc:
            raise WriterError(f"cannot write {path}: {exc.strerror or exc}") from None
        _lock(fd)  # held by the writer process's copy of the descriptor until it ends (a reader can tell)
        self.path = Path(path)
        self.error: str | None = None
        self._schemas: list[Schema] = []
        self._channels: list[Channel] = []
        self._counts: dict[int, int] = {}  # messages per channel id in the chunks handed over before ...
        self._chunk_counts: list[dict[int, int]] = []  # ... and those of each chunk handed over since
        self._message_count = 0
        self._chunk_count = 0
        self._times: tuple[int, int] | None = None
        self._records = RecordBuilder()
        self._closed = False
        self._handed: deque[int | None] = deque()  # per acknowledgement still to come: the slot it frees
        self._written = 0  # chunks and flushes acknowledged
        self._starting = True  # until the writer process has written a chunk and caught up (`MAX_HANDED_STARTING`)
        slot_size = SLOT_SIZE if slot_size is None else slot_size
        share = _shared_memory(SLOTS * slot_size) if shared else None
        self._map = share[1] if share else None
        self._slots = (
            [memoryview(self._map)[i * slot_size : (i + 1) * slot_size] for i in range(SLOTS)] if share else []
        )
        self._free = list(range(len(self._slots)))[::-1]  # slots neither handed over nor lent to the log
        self._lent: int | None = None  # the slot lent for the chunk being filled
        to_child, self._out = os.pipe()
        self._back, from_child = os.pipe()
        _widen(self._out)
        fds = (to_child, from_child, fd) + ((share[0],) if share else ())
        args = [str(to_child), str(from_child), str(fd), str(compression_level)]
        if share:
            args += [str(share[0]), str(slot_size), str(SLOTS)]
        command, env = _writer_start(args)
        try:
            self._proc = subprocess.Popen(
                command,
                pass_fds=fds,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                start_new_session=True,
                env=env,
            )
        except OSError as exc:
            for end in (self._out, self._back):
                os.close(end)
            os.unlink(path)  # the empty file made above: nothing recorded
            raise WriterError(f"cannot start the writer process: {exc}") from None
        finally:
            for end in fds:
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

    @property
    def shared(self) -> bool:
        """Chunks are handed over in shared memory (else through the pipe)."""
        return bool(self._slots)

    def buffer(self) -> memoryview | None:
        """Shared memory for the next chunk's records, to lend the message log (``log.into``): the same slot
        until a chunk in it is handed over. None where there is none (or the writer process is gone)."""
        if not self._slots or self.error is not None:
            return None
        if self._lent is None:
            self._lent = self._free.pop()  # at most MAX_HANDED_STARTING slots are handed over: one is free
        return self._slots[self._lent]

    def end_chunk(self, data, start_ns: int, end_ns: int, counts: dict[int, int]) -> None:
        """Hand one chunk's records (messages from ``start_ns`` to ``end_ns``; ``counts`` per channel id) to the
        writer process: ``data`` is a bytes-like object, or the records in the slot `buffer` lent (a memoryview
        of its first bytes, as ``log.take`` gives it). Waits while `MAX_HANDED` chunks are still to be
        written (`MAX_HANDED_STARTING` while the writer process starts)."""
        if not len(data):
            return
        self._chunk_counts.append(counts)  # (added up when asked: a chunk of the match counts some hundred channels)
        self._message_count += sum(counts.values())
        self._chunk_count += 1
        self._times = (start_ns, end_ns) if self._times is None else (self._times[0], end_ns)
        if self._starting:
            self._acknowledged(MAX_HANDED_STARTING - 1, poll=True)
            self._starting = not (self._written and len(self._handed) < MAX_HANDED)
        else:
            self._acknowledged(MAX_HANDED - 1)
        head = SPAN.pack(start_ns, end_ns, len(counts)) + _count_records(counts)
        in_slot = self._map is not None and isinstance(data, memoryview) and data.obj is self._map
        slot = self._lent if in_slot else None
        if slot is not None:  # in the lent slot: only where it is crosses the pipe
            self._lent = None
            if self._send(SHARED, SLOT.pack(slot, len(data)), head):
                self._handed.append(slot)
            else:
                self._free.append(slot)
        elif self._send(CHUNK, head, data):
            self._handed.append(None)

    def counts(self) -> dict[int, int]:
        """Messages per channel id in the chunks handed over."""
        counted = self._counts
        for counts in self._chunk_counts:
            for cid, k in counts.items():
                counted[cid] = counted.get(cid, 0) + k
        self._chunk_counts.clear()
        return dict(counted)

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
            self._handed.append(None)
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
                    "counts": self.counts(),
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
        status = status[len(self._handed) :].decode(errors="replace").strip()  # after the acknowledgements due
        self._slots.clear()  # the shared memory goes with the last view of it
        if self.error is None and status != "ok":
            self.error = status or f"the writer process ended with status {self._proc.returncode}"
        if self.error is not None:
            raise WriterError(f"writing {self.path} failed: {self.error}")

    def _send(self, kind: int, *parts: bytes) -> bool:
        """One frame to the writer process (False, and the error noted, if it is gone)."""
        if self.error is not None:
            return False
        size = sum(map(len, parts))
        head = FRAME.pack(kind, size)
        try:
            # one write: a blocking pipe takes the whole frame, waiting for the writer process to read where it
            # does not fit; what a signal may leave unwritten, `write_all` writes
            done = os.writev(self._out, (head, *parts))
            if done < FRAME.size + size:
                write_all(self._out, [b"".join((head, *parts))[done:]])
        except OSError as exc:  # the writer process died: keep the run going, say so at the end
            self._failed(f"the writer process is gone ({exc.strerror or exc})")
            return False
        return True

    def _acknowledged(self, left: int, poll: bool = False) -> None:
        """Wait until at most ``left`` chunks or flushes are unacknowledged (their slots are free then); ``poll``:
        take the acknowledgements that came meanwhile too, without waiting for more."""
        while self._handed and self.error is None:
            if len(self._handed) <= left and not (poll and _readable(self._back)):
                return
            got = os.read(self._back, len(self._handed))  # (one byte per acknowledgement; blocks only for the first)
            if not got:
                self._failed("the writer process ended unexpectedly")
                return
            for _ in range(got.count(ACK)):
                slot = self._handed.popleft()
                self._written += 1
                if slot is not None:
                    self._free.append(slot)

    def _failed(self, why: str) -> None:
        self.error = why
        self._handed.clear()
        self._free = [i for i in range(len(self._slots)) if i != self._lent]
        log.error("recording: writing %s failed (%s); the rest of the run is not recorded", self.path, why)


def _count_records(counts: dict[int, int]) -> bytes:
    """The COUNT records of ``counts`` (channel id -> messages), packed in one call (a chunk of the match counts
    some hundred channels, twice per simulated second)."""
    return struct.pack("<" + COUNT.format.lstrip("<") * len(counts), *chain.from_iterable(counts.items()))


def _readable(fd: int) -> bool:
    """Whether a read of ``fd`` would return at once (``poll``: any descriptor number, where ``select`` takes
    those below 1024 only)."""
    try:
        waiting = select.poll()
        waiting.register(fd, select.POLLIN)
        return bool(waiting.poll(0))
    except (AttributeError, OSError, ValueError):  # no poll (not POSIX): waits as once it runs
        return False


def _writer_start(args: list[str]) -> tuple[list[str], dict[str, str]]:
    """The writer process's command line and environment. It runs the file itself, not simatch's package, with
    ``-P`` (nothing of the file's folder on the path) and, where the packages it imports (`writer_process.IMPORTS`:
    zstd's binding and mcap) are found, with ``-S`` and their folders as its ``PYTHONPATH``: without ``site``,
    which in a typical environment imports what its ``.pth`` files name (an editable install's hook, coverage's
    start-up, ROS wheels' bootstrap), so that it starts while the run's first chunks wait."""
    folders: list[str] = []
    for name in writer_process.IMPORTS:
        spec = importlib.util.find_spec(name)
        where = spec.submodule_search_locations if spec is not None else None
        if not where:  # (not met: both are packages) the interpreter's own search, with site
            return [sys.executable, "-P", writer_process.__file__, *args], dict(os.environ)
        folder = os.path.dirname(next(iter(where)))
        if folder not in folders:
            folders.append(folder)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(folders)}
    return [sys.executable, "-S", "-P", writer_process.__file__, *args], env


def _lock(fd: int) -> None:
    """An exclusive lock on the file for as long as a descriptor of this opening of it lives: the writer
    process's, once this process closes its own (`simatch.record.reader.being_written`)."""
    try:
        import fcntl

        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except (ImportError, OSError):  # not POSIX, or a file system without locks: readers cannot tell
        pass


def _shared_memory(size: int) -> tuple[int, mmap.mmap] | None:
    """An anonymous memory file of ``size`` bytes and this process's mapping of it, or None where the system
    has none (the chunks then go through the pipe)."""
    try:
        fd = os.memfd_create("simatch-recording")  # close-on-exec: only the writer process is handed it
    except (AttributeError, OSError):
        return None
    try:
        os.ftruncate(fd, size)
        return fd, mmap.mmap(fd, size)
    except (OSError, ValueError):
        os.close(fd)
        return None


def _widen(fd: int) -> None:
    try:
        import fcntl

        fcntl.fcntl(fd, fcntl.F_SETPIPE_SZ, _PIPE_SIZE)
    except (ImportError, AttributeError, OSError):  # not Linux, or a lower limit: smaller copies, the same bytes
        pass
