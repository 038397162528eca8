"""Recordings as rosbag2 folders, read by rosbags' AnyReader as ROS 2 users would (no simatch code reads them)."""

from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from simatch.record import rosbag2
from simatch.record.reader import being_written

SIMATCH = [sys.executable, "-m", "simatch"]


def _read(folder: Path):
    with AnyReader([folder]) as reader:
        by_topic = {c.topic: c for c in reader.connections}
        clock = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections=[by_topic["/clock"]])]
        return by_topic, clock, reader.message_count


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("rosbag2")
    subprocess.run([*SIMATCH, "run", "msl_5v5", "--duration", "1", "--quiet", "--record", f"{tmp}/match/"], check=True)
    subprocess.run(
        [*SIMATCH, "run", "msl_5v5", "--duration", "1", "--quiet", "--record", str(tmp / "plain.mcap")], check=True
    )
    return tmp


def test_record_into_a_folder_reads_with_anyreader(recorded):
    folder = recorded / "match"
    assert sorted(p.name for p in folder.iterdir()) == ["match_0.mcap", "metadata.yaml"]
    topics, clock, count = _read(folder)
    assert topics["/clock"].msgtype == "rosgraph_msgs/msg/Clock"
    assert topics["/simatch/clock"].msgtype == "simatch_msgs/msg/Clock"
    assert topics["/cyan/2/VelCmd"].msgtype == "simatch_msgs/msg/VelCmd"
    # one ROS clock per control period (25 ms), simulated time from 0
    times = [c.clock.sec + c.clock.nanosec * 1e-9 for c in clock]
    assert len(times) == 40 and times[0] == 0.0 and abs(times[-1] - 0.975) < 1e-9
    assert count > 1000


def test_a_folder_of_the_mcap_alone_fails_and_export_makes_it_readable(recorded, tmp_path):
    bare = tmp_path / "bare"
    bare.mkdir()
    (bare / "plain.mcap").write_bytes((recorded / "plain.mcap").read_bytes())
    with pytest.raises(Exception, match="metadata"):
        _read(bare)
    out = subprocess.run(
        [*SIMATCH, "export", str(recorded / "plain.mcap"), "--format", "rosbag2", "--out", str(tmp_path / "bag")],
        check=True,
        capture_output=True,
        text=True,
    )
    assert "rosbag2 folder" in out.stdout
    topics, clock, count = _read(tmp_path / "bag")
    assert topics["/clock"].msgtype == "rosgraph_msgs/msg/Clock" and len(clock) == 40
    # the metadata's counts are the file's, and the hashes ROS 2's (a hash rosbags computes the same way)
    ref_topics, _, ref_count = _read(recorded / "match")
    assert count == ref_count and set(topics) == set(ref_topics)
    kilted = get_typestore(Stores.ROS2_KILTED)
    assert topics["/clock"].digest == kilted.hash_rihs01("rosgraph_msgs/msg/Clock")


def test_refuses_a_folder_that_is_not_empty(tmp_path):
    (tmp_path / "busy").mkdir()
    (tmp_path / "busy" / "x").write_text("keep me")
    with pytest.raises(rosbag2.Rosbag2Error, match="not an empty folder"):
        rosbag2.prepare(tmp_path / "busy")
    assert (tmp_path / "busy" / "x").read_text() == "keep me"
    bad = subprocess.run(
        [*SIMATCH, "run", "msl_5v5", "--duration", "0.1", "--quiet", "--record", f"{tmp_path}/busy/"],
        capture_output=True,
        text=True,
    )
    assert bad.returncode == 2 and "not an empty folder" in bad.stderr and bad.stderr.count("\n") == 1


def test_simatch_commands_take_the_folder(recorded, tmp_path):
    """A folder recorded with --record DIR/ is a recording wherever simatch takes one."""
    info = subprocess.run(
        [*SIMATCH, "replay", str(recorded / "match"), "--info", "--json"], check=True, capture_output=True, text=True
    )
    assert json.loads(info.stdout)["file"].endswith("match_0.mcap")
    verdict = subprocess.run(
        [*SIMATCH, "replay", str(recorded / "match"), "--verify", "--json"], capture_output=True, text=True
    )
    assert verdict.returncode == 0 and json.loads(verdict.stdout)["identical"], verdict.stdout + verdict.stderr
    out = tmp_path / "tables"
    subprocess.run([*SIMATCH, "export", str(recorded / "match"), "--format", "csv", "--out", str(out)], check=True)
    assert (out / "events.csv").is_file()


