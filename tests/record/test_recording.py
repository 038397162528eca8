"""A recording holds every topic of the run, the metadata that reproduces it and a Foxglove 3D scene, and
tools that know nothing of simatch read it: rosbags and the mcap readers, in a process that never imports
simatch."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import simatch
from simatch.record import Recorder, RecordError, Recording

from .conftest import NOISY, play_a_little, record_run

ROBOTS = [f"{team}/{i}" for team in ("cyan", "magenta") for i in range(1, 6)]


def test_every_topic_of_the_run_is_recorded(recording):
    path, _ = recording
    rec = Recording(path)
    assert rec.finalised and not rec.problems
    types = rec.topics()
    for robot in ROBOTS:
        for leaf, typ in (
            ("OmniVisionInfo", "OmniVisionInfo"),
            ("VelCmd", "VelCmd"),
            ("ActionCmd", "ActionCmd"),
            ("StrategyInfo", "StrategyInfo"),
        ):
            assert types[f"{robot}/{leaf}"] == f"simatch_msgs/msg/{typ}"
    for team in ("cyan", "magenta"):
        assert types[f"{team}/TeamStrategy"] == "simatch_msgs/msg/TeamStrategy"
        assert types[f"{team}/receive_from_coach"] == "simatch_msgs/msg/CoachInfo"
    for topic, typ in (
        ("clock", "Clock"),
        ("model_states", "ModelStates"),
        ("events", "GameEvent"),
        ("operator", "OperatorCommand"),
        ("ball_contacts", "BallContacts"),
    ):
        assert types[topic] == f"simatch_msgs/msg/{typ}"
    assert types["scene/field"] == types["scene/game"] == "foxglove_msgs/msg/SceneUpdate"
    counts = json.loads(rec.end["messages"])
    assert counts["model_states"] == 400  # 2 s at the physics rate, every step
    assert counts["cyan/3/OmniVisionInfo"] == 80  # every control period (0.025 s)
    steps = [m.step for _, _, m in rec.messages(topics={"model_states"})]
    assert steps == list(range(400))


def test_metadata_reproduces_the_run(recording):
    path, digest = recording
    rec = Recording(path)
    meta = rec.metadata
    assert meta["scene_name"] == "msl_5v5" and meta["seed"] == "4"
    assert json.loads(meta["overrides"]) == NOISY
    assert "[teams.cyan]" in meta["scene_text"]
    assert json.loads(meta["command_line"]) == ["pytest"]
    assert meta["simatch_version"] and meta["format"] == "simatch-recording"
    assert rec.end["status"] == "complete" and rec.end["state_digest"] == digest


def test_operator_commands_are_recorded_in_order(recording):
    path, _ = recording
    ops = [(m.step, m.call, m.target) for _, _, m in Recording(path).messages(topics={"operator"})]
    assert ops == [
        (0, "coach", "cyan"),
        (0, "coach", "magenta"),
        (0, "set_model_state", "ball"),
        (0, "set_model_state", "magenta/3"),
        (120, "take_control", "cyan/2"),
        (120, "send_vel", "cyan/2"),
        (120, "apply_wrench", "ball"),
        (240, "send_action", "cyan/2"),
        (240, "coach", "magenta"),
        (320, "release_control", "cyan/2"),
        (320, "coach", "magenta"),
    ]


def test_the_3d_scene_shows_field_robots_and_ball(recording):
    path, _ = recording
    rec = Recording(path)
    ((_, t0, field),) = list(rec.messages(topics={"scene/field"}))
    entity = field.entities[0]
    assert t0 == 0 and entity.id == "field" and len(entity.lines) >= 10 and len(entity.cubes) >= 7
    games = list(rec.messages(topics={"scene/game"}))
    assert len(games) == 40  # 20 per simulated second
    states = {m.step: m for _, _, m in rec.messages(topics={"model_states"})}
    _, t, last = games[-1]
    state = states[t // 5_000_000]
    pose = np.asarray(state.pose).reshape(-1, 7)
    ids = [e.id for e in last.entities]
    assert ids == list(state.name)
    for k, e in enumerate(last.entities):
        p = (e.spheres or e.cylinders)[0].pose.position
        assert (p.x, p.y) == (round(pose[k, 0] * 1024) / 1024, round(pose[k, 1] * 1024) / 1024)  # to a mm grid
        assert abs(p.x - pose[k, 0]) <= 0.5 / 1024 and abs(p.y - pose[k, 1]) <= 0.5 / 1024
    cyan = last.entities[ids.index("cyan/2")]
    assert cyan.texts[0].text == "2" and cyan.cylinders[0].color.b > 0.5 and cyan.cylinders[0].color.r < 0.2


def test_recording_does_not_change_the_run(tmp_path):
    with simatch.Simulation("msl_5v5", seed=4, overrides=NOISY) as sim:
        play_a_little(sim)
        plain = sim.state_digest()
    assert record_run(tmp_path / "a.mcap") == plain


def test_an_existing_file_is_never_overwritten(tmp_path):
    path = tmp_path / "kept.mcap"
    path.write_bytes(b"precious")
    with simatch.Simulation("omni_circle") as sim:
        with pytest.raises(RecordError, match="already exists"):
            Recorder.for_run(sim, path)
        with pytest.raises(RecordError, match="does not exist"):
            Recorder.for_run(sim, tmp_path / "nowhere" / "x.mcap")
    assert path.read_bytes() == b"precious"


def test_a_writer_process_that_cannot_start_is_a_clear_error(tmp_path, monkeypatch):
    import subprocess

    def refuse(*args, **kwargs):
        raise OSError(11, "Resource temporarily unavailable")

    monkeypatch.setattr(subprocess, "Popen", refuse)
    path = tmp_path / "never.mcap"
    with simatch.Simulation("omni_circle") as sim:
        with pytest.raises(RecordError, match="cannot start the writer process"):
            Recorder.for_run(sim, path)
    assert not path.exists()  # nothing left behind to refuse the next attempt


def test_close_returns_with_the_file_whole_and_the_writer_process_ended(tmp_path):
    """`close` hands the writer process the summary and returns once the file is finalised: by then the
    process has ended with status 0 (it ends itself right after closing the file, without waiting for its
    interpreter's teardown) and the plain mcap reader reads every message."""
    from mcap.reader import make_reader

    path = tmp_path / "closed.mcap"
    with simatch.Simulation("omni_circle") as sim:
        rec = Recorder.for_run(sim, path)
        sim.run(seconds=0.5)
        rec.close()
        proc = rec._writer._proc
    assert proc.returncode == 0
    with open(path, "rb") as f:
        reader = make_reader(f)
        n = sum(1 for _ in reader.iter_messages())
        assert n == sum(reader.get_summary().statistics.channel_message_counts.values()) > 0


FOREIGN_READER = textwrap.dedent("""
    import json, sys
    from pathlib import Path
    assert "simatch" not in sys.modules
    path = Path(sys.argv[1])
    out = {}
    # rosbags: types are rebuilt from the definitions in the file
    from rosbags.highlevel import AnyReader
    with AnyReader([path]) as reader:
        out["rosbags_topics"] = sorted({c.topic: c.msgtype for c in reader.connections}.items())
        n, last = 0, None
        for conn, t, raw in reader.messages([c for c in reader.connections if c.topic == "/model_states"]):
            msg = reader.deserialize(raw, conn.msgtype)
            n, last = n + 1, (t, list(msg.name), [float(v) for v in msg.pose])
        out["rosbags_model_states"], out["rosbags_last"] = n, last
        vision = [c for c in reader.connections if c.topic == "/magenta/4/OmniVisionInfo"]
        for conn, t, raw in reader.messages(vision):
            msg = reader.deserialize(raw, conn.msgtype)
            out["rosbags_vision"] = [msg.robot_id, len(msg.robots), len(msg.obstacles.x)]
            break
    # the mcap readers with the ROS 2 decoder
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        header = reader.get_header()
        out["profile"] = header.profile
        out["mcap_metadata"] = sorted(m.name for m in reader.iter_metadata())
        n, scene = 0, None
        for schema, channel, message, decoded in reader.iter_decoded_messages(topics=["/model_states", "/scene/game"]):
            if channel.topic == "/model_states":
                n += 1
            elif scene is None:
                scene = [schema.name, len(decoded.entities), decoded.entities[0].id]
        out["mcap_model_states"], out["mcap_scene"] = n, scene
    print(json.dumps(out))
""")


def test_readable_without_simatch_by_rosbags_and_mcap(recording):
    path, _ = recording
    proc = subprocess.run(
        [sys.executable, "-c", FOREIGN_READER, str(path)], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    topics = dict(out["rosbags_topics"])
    assert topics["/cyan/1/VelCmd"] == "simatch_msgs/msg/VelCmd"
    assert topics["/scene/game"] == "foxglove_msgs/msg/SceneUpdate"
    assert out["profile"] == "ros2"
    assert out["rosbags_model_states"] == out["mcap_model_states"] == 400
    assert out["rosbags_vision"] == [4, 5, 9]
    assert out["mcap_scene"] == ["foxglove_msgs/msg/SceneUpdate", 11, "cyan/1"]
    assert "simatch" in out["mcap_metadata"] and "simatch_end" in out["mcap_metadata"]
    # the same numbers as simatch's own reader
    t, names, pose = out["rosbags_last"]
    _, t2, mine = list(Recording(path).messages(topics={"model_states"}))[-1]
    assert (t, names, pose) == (t2, list(mine.name), list(mine.pose))


def test_what_a_producer_sends_never_stops_the_recording(tmp_path):
    """A malformed message, or an object that is no message at all, is counted and skipped."""
    from simatch import msgs

    path = tmp_path / "odd.mcap"
    with simatch.Simulation("omni_circle") as sim:
        with Recorder.for_run(sim, path):
            bad = sim.bus.publisher("cyan/1/Weird", msgs.VelCmd)
            alien = sim.bus.publisher("cyan/1/Alien", "not/a/Type")
            sim.run(seconds=0.1)
            bad.put(msgs.VelCmd(stamp=0.1, tick=0, vx="fast", vy=0.0, w=0.0))  # does not encode
            alien.put(object())
            bad.put(msgs.VelCmd(stamp=0.1, tick=0, vx=1.0, vy=0.0, w=0.0))
            sim.run(seconds=0.1)
    rec = Recording(path)
    assert rec.end["status"] == "complete"
    assert json.loads(rec.end["encode_errors"]) == {"cyan/1/Weird": 1}
    assert "cyan/1/Alien" in json.loads(rec.end["skipped_topics"])
    assert [m.vx for _, _, m in rec.messages(topics={"cyan/1/Weird"})] == [1.0]
