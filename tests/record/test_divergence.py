"""A re-simulation that departs from its recording names the first step and component (world physics, ball
handling, ...) from the per-component fingerprints a recording keeps (`simatch.sim.components`)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest
from mcap.reader import NonSeekingReader
from mcap.writer import Writer

import simatch
from simatch import msgs
from simatch.bus import topics
from simatch.record import Recorder, layout
from simatch.record.reader import Recording
from simatch.record.reproduce import verify
from simatch.sim.ballhandling import BallHandling
from simatch.sim.components import COMPONENTS

from .conftest import NOISY, play_a_little

CHANNEL = layout.channel_topic(topics.COMPONENT_FINGERPRINTS)
TYPE = "simatch_msgs/msg/ComponentFingerprints"


def rewrite(src, dst, change, metadata=lambda name, data: data) -> int:
    """Copy the recording ``src`` into ``dst`` (a plain MCAP writer), each message's payload passed through
    ``change(channel topic, data) -> data`` (None: left out) and each metadata record through ``metadata``;
    the number of messages changed."""
    changed = 0
    with open(src, "rb") as f:
        meta = [(m.name, dict(m.metadata)) for m in NonSeekingReader(f).iter_metadata()]
    with open(src, "rb") as f, open(dst, "wb") as out:
        writer = Writer(out)
        writer.start(profile=layout.PROFILE, library="test")
        schemas, channels = {}, {}
        for schema, channel, message in NonSeekingReader(f).iter_messages():
            data = change(channel.topic, message.data)
            if data is None:
                continue
            changed += data != message.data
            if schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = writer.register_channel(
                    channel.topic, channel.message_encoding, schemas[schema.id], channel.metadata
                )
            writer.add_message(channels[channel.id], message.log_time, data, message.publish_time, message.sequence)
        for name, data in meta:
            writer.add_metadata(name, metadata(name, data))
        writer.finish()
    return changed


def tamper(src, dst, step: int, component: str) -> None:
    """Rewrite the one recorded fingerprint of ``component`` at physics step ``step`` (one bit flipped)."""

    def change(topic, data):
        if topic != CHANNEL:
            return data
        msg = msgs.decode(msgs.ComponentFingerprints, data)
        rows = np.asarray(msg.fingerprint, dtype=np.uint64).reshape(-1, len(msg.component)).copy()
        if not msg.step <= step < msg.step + len(rows):
            return data
        rows[step - msg.step, list(msg.component).index(component)] ^= np.uint64(1)
        msg.fingerprint = rows.ravel()
        return msgs.encode(msg)

    assert rewrite(src, dst, change) == 1


def test_every_step_of_a_recording_has_its_component_fingerprints(recording):
    path, _ = recording
    rec = Recording(path)
    assert rec.metadata["format_version"] == layout.FORMAT_VERSION == "3"
    steps = []
    for _, _, msg in rec.messages(topics={topics.COMPONENT_FINGERPRINTS}):
        assert tuple(msg.component) == COMPONENTS
        rows = np.asarray(msg.fingerprint).reshape(-1, len(COMPONENTS))
        steps += range(msg.step, msg.step + len(rows))
        assert rows[:, COMPONENTS.index("world physics")].all() and rows[:, COMPONENTS.index("inputs")].all()
    # every step but those of the control period under way when the recording ended (5 steps of 5 ms)
    assert steps == list(range(len(steps))) and len(steps) == 400 - 5


@pytest.mark.parametrize(("step", "component"), [(123, "ball handling"), (250, "world physics"), (7, "inputs")])
def test_a_tampered_component_fingerprint_is_named_at_its_step(recording, tmp_path, step, component):
    path, _ = recording
    tampered = tmp_path / "tampered.mcap"
    tamper(path, tampered, step, component)
    for mode in ("inputs", "strategies"):
        verdict = verify(tampered, mode=mode)
        assert not verdict.identical and verdict.first_difference is None, (mode, verdict.describe())
        assert (verdict.component.step, verdict.component.component) == (step, component), mode
        line = verdict.describe().splitlines()[0]
        assert line.startswith(f"NOT reproduced: differs from step {step} (t={step * 0.005:.3f} s): first in "), line
        assert "the model states and the exact states' fingerprints agree to the end (400 samples)" in line, line
        out = verdict.as_dict()
        assert out["first_component"]["component"] == component and out["verdict"] == line


def _nudged_mj_step(at: int):
    """MuJoCo's step, with one robot's x velocity one ULP off after step ``at``."""
    original = mujoco.mj_step

    def mj_step(m, d, *args):
        k = round(d.time / m.opt.timestep)
        original(m, d, *args)
        if k == at:
            d.qvel[0] = np.nextafter(d.qvel[0], np.inf)

    return mj_step


def _nudged_ball_handling(at: int):
    """Ball handling's step, with the ball's x velocity one ULP off at step ``at``."""
    original = BallHandling.before_step

    def before_step(self, step, enabled):
        original(self, step, enabled)
        if step == at:
            v = self.ix.ball_qvel
            self.d.qvel[v] = np.nextafter(self.d.qvel[v], np.inf)

    return before_step


@pytest.mark.parametrize(
    ("component", "target", "name", "nudge"),
    [
        ("world physics", mujoco, "mj_step", _nudged_mj_step),
        ("ball handling", BallHandling, "before_step", _nudged_ball_handling),
    ],
)
def test_a_component_one_ulp_off_at_a_step_is_named_there(tmp_path, monkeypatch, component, target, name, nudge):
    """A run recorded with one component's output one ULP off at step 137 (the rest exact), verified with the
    exact component: the verdict names step 137 and that component, from the inputs and from the strategies."""
    path = tmp_path / "nudged.mcap"
    monkeypatch.setattr(target, name, nudge(137))
    with simatch.Simulation("msl_5v5", seed=2, overrides=NOISY) as sim:
        with Recorder.for_run(sim, path, command_line=["pytest"]):
            play_a_little(sim)
    monkeypatch.undo()
    for mode in ("inputs", "strategies"):
        verdict = verify(path, mode=mode)
        assert not verdict.identical, mode
        assert (verdict.component.step, verdict.component.component) == (137, component), (mode, verdict.describe())
    proc = subprocess.run(
        [sys.executable, "-m", "simatch", "replay", str(path), "--verify", "--json"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    out = json.loads(proc.stdout)
    assert proc.returncode != 0 and out["first_component"]["component"] == component, proc.stdout + proc.stderr
    assert out["verdict"].startswith(f"NOT reproduced: differs from step 137 (t=0.685 s): first in {component}")


def test_a_recording_without_component_fingerprints_names_the_step_only(recording, tmp_path):
    """A recording of format 2 (before the component fingerprints) that does not reproduce: the verdict names
    the step and says that the recording predates them."""
    path, _ = recording
    old = tmp_path / "format2.mcap"

    def as_format_2(topic, data):
        """No component fingerprints; the first robot's recorded x one float32 ULP off at step 300."""
        if topic == CHANNEL:
            return None
        if topic == layout.channel_topic(topics.MODEL_STATES) and msgs.decode(msgs.ModelStates, data).step == 300:
            msg = msgs.decode(msgs.ModelStates, data)
            msg.pose = np.asarray(msg.pose).copy()
            msg.pose[0] = np.nextafter(msg.pose[0], np.float32(np.inf))
            return msgs.encode(msg)
        return data

    def format_2(name, data):
        return {**data, "format_version": "2"} if name == layout.META_START else data

    assert rewrite(path, old, as_format_2, format_2) == 1
    verdict = verify(old)
    assert not verdict.identical and verdict.component is None and not verdict.components
    line = verdict.describe().splitlines()[0]
    assert line.startswith(
        "NOT reproduced: differs from step 300 (t=1.500 s): the recording (format 2) predates component fingerprints, "
        "so no component is named — "
    ), line