def test_a_killed_run_leaves_a_folder_that_recover_completes(tmp_path):
    """SIGKILL: the run cannot write metadata.yaml (its writer process still finalises the file); ``simatch
    recover DIR`` writes it, and AnyReader reads the folder."""
    folder = tmp_path / "killed"
    proc = subprocess.Popen(
        [*SIMATCH, "run", "msl_5v5", "--duration", "600", "--quiet", "--record", f"{folder}/"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    mcap = folder / "killed_0.mcap"
    try:
        deadline = time.monotonic() + 120
        while not (mcap.is_file() and mcap.stat().st_size > 300_000) and time.monotonic() < deadline:
            assert proc.poll() is None, proc.stderr.read()
            time.sleep(0.1)
        proc.send_signal(signal.SIGKILL)
        proc.wait(30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(30)
    deadline = time.monotonic() + 30
    while being_written(mcap):
        assert time.monotonic() < deadline, "the writer process did not end"
        time.sleep(0.05)
    assert sorted(p.name for p in folder.iterdir()) == ["killed_0.mcap"]
    with pytest.raises(Exception, match="metadata"):
        _read(folder)
    out = subprocess.run([*SIMATCH, "recover", str(folder)], check=True, capture_output=True, text=True)
    assert "nothing to recover" in out.stdout and "metadata.yaml" in out.stdout, out.stdout
    topics, clock, count = _read(folder)
    assert topics["/clock"].msgtype == "rosgraph_msgs/msg/Clock" and len(clock) > 10
    with open(mcap, "rb") as f:
        assert count == sum(1 for _ in make_reader(f).iter_messages())


def test_outputs_of_a_folder_lie_beside_it_and_the_folder_keeps_the_bag_alone(recorded, tmp_path):
    shutil.copytree(recorded / "match", tmp_path / "match")
    folder = tmp_path / "match"
    report = subprocess.run([*SIMATCH, "report", str(folder)], check=True, capture_output=True, text=True)
    assert (tmp_path / "match.html").is_file() and "wrote" in report.stdout, report.stdout
    subprocess.run([*SIMATCH, "export", str(folder), "--format", "csv"], check=True, capture_output=True)
    assert (tmp_path / "match_tables" / "events.csv").is_file()
    # from inside the folder too ("simatch report ." names the page after the folder)
    (tmp_path / "match.html").unlink()
    subprocess.run([*SIMATCH, "report", "."], cwd=folder, check=True, capture_output=True)
    assert (tmp_path / "match.html").is_file()
    assert sorted(p.name for p in folder.iterdir()) == ["match_0.mcap", "metadata.yaml"]
    topics, clock, _ = _read(folder)
    assert len(clock) == 40


def test_export_rosbag2_of_a_folder_writes_its_missing_metadata(recorded, tmp_path):
    folder = tmp_path / "match"
    shutil.copytree(recorded / "match", folder)
    (folder / rosbag2.METADATA).unlink()
    with pytest.raises(Exception, match="metadata"):
        _read(folder)
    out = subprocess.run(
        [*SIMATCH, "export", str(folder), "--format", "rosbag2"], check=True, capture_output=True, text=True
    )
    assert str(folder) in out.stdout
    topics, clock, count = _read(folder)
    ref_topics, ref_clock, ref_count = _read(recorded / "match")
    assert count == ref_count and set(topics) == set(ref_topics) and len(clock) == len(ref_clock)
    written = (folder / rosbag2.METADATA).read_text()
    assert written == (recorded / "match" / rosbag2.METADATA).read_text()


@pytest.mark.parametrize("files", [0, 2])
def test_a_folder_without_exactly_one_recording_is_refused_in_one_line(recorded, tmp_path, files):
    folder = tmp_path / "odd"
    folder.mkdir()
    for i in range(files):
        shutil.copy(recorded / "plain.mcap", folder / f"part{i}.mcap")
    before = sorted(p.name for p in folder.iterdir())
    for command in (
        ["replay", str(folder), "--info"],
        ["report", str(folder)],
        ["recover", str(folder)],
        ["export", str(folder), "--format", "csv"],
        ["export", str(folder), "--format", "rosbag2"],
        ["export", str(folder), "--format", "rosbag1"],
    ):
        bad = subprocess.run([*SIMATCH, *command], capture_output=True, text=True)
        assert bad.returncode == 2, (command, bad.stdout, bad.stderr)
        assert bad.stderr.count("\n") == 1 and "one .mcap" in bad.stderr, (command, bad.stderr)
    assert sorted(p.name for p in folder.iterdir()) == before  # nothing written, nothing lost
