"""The writer process of a recording (started by `simatch.record.writer.McapWriter`, which says why):
frames in over a pipe, the MCAP file out.

``python -S -P .../writer_process.py FRAMES_FD ACKS_FD FILE_FD LEVEL [SHARED_FD SLOT_SIZE SLOTS]``: reads
frames (kind, payload length, payload) from FRAMES_FD until it is closed, writes the file FILE_FD, and
answers on ACKS_FD one `ACK` per chunk written or flush done, then, once the frames end, ``ok`` or what went
wrong. With SHARED_FD (a memory file of SLOTS slots of SLOT_SIZE bytes, shared with the recording process),
a `SHARED` frame says that a chunk's records lie in one of its slots; its acknowledgement frees the slot. It is run as
a file, not as a module of simatch, and imports only the standard library, zstd and (for the summary)
mcap, and runs without ``site`` (the packages' folders on its ``PYTHONPATH``), so that it starts at once.

It keeps what the summary needs as the frames come (the schemas and channels declared to it, each chunk's
message counts), so that when the frames end without a `SUMMARY` — the recording process died, killed or
crashed — it still **finalises the file**: the `EPITAPH` metadata the recording process gave it at the
start (with the simulated time and the message counts of what was written), the summary and the footer.
Every MCAP reader then reads the file whole, and nothing needs recovering. It ends quietly when its parent
is gone (no acknowledgement can be delivered then: that is expected, not an error). While its descriptor
of the file lives, the file is locked (``flock``, taken by the recording process before it handed the
descriptor over), so that a reader can tell a recording being written from one whose writer died.

It runs as a batch process (``SCHED_BATCH``, where the system has it): the frame that hands it a chunk wakes it
without making it preempt the recording process on that processor, so that the simulation thread does not
wait while the writer compresses.
"""

from __future__ import annotations

import mmap
import os
import signal
import struct
import sys
import zlib

#: the packages besides the standard library that it imports (its starter puts them on its path: it runs
#: without ``site``)
IMPORTS = ("zstandard", "mcap")
MAGIC = b"\x89MCAP0\r\n"
FRAME = struct.Struct("<BQ")  # a frame's kind and payload length
RAW, CHUNK, METADATA, SUMMARY, FLUSH, DECLARE, EPITAPH, SHARED = 1, 2, 3, 4, 5, 6, 7, 8
SPAN = struct.Struct("<QQI")  # a chunk's payload starts with its first and last log time and its count of counts
COUNT = struct.Struct("<HI")  # then (channel id, messages) per channel, then the records
SLOT = struct.Struct("<IQ")  # a SHARED frame's payload: the slot and length of the records, then SPAN and counts
ACK = b"A"
_CHUNK_HEADER = struct.Struct("<BQQQQI")
_ZSTD = struct.pack("<I", 4) + b"zstd"
_U64 = struct.Struct("<Q")
_OPCODE_CHUNK = 0x06


def write_all(fd: int, parts) -> int:
    """Write every part to ``fd`` in order, with as few system calls as the kernel allows (no copy to join
    them); the number of bytes written."""
    views = [memoryview(p).cast("B") for p in parts if len(p)]
    total = sum(len(v) for v in views)
    while views:
        n = os.writev(fd, views)
        while views and n >= len(views[0]):
            n -= len(views[0])
            views.pop(0)
        if n:
            views[0] = views[0][n:]
    return total