def test_a_strategy_that_decides_otherwise_is_named_from_the_strategies(tmp_path):
    """A strategy drawing from unseeded randomness: re-run from the strategies, its commands differ at the first
    control tick where it decides, before anything in the world, and the verdict names a strategy; from the
    recorded inputs the world reproduces."""
    path = tmp_path / "wander.mcap"
    overrides = {**NOISY, "teams.cyan.strategy": "tests.record.random_plugins:Wanderer"}
    with simatch.Simulation("msl_5v5", seed=1, overrides=overrides) as sim:
        with Recorder.for_run(sim, path, command_line=["pytest"]):
            for coach in sim.coaches.values():
                coach.start_play()
            sim.run(seconds=0.5)
    assert verify(path).identical
    verdict = verify(path, mode="strategies")
    assert verdict.component.component == "strategies" and verdict.component.step % 5 == 0, verdict.describe()
    assert verdict.describe().startswith(
        f"NOT reproduced: differs from step {verdict.component.step} (t={verdict.component.t:.3f} s): "
        "first in a strategy (the commands the robots sent)"
    )


ROOT = Path(__file__).resolve().parents[2]
#: other Pythons to check recordings across: SIMATCH_OTHER_PYTHONS (interpreters, separated by os.pathsep), or the
#: checkout's venvs (`make test` sets one up for another supported Python of the machine: its run dependencies,
#: its C extensions built in place)
OTHER_PYTHONS = os.environ.get("SIMATCH_OTHER_PYTHONS", "")


