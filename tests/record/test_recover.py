"""Recovery (``simatch recover FILE [-o OUT]``): a recording that was never finalised (its writer process died
too) or is damaged becomes a finalised, indexed MCAP file that the plain ``mcap`` reader and rosbags read
whole, and that still re-simulates bit for bit."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from mcap.exceptions import McapError
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader

import simatch
from simatch.record import Recorder, Recording, verify
from simatch.record.recover import RecoverError, recover

from .test_nothing_lost import _until_no_writer, _writers_of

SIMATCH = [sys.executable, "-m", "simatch"]


def _plain_count(path) -> int:
    """Messages the plain mcap reader reads (raises where it cannot read the file)."""
    with open(path, "rb") as f:
        return sum(1 for _ in make_reader(f).iter_messages())


def _recover(*args):
    return subprocess.run(SIMATCH + ["recover", *map(str, args)], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def unfinalised(tmp_path_factory):
    """A recording whose writer process was killed mid-run (SIGKILL): never finalised."""
    path = tmp_path_factory.mktemp("unfinalised") / "lost.mcap"
    with simatch.Simulation("msl_5v5", seed=2, overrides={"judge.kind": "none"}) as sim:
        rec = Recorder.for_run(sim, path)
        for coach in sim.coaches.values():
            coach.start_play()
        sim.run(seconds=1.6)
        deadline = time.monotonic() + 30
        while Recording(path).duration < 1.4:
            assert time.monotonic() < deadline
            time.sleep(0.05)
        (writer,) = _writers_of(path)
        os.kill(writer, signal.SIGKILL)
        _until_no_writer(path)
        sim.run(seconds=0.5)
        try:
            rec.close()
        except Exception:  # the writer process is gone: the recorder says so
            pass
    return path


def test_a_file_whose_writer_died_is_recovered_whole(unfinalised, tmp_path):
    with pytest.raises(McapError):
        _plain_count(unfinalised)  # what the issue saw: the plain reader fails on it
    info = subprocess.run(SIMATCH + ["replay", str(unfinalised), "--info"], capture_output=True, text=True)
    assert f"simatch recover {unfinalised}" in info.stderr  # the message names the command that fixes it
    kept = sum(1 for _ in Recording(unfinalised).raw())
    out = tmp_path / "recovered.mcap"
    proc = _recover(unfinalised, "-o", out, "--json")
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout)
    assert report["messages"] == kept and report["chunks"] >= 2 and report["end"] >= 1.4
    assert _plain_count(out) == kept  # the plain reader reads it whole
    with open(out, "rb") as f:
        summary = make_reader(f).get_summary()
        assert len(summary.chunk_indexes) == report["chunks"]  # indexed
        assert all(c.message_index_offsets for c in summary.chunk_indexes)
        models = sum(1 for _ in make_reader(f).iter_messages(topics=["/model_states"]))
    with AnyReader([out]) as reader:  # and so does rosbags
        assert sum(1 for _ in reader.messages()) == kept
    rec = Recording(out)
    assert rec.finalised and rec.end["status"].startswith("recovered")
    assert json.loads(rec.end["messages"])["model_states"] == models
    verdict = verify(out)
    assert verdict.identical and not verdict.complete and verdict.compared == models
    assert unfinalised.exists() and not Recording(unfinalised).finalised  # -o leaves the source as it was


def test_recovering_in_place(unfinalised, tmp_path):
    path = tmp_path / "in_place.mcap"
    shutil.copy(unfinalised, path)
    first = _recover(path, "--quiet")
    assert first.returncode == 0 and "finalised and indexed" in first.stdout, first.stderr
    assert Recording(path).finalised and _plain_count(path) > 0
    assert not list(tmp_path.glob("*.recovering"))
    again = _recover(path)
    assert again.returncode == 0 and "nothing to recover" in again.stdout


def test_damaged_and_truncated_files(recording, tmp_path):
    """A damaged chunk in the middle is left out (and named), a file cut anywhere keeps what comes before."""
    path, _ = recording
    data = path.read_bytes()
    chunks = Recording(path).chunks
    bad = bytearray(data)
    bad[chunks[1].offset + 2000] ^= 0xFF
    damaged = tmp_path / "damaged.mcap"
    damaged.write_bytes(bad)
    report = recover(damaged, tmp_path / "damaged_out.mcap")
    assert any(f"the chunk at byte {chunks[1].offset}" in s for s in report.skipped)
    assert _plain_count(tmp_path / "damaged_out.mcap") == report.messages > 0
    for k, fraction in enumerate((0.2, 0.45, 0.7, 0.999)):
        cut = tmp_path / f"cut{k}.mcap"
        cut.write_bytes(data[: int(len(data) * fraction)])
        out = tmp_path / f"cut{k}_out.mcap"
        report = recover(cut, out)
        assert _plain_count(out) == report.messages == sum(1 for _ in Recording(cut).raw())


def test_lost_channel_definitions_drop_only_their_messages(recording, tmp_path):
    """The first chunk (which defines the channels) damaged, the file cut: what is left of the other chunks is
    kept for the channels the summary-less file still defines, and the plain reader reads the result whole."""
    path, _ = recording
    data = bytearray(path.read_bytes())
    first = Recording(path).chunks[0]
    data[first.offset + 3000] ^= 0xFF
    cut = tmp_path / "nodefs.mcap"
    cut.write_bytes(data[: int(len(data) * 0.8)])
    out = tmp_path / "nodefs_out.mcap"
    report = recover(cut, out)
    assert any("whose definition was lost" in s for s in report.skipped)
    assert _plain_count(out) == report.messages


def test_refusals(tmp_path):
    junk = tmp_path / "junk.mcap"
    junk.write_text("not a recording")
    proc = _recover(junk)
    assert proc.returncode == 2 and "is not an MCAP file" in proc.stderr and "Traceback" not in proc.stderr
    proc = _recover(tmp_path / "missing.mcap")
    assert proc.returncode == 2 and "no such file" in proc.stderr
    path = tmp_path / "live.mcap"
    with simatch.Simulation("omni_circle") as sim, Recorder.for_run(sim, path) as recorder:
        sim.run(seconds=0.6)
        recorder._writer.flush()  # the first chunk is on disk
        with pytest.raises(RecoverError, match="being written by a running recorder"):
            recover(path)
        assert any("being written right now" in p for p in Recording(path).problems)
    exists = tmp_path / "exists.mcap"
    exists.write_text("")
    proc = _recover(path, "-o", exists)
    assert proc.returncode == 2 and "already exists" in proc.stderr
    assert Path(path).read_bytes()  # nothing was touched


def test_info_on_damaged_metadata(recording, tmp_path):
    """Found by the fuzzing campaign: `replay --info` on a file whose metadata values were damaged raised a
    JSONDecodeError traceback. It describes what it can and says what is damaged."""
    path, _ = recording
    data = path.read_bytes()
    assert data.count(b'["pytest"]') == 1
    bad = tmp_path / "damaged_meta.mcap"
    bad.write_bytes(data.replace(b'["pytest"]', b'["pytest" '))
    for extra in ([], ["--json"]):
        proc = subprocess.run(SIMATCH + ["replay", str(bad), "--info", *extra], capture_output=True, text=True)
        assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr
    assert json.loads(proc.stdout)["command_line"] is None