class FileWriter:
    """Frames in, the file out."""

    def __init__(self, frames: int, acks: int, fd: int, level: int, shared: tuple[int, int, int] | None = None):
        """``shared``: (descriptor, slot size, slots) of the memory shared with the recording process."""
        import zstandard

        self._in = os.fdopen(frames, "rb", buffering=0)
        self._acks = acks
        self._fd = fd
        self._compressor = zstandard.ZstdCompressor(level=level, write_checksum=True)
        self._pos = 0
        self._metadata_index: list = []  # (offset, length, name)
        self.error: str | None = None
        # what the summary needs, kept as the frames come (for a file whose recording process died)
        self._schemas: list = []
        self._channels: list = []
        self._counts: dict[int, int] = {}
        self._chunks = 0
        self._span: tuple[int, int] | None = None
        self._epitaph: tuple[str, dict] | None = None
        self._finished = False  # the SUMMARY frame came
        self._parent = True  # acknowledgements can be delivered
        self._shared: memoryview | None = None
        self._slot_size = 0
        if shared is not None:
            shm, self._slot_size, slots = shared
            self._shared = memoryview(mmap.mmap(shm, self._slot_size * slots, prot=mmap.PROT_READ))
            os.close(shm)

    def run(self) -> None:
        while (head := self._read(FRAME.size)) is not None:
            kind, size = FRAME.unpack(head)
            payload = self._read(size)
            if payload is None:
                break  # the recording process died mid-frame
            if self.error is None:
                try:
                    self._do(kind, payload)
                except Exception as exc:  # the disk, mostly: write nothing more, keep acknowledging
                    self.error = f"{type(exc).__name__}: {exc}"
            if kind in (CHUNK, SHARED, FLUSH):
                self._answer(ACK)
                _summary_imports()  # while the run goes on, not when it waits for the end
        if not self._finished and self.error is None:
            try:  # the recording process is gone: what it handed over is written; finalise the file
                self._finalise()
            except Exception as exc:
                self.error = f"{type(exc).__name__}: {exc}"
        os.close(self._fd)
        self._answer(b"ok\n" if self.error is None else (self.error + "\n").encode())
        os.close(self._acks)  # the recording process reads to the end of this pipe: it ends here, not at our exit

    def _answer(self, data: bytes) -> None:
        """An acknowledgement to the recording process, if it is still there to read it."""
        if self._parent:
            try:
                os.write(self._acks, data)
            except OSError:  # its end of the pipe is closed: it died; the file is finished all the same
                self._parent = False

    def _read(self, n: int) -> bytearray | None:
        buf = bytearray(n)
        view, got = memoryview(buf), 0
        while got < n:
            k = self._in.readinto(view[got:])
            if not k:
                return None
            got += k
        return buf

    def _write(self, *parts) -> None:
        self._pos += write_all(self._fd, parts)

    def _do(self, kind: int, payload: bytearray) -> None:
        if kind == RAW:
            self._write(payload)
        elif kind == CHUNK:
            at, start_ns, end_ns = self._counted(payload, 0)
            self._chunk(memoryview(payload)[at:], start_ns, end_ns)
        elif kind == SHARED:
            slot, n = SLOT.unpack_from(payload)
            if self._shared is None or slot * self._slot_size + n > len(self._shared) or n > self._slot_size:
                raise ValueError(f"a chunk of {n} bytes in slot {slot}, outside the shared memory")
            _, start_ns, end_ns = self._counted(payload, SLOT.size)
            with self._shared[slot * self._slot_size : slot * self._slot_size + n] as data:
                self._chunk(data, start_ns, end_ns)
        elif kind == METADATA:
            import pickle

            name, record = pickle.loads(payload)
            self._metadata_index.append((self._pos, len(record), name))
            if self._epitaph is not None and name == self._epitaph[0]:
                self._epitaph = None  # the real end was written: no epitaph
            self._write(record)
        elif kind == SUMMARY:
            import pickle

            self._finished = True
            self._write(self._summary(pickle.loads(payload)))
        elif kind == DECLARE:  # a schema or channel record (mcap's record object), for the summary
            import pickle

            record = pickle.loads(payload)
            (self._channels if hasattr(record, "topic") else self._schemas).append(record)
        elif kind == EPITAPH:  # the metadata to end the file with should the recording process die
            import pickle

            self._epitaph = pickle.loads(payload)

    def _counted(self, payload, at: int) -> tuple[int, int, int]:
        """Take in a chunk's span and message counts (SPAN and COUNTs at ``at``): where they end, the span."""
        start_ns, end_ns, n = SPAN.unpack_from(payload, at)
        at += SPAN.size
        for _ in range(n):
            cid, count = COUNT.unpack_from(payload, at)
            self._counts[cid] = self._counts.get(cid, 0) + count
            at += COUNT.size
        self._chunks += 1
        self._span = (start_ns, end_ns) if self._span is None else (self._span[0], end_ns)
        return at, start_ns, end_ns

    def _chunk(self, data: memoryview, start_ns: int, end_ns: int) -> None:
        """One Chunk record of ``data``: the records of messages from ``start_ns`` to ``end_ns``."""
        packed = self._compressor.compress(data)
        length = 8 + 8 + 8 + 4 + len(_ZSTD) + 8 + len(packed)
        head = _CHUNK_HEADER.pack(_OPCODE_CHUNK, length, start_ns, end_ns, len(data), 0)  # CRC: zstd's
        self._write(head, _ZSTD, _U64.pack(len(packed)), packed)

    def _finalise(self) -> None:
        """End the file whose recording process died: its epitaph, then the summary and the footer."""
        import json
        import pickle

        from mcap.data_stream import RecordBuilder
        from mcap.records import Metadata

        first, last = self._span or (0, 0)
        if self._epitaph is not None:
            name, data = self._epitaph
            topics = {c.id: c.topic.lstrip("/") for c in self._channels}  # channels are "/" + bus topic
            data = dict(data, sim_seconds=repr(last / 1e9))
            data["messages"] = json.dumps({topics.get(c, str(c)): n for c, n in sorted(self._counts.items())})
            builder = RecordBuilder()
            Metadata(name=name, metadata=data).write(builder)
            self._do(METADATA, bytearray(pickle.dumps((name, builder.end()))))
        summary = {
            "schemas": self._schemas,
            "channels": self._channels,
            "counts": dict(self._counts),
            "messages": sum(self._counts.values()),
            "chunks": self._chunks,
            "first": first,
            "last": last,
        }
        self._write(self._summary(summary))

    def _summary(self, s: dict) -> bytes:
        return summary_section(self._pos, s, self._metadata_index)


