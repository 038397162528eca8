"""The chunks' hand-over in memory shared with the writer process (`simatch.record.writer`): real runs, a real
writer process, files read back by the plain ``mcap`` reader. What must hold: the same recording as through
the pipe, no file in ``/dev/shm`` (an anonymous memory file), a chunk larger than its slot and a system
without ``memfd_create`` handled by the pipe. (Killed recording and writer processes: test_nothing_lost.py,
which records through the shared memory too.)"""

from __future__ import annotations

import os
import sys

from mcap.reader import make_reader

from simatch.record import Recording, verify, writer, writer_process
from simatch.record.messagelog import new_log
from simatch.record.writer_process import CHUNK, SHARED

from .conftest import play_a_little, record_run
from .test_nothing_lost import _writers_of


def _shared_maps(pid) -> list[str]:
    """The files of ``pid``'s shared mappings that are memory, not code or data files: memfds and /dev/shm."""
    with open(f"/proc/{pid}/maps") as f:
        names = [line.split(None, 5)[5].strip() for line in f if len(line.split(None, 5)) == 6]
    return [n for n in names if n.startswith("/memfd:") or n.startswith("/dev/shm")]


def _frames(monkeypatch) -> list[int]:
    """The kinds of the chunk frames every McapWriter sends from now on."""
    kinds: list[int] = []
    send = writer.McapWriter._send

    def spy(self, kind, *parts):
        if kind in (CHUNK, SHARED):
            kinds.append(kind)
        return send(self, kind, *parts)

    monkeypatch.setattr(writer.McapWriter, "_send", spy)
    return kinds


def test_a_run_hands_its_chunks_over_in_an_anonymous_shared_memory_file(tmp_path, monkeypatch, recording):
    """A recorded run writes its chunks into memory that it and the writer process map from one memfd (no
    name in /dev/shm: nothing to leave behind, however the processes end); the pipe carries no chunk, and the
    recording is the one the fixture made (the same run) and re-simulates bit for bit."""
    kinds = _frames(monkeypatch)
    path = tmp_path / "shared.mcap"
    before = _shared_maps(os.getpid())  # (other libraries of the test process may map /dev/shm files of theirs)
    seen = {}

    def script(sim):
        play_a_little(sim)
        (pid,) = _writers_of(path)
        seen["writer"], seen["run"] = _shared_maps(pid), _shared_maps(os.getpid())

    digest = record_run(path, script=script)
    assert seen["writer"] == ["/memfd:simatch-recording (deleted)"]
    assert "/memfd:simatch-recording (deleted)" in seen["run"]
    assert {n for n in seen["run"] if n.startswith("/dev/shm")} <= set(before)
    assert kinds and set(kinds) == {SHARED}
    assert digest == recording[1] and list(Recording(path).raw()) == list(Recording(recording[0]).raw())
    assert verify(path).identical


def test_without_memfd_the_chunks_go_through_the_pipe(tmp_path, monkeypatch, recording):
    """A system without ``memfd_create`` (not Linux): the pipe carries the chunks, with the same recording."""
    monkeypatch.delattr(os, "memfd_create")
    kinds = _frames(monkeypatch)
    path = tmp_path / "piped.mcap"
    assert record_run(path) == recording[1]
    assert kinds and set(kinds) == {CHUNK}
    assert list(Recording(path).raw()) == list(Recording(recording[0]).raw())
    with open(path, "rb") as f:
        assert sum(1 for _ in make_reader(f).iter_messages()) == sum(1 for _ in Recording(path).raw())


def test_chunks_larger_than_a_slot_go_through_the_pipe(tmp_path, monkeypatch, recording):
    """Slots smaller than the run's chunks (some 370 kB of the match): every chunk outgrows its slot and goes
    through the pipe, and the recording is the same."""
    monkeypatch.setattr(writer, "SLOT_SIZE", 64 * 1024)
    kinds = _frames(monkeypatch)
    path = tmp_path / "large.mcap"
    assert record_run(path) == recording[1]
    assert kinds and set(kinds) == {CHUNK}
    assert list(Recording(path).raw()) == list(Recording(recording[0]).raw())


def _blob_writer(path):
    """A writer of ``path`` with slots of 4 kB, a message log lent its first slot, and one channel of blobs:
    (writer, log, channel id, the schema and channel records the log holds first)."""
    w = writer.McapWriter(path, profile="ros2", library="pytest", slot_size=4096)
    log = new_log(lambda topic, msg: None)
    log.into(w.buffer())
    sid, schema = w.schema("pytest/Blob", "ros2msg", b"uint8[] data")
    cid, channel = w.channel("/blob", sid, "cdr")
    log.append(schema + channel)
    return w, log, cid, schema + channel