def _other_python() -> str:
    """Another Python than this one that runs simatch from this checkout (the test is skipped without one)."""
    candidates = [c for c in OTHER_PYTHONS.split(os.pathsep) if c] or [
        str(p) for p in sorted(ROOT.glob(".venv*/bin/python"))
    ]
    tried = []
    for python in candidates:
        probe = subprocess.run(
            [python, "-c", "import sys, simatch.sim.simulator; print(sys.version_info[:2])"],
            capture_output=True,
            text=True,
            env={**os.environ, "PYTHONPATH": str(ROOT / "src")},
            timeout=120,
        )
        if probe.returncode == 0 and probe.stdout.strip() != str(sys.version_info[:2]):
            return python
        tried.append(f"{python}: {(probe.stderr.strip().splitlines() or ['the same Python as this one'])[-1]}")
    pytest.skip(
        "no other Python runs simatch here (`make test` sets one up where the machine has another supported "
        "Python; or set SIMATCH_OTHER_PYTHONS to an interpreter with simatch's run dependencies and its C "
        "extensions built for it)" + (f"; tried {'; '.join(tried)}" if tried else "")
    )


@pytest.mark.parametrize("scene", ["msl_5v5", "aerial_encirclement"])
@pytest.mark.parametrize("made_there", [True, False], ids=["made-there-verified-here", "made-here-verified-there"])
def test_a_recording_made_under_another_python_is_reproduced(tmp_path, made_there, scene):
    """A recording made under another Python (and there another NumPy and OpenBLAS) re-simulates bit for bit
    under this one, and the reverse: the world computes nothing that the Python or NumPy version changes
    (docs/reliability.md, "Across machines"). Were it to differ, the verdict names the first divergent step and
    component and says that the Python differs: the assertion shows that line."""
    other = _other_python()
    maker, checker = (other, sys.executable) if made_there else (sys.executable, other)
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    path = tmp_path / "python.mcap"
    made = subprocess.run(
        [maker, "-m", "simatch", "run", scene, "--duration", "1", "--record", str(path)],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert made.returncode == 0, made.stderr
    proc = subprocess.run(
        [checker, "-m", "simatch", "replay", str(path), "--verify", "--json"],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    out = json.loads(proc.stdout)
    assert out["identical"] and proc.returncode == 0, out["verdict"]
    assert out["verdict"].startswith("reproduced bit for bit"), out["verdict"]


def test_a_damaged_component_message_is_left_out_and_said(recording, tmp_path):
    """A component-fingerprints message that claims steps after the one it was recorded at (a damaged step
    number) is neither followed nor compared: the verdict notes it, and the rest is verified."""
    path, _ = recording
    damaged = tmp_path / "damaged.mcap"

    def change(topic, data):
        if topic != CHANNEL:
            return data
        msg = msgs.decode(msgs.ComponentFingerprints, data)
        if msg.step != 100:
            return data
        msg.step = 10**12
        return msgs.encode(msg)

    assert rewrite(path, damaged, change) == 1
    for mode in ("inputs", "strategies"):
        verdict = verify(damaged, mode=mode)
        assert verdict.identical and not verdict.complete, (mode, verdict.describe())
        assert any("component-fingerprints message at t=0.525 s is damaged" in p for p in verdict.problems), mode