def summary_section(pos: int, s: dict, metadata_index: list, chunk_indexes: list = ()) -> bytes:
    """The end of an MCAP file whose data section ends at byte ``pos``: DataEnd, the summary (schemas,
    channels, statistics from ``s``, the chunk indexes given, the metadata index of ``metadata_index``:
    (offset, length, name)), the summary offsets, the footer and the closing magic."""
    from mcap.data_stream import RecordBuilder
    from mcap.opcode import Opcode
    from mcap.records import DataEnd, Footer, MetadataIndex, Statistics, SummaryOffset

    builder = RecordBuilder()
    DataEnd(data_section_crc=0).write(builder)
    data_end = builder.end()
    start = pos + len(data_end)
    offsets: list = []

    def group(opcode, records) -> None:
        at = builder.count
        for record in records:
            record.write(builder)
        if builder.count > at:
            offsets.append(SummaryOffset(group_opcode=opcode, group_start=start + at, group_length=builder.count - at))

    index = [MetadataIndex(offset=o, length=n, name=name) for o, n, name in metadata_index]
    group(Opcode.SCHEMA, s["schemas"])
    group(Opcode.CHANNEL, s["channels"])
    group(Opcode.CHUNK_INDEX, chunk_indexes)
    group(
        Opcode.STATISTICS,
        [
            Statistics(
                message_count=s["messages"],
                schema_count=len(s["schemas"]),
                channel_count=len(s["channels"]),
                attachment_count=0,
                metadata_count=len(index),
                chunk_count=s["chunks"],
                message_start_time=s["first"],
                message_end_time=s["last"],
                channel_message_counts=s["counts"],
            )
        ],
    )
    group(Opcode.METADATA_INDEX, index)
    offset_start = start + builder.count
    for record in offsets:
        record.write(builder)
    summary = builder.end()
    crc = zlib.crc32(summary)
    crc = zlib.crc32(struct.pack("<BQQQ", Opcode.FOOTER, 20, start, offset_start), crc)
    Footer(summary_start=start, summary_offset_start=offset_start, summary_crc=crc).write(builder)
    return data_end + summary + builder.end() + MAGIC


def _summary_imports() -> None:
    import pickle  # noqa: F401

    import mcap.records  # noqa: F401


def main(argv: list[str]) -> int:
    if len(argv) not in (4, 7) or not all(a.isdigit() for a in argv):
        print(
            "usage: writer_process.py FRAMES_FD ACKS_FD FILE_FD LEVEL [SHARED_FD SLOT_SIZE SLOTS] (started by "
            "simatch's recorder)",
            file=sys.stderr,
        )
        return 2
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the recording process decides when it ends
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    try:  # woken by a chunk, it waits for its turn rather than taking the recording process's processor at once
        os.sched_setscheduler(0, os.SCHED_BATCH, os.sched_param(0))
    except (AttributeError, OSError):  # not Linux
        pass
    frames, acks, fd, level, *shared = map(int, argv)
    FileWriter(frames, acks, fd, level, tuple(shared) if shared else None).run()
    # everything is written and closed: end without the interpreter's teardown (some milliseconds that the
    # recording process would wait for in `McapWriter.close`)
    os._exit(0)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