def _hand_over(w, log) -> None:
    """The log's chunk to the writer, as the recorder hands it over, and the next slot lent to the log."""
    data, counts, first, last = log.take()
    w.end_chunk(data, first, last, counts)
    del data
    log.into(w.buffer())


def test_chunks_that_fit_their_slot_and_chunks_that_do_not_mix(tmp_path, monkeypatch):
    """Chunks of every size, in slots of 4 kB: each one that fits goes through the shared memory, each one that
    does not through the pipe, and every message is in the file in order, as the plain mcap reader reads it."""
    kinds = _frames(monkeypatch)
    path = tmp_path / "mixed.mcap"
    w, log, cid, records = _blob_writer(path)
    assert w.shared
    sizes = [100, 5000, 200, 3000, 9000, 4000, 50, 70000, 10]
    sent = []
    for i, size in enumerate(sizes):
        log.now = i * 1000
        for j in range(3):
            payload = bytes([i, j]) * (size // 2)
            log.record(cid, payload)
            sent.append(payload)
        _hand_over(w, log)
    log.into(None)
    w.close()
    # a chunk's records: its three messages (31 bytes of header each) and, in the first, the schema and channel
    fits = [3 * (31 + s) + (len(records) if i == 0 else 0) <= 4096 for i, s in enumerate(sizes)]
    assert kinds == [SHARED if fit else CHUNK for fit in fits]
    assert CHUNK in kinds and SHARED in kinds
    with open(path, "rb") as f:
        got = [(ch.topic, msg.data) for _, ch, msg in make_reader(f).iter_messages()]
    assert got == [("/blob", p) for p in sent]


def test_a_chunk_larger_than_the_pipe_is_written_whole(tmp_path):
    """Chunks that fit neither their slot nor the pipe (1 MB at most): the frame's write waits for the writer
    process to read, every byte arrives in order, and the counts add up over the chunks."""
    path = tmp_path / "huge.mcap"
    w, log, cid, _ = _blob_writer(path)
    sent = []
    for i, size in enumerate([3_000_001, 10, 2_200_000]):
        log.now = i * 1000
        payload = bytes(range(256)) * (size // 256) + bytes([i])
        log.record(cid, payload)
        sent.append(payload)
        _hand_over(w, log)
        assert w.counts() == {cid: i + 1}
    log.into(None)
    w.close()
    with open(path, "rb") as f:
        got = [msg.data for _, _, msg in make_reader(f).iter_messages()]
    assert got == sent


def test_the_run_does_not_wait_for_the_writer_process_to_start(tmp_path, monkeypatch):
    """While the writer process starts (held back here for 1.5 s), up to `MAX_HANDED_STARTING` chunks are handed
    over without waiting for it; once it has written and caught up, at most `MAX_HANDED` are in its hands."""
    script = writer_process.__file__
    late = f"import runpy, time; time.sleep(1.5); runpy.run_path({script!r}, run_name='__main__')"
    start = writer._writer_start
    monkeypatch.setattr(
        writer, "_writer_start", lambda args: ([sys.executable, "-S", "-P", "-c", late, *args], start(args)[1])
    )
    path = tmp_path / "late.mcap"
    w, log, cid, _ = _blob_writer(path)
    sent = []

    def chunk() -> None:
        log.now = len(sent) * 1000
        sent.append(bytes([len(sent)]) * 3000)
        log.record(cid, sent[-1])
        _hand_over(w, log)

    for _ in range(writer.MAX_HANDED_STARTING):
        chunk()
    assert len(w._handed) == writer.MAX_HANDED_STARTING  # none waited for the sleeping process
    chunk()  # one more waits until it writes
    w.flush()
    for _ in range(8):
        chunk()
        assert len(w._handed) <= writer.MAX_HANDED and not w._starting  # it runs: two at most again
    log.into(None)
    w.close()
    with open(path, "rb") as f:
        assert [msg.data for _, _, msg in make_reader(f).iter_messages()] == sent


def test_a_writer_process_whose_packages_are_not_found_starts_with_site(tmp_path, monkeypatch):
    """Without the folders of its packages to put on its path, the writer process starts as any Python program
    does (with ``site``), and writes the recording all the same."""
    command, env = writer._writer_start(["1"])
    assert command[1:3] == ["-S", "-P"] and env["PYTHONPATH"]
    monkeypatch.setattr(writer_process, "IMPORTS", ("zstandard", "mcap", "no_such_package_here"))
    command, env = writer._writer_start(["1"])
    assert "-S" not in command and env == dict(os.environ)
    path = tmp_path / "site.mcap"
    w, log, cid, _ = _blob_writer(path)
    log.record(cid, b"written")
    _hand_over(w, log)
    log.into(None)
    w.close()
    with open(path, "rb") as f:
        assert [msg.data for _, _, msg in make_reader(f).iter_messages()] == [b"written"]
