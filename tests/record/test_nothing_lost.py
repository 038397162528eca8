"""Nothing lost: real processes killed (SIGKILL), interrupted (Ctrl-C) or terminated (SIGTERM) while
recording, and truncated or damaged files given to replay."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time

import pytest
from mcap.reader import make_reader

import simatch
from simatch.record import Recorder, RecordError, Recording, RecordingError, verify

SIMATCH = [sys.executable, "-m", "simatch"]

KILLED_CHILD = textwrap.dedent("""
    import sys, time
    import simatch
    from simatch.record import Recorder
    sim = simatch.Simulation("msl_5v5", seed=2, overrides={"judge.kind": "none"})
    Recorder.for_run(sim, sys.argv[1])
    for coach in sim.coaches.values():
        coach.start_play()
    sim.set_model_state("cyan/4", x=0.0, y=2.0)
    sim.run(seconds=3.5)
    print("at", sim.time, flush=True)
    time.sleep(120)
""")


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.kill()
        proc.wait(timeout=30)


def _writers_of(path) -> list[int]:
    """The processes other than this one that hold ``path`` open (a recording's writer process; this process may
    hold it for a moment, reading it)."""
    found = []
    for entry in os.scandir("/proc"):
        if entry.name.isdigit() and int(entry.name) != os.getpid():
            try:
                if any(os.readlink(fd.path) == str(path) for fd in os.scandir(f"/proc/{entry.name}/fd")):
                    found.append(int(entry.name))
            except OSError:  # gone meanwhile, or not ours to look at
                pass
    return found


def _until_no_writer(path, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while _writers_of(path):
        assert time.monotonic() < deadline, f"the writer process of {path} did not end"
        time.sleep(0.05)


def test_sigkill_leaves_every_chunk_but_the_one_being_filled(tmp_path):
    """The run's process killed: its writer process still writes every chunk it was handed, finalises the file
    (every MCAP reader reads it whole) and ends by itself, quietly; only the half second being filled is lost."""
    path = tmp_path / "killed.mcap"
    proc = subprocess.Popen(
        [sys.executable, "-c", KILLED_CHILD, str(path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        line = proc.stdout.readline()
        assert line.startswith("at "), line
        killed_at = float(line.split()[1])
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        _stop(proc)
    _until_no_writer(path)
    assert proc.stderr.read() == ""  # the writer process (which shares it) ended quietly: no BrokenPipeError
    rec = Recording(path)
    assert rec.finalised and len(rec.problems) == 1 and "before the run did" in rec.problems[0]
    assert rec.end["status"].startswith("killed:") and float(rec.end["sim_seconds"]) == pytest.approx(rec.duration)
    steps = [m.step for _, _, m in rec.messages(topics={"model_states"})]
    assert steps == list(range(len(steps)))  # intact from the start, no gap
    assert steps[-1] * 0.005 >= killed_at - 0.5 - 0.005 - 1e-9  # all but the chunk being filled
    assert json.loads(rec.end["messages"])["model_states"] == len(steps)
    with open(path, "rb") as f:  # the plain mcap reader reads it whole
        assert sum(1 for _, ch, _ in make_reader(f).iter_messages() if ch.topic == "/model_states") == len(steps)
    verdict = verify(path)  # what is there re-simulates bit for bit
    assert verdict.identical and not verdict.complete and verdict.compared == len(steps)


def test_a_killed_writer_process_does_not_stop_the_run(tmp_path):
    """The writer process dies mid-run: the run goes on, closing says what happened, and what was written
    before reads back."""
    path = tmp_path / "lost.mcap"
    with simatch.Simulation("msl_5v5", seed=2, overrides={"judge.kind": "none"}) as sim:
        rec = Recorder.for_run(sim, path)
        for coach in sim.coaches.values():
            coach.start_play()
        sim.run(seconds=1.6)
        deadline = time.monotonic() + 30
        while Recording(path).duration < 1.4:  # the chunks handed over are on disk
            assert time.monotonic() < deadline
            time.sleep(0.05)
        writers = _writers_of(path)
        assert len(writers) == 1
        os.kill(writers[0], signal.SIGKILL)
        _until_no_writer(path)
        sim.run(seconds=1.6)
        assert sim.time >= 3.2
        assert rec._writer.buffer() is None  # the log went on in memory of its own, not in the shared slots
        with pytest.raises(RecordError, match="writer process"):
            rec.close()
    got = Recording(path)
    assert not got.finalised and got.duration >= 1.4


def _run_until_recording(path, *extra):
    proc = subprocess.Popen(
        SIMATCH
        + [
            "run",
            "msl_5v5",
            "--duration",
            "120",
            "--realtime",
            "--quiet",
            "--seed",
            "3",
            "--record",
            str(path),
            *extra,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            if path.exists() and Recording(path).end_ns >= 1_995_000_000:  # two simulated seconds on disk
                return proc
        except RecordingError:  # caught between the file's creation and its header: not an MCAP file yet
            pass
        time.sleep(0.2)
    _stop(proc)
    raise AssertionError(f"the run did not start recording: {proc.stderr.read()}")


@pytest.mark.parametrize(
    "sig, code, status", [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 128 + signal.SIGTERM, "terminated")]
)
def test_ctrl_c_and_sigterm_finalise_the_file(tmp_path, sig, code, status):
    path = tmp_path / "stopped.mcap"
    proc = _run_until_recording(path)
    try:
        proc.send_signal(sig)
        proc.wait(timeout=60)
    finally:
        _stop(proc)
    assert proc.returncode == code, proc.stderr.read()
    assert not _writers_of(path)  # the writer process ended before the run
    rec = Recording(path)
    assert rec.finalised and not rec.problems
    assert rec.end["status"] == status and rec.duration >= 1.9
    assert verify(path).identical


def _replay(*args):
    return subprocess.run(SIMATCH + ["replay", *map(str, args)], capture_output=True, text=True, timeout=300)


def test_a_truncated_file_plays_what_is_intact(recording, tmp_path):
    path, _ = recording
    cut = tmp_path / "cut.mcap"
    data = path.read_bytes()
    cut.write_bytes(data[: int(len(data) * 0.7)])
    proc = _replay(cut, "--speed", "max")
    assert proc.returncode == 0, proc.stderr
    assert "breaks off at byte" in proc.stderr and "Traceback" not in proc.stderr
    played_until = float(proc.stdout.split("..")[1].split()[0])
    assert 0.9 <= played_until < 1.995
    out = json.loads(_replay(cut, "--verify", "--json").stdout)
    assert out["identical"] and not out["complete"] and out["until"] == pytest.approx(played_until)


def test_a_damaged_chunk_is_skipped_and_named(recording, tmp_path):
    path, _ = recording
    bad = tmp_path / "bad.mcap"
    shutil.copy(path, bad)
    chunk = next(c for c in Recording(path).chunks if c.start < 250_000_000 < c.end)  # the first chunk
    with open(bad, "r+b") as f:
        f.seek(chunk.offset + 2000)
        f.write(bytes(64))
    proc = _replay(bad, "--speed", "max")
    assert proc.returncode == 0, proc.stderr
    assert f"the chunk at byte {chunk.offset}" in proc.stderr and "is damaged" in proc.stderr
    assert "t=" in proc.stdout and proc.stdout.strip().split("..")[1].startswith("1.995")


def test_not_a_recording_is_refused_clearly(tmp_path):
    junk = tmp_path / "junk.mcap"
    junk.write_text("this is not a recording")
    proc = _replay(junk)
    assert proc.returncode == 2 and "is not an MCAP recording" in proc.stderr and "Traceback" not in proc.stderr
    proc = _replay(tmp_path / "missing.mcap")
    assert proc.returncode == 2 and "no such recording" in proc.stderr


def test_any_damaged_byte_of_a_chunk_is_caught(recording, tmp_path):
    """Chunks carry zstd's content checksum (their CRC32 field is 0): one changed byte anywhere in a chunk's
    compressed records is a damaged chunk, never wrong messages."""
    path, _ = recording
    data = path.read_bytes()
    chunk = Recording(path).chunks[1]
    end = chunk.offset + 9 + int.from_bytes(data[chunk.offset + 1 : chunk.offset + 9], "little")
    body = chunk.offset + 9 + 8 * 3 + 4 + 4 + 4 + 8  # after times, sizes, CRC, compression, length
    bad = tmp_path / "flipped.mcap"
    for at in range(body, end, (end - body) // 7):
        damaged = bytearray(data)
        damaged[at] ^= 0x20
        bad.write_bytes(damaged)
        rec = Recording(bad)
        kept = [t for _, t, _ in rec.raw()]
        assert any(f"the chunk at byte {chunk.offset}" in p for p in rec.problems), at
        assert not [t for t in kept if chunk.start <= t <= chunk.end], at
