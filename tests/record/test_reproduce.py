"""Reproduction from the strategies (``--verify strategies``): a recorded run re-simulates bit for bit from its
scene, seed and operator commands, and a run changed behind the recorder's back is caught at the step where
it first differs. (Reproduction from the recorded world inputs, the default: test_world_inputs.py.)"""

from __future__ import annotations

import json
import re
import subprocess
import sys

import pytest

import simatch
from simatch.bus import Node, Phase
from simatch.record import Recorder, VerifyError, verify

from .conftest import NOISY, record_run

SIMATCH = [sys.executable, "-m", "simatch"]


def test_a_recorded_run_reproduces_bit_for_bit(recording):
    path, _ = recording
    proc = subprocess.run(
        SIMATCH + ["replay", str(path), "--verify", "strategies", "--json"], capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["identical"] and out["complete"] and out["compared"] == 400 and out["mode"] == "strategies"
    assert out["operator_commands"] == 11 and out["first_difference"] is None


def _verify_a_run_changed_behind_the_recorder(path, change):
    """Record 1 s in which ``change(sim)`` moves magenta/2 at 0.5 s below the Python API (not recorded), then
    verify it. Robots hold their start poses (msl_5v5's default teams play: they would move away)."""

    def sneaky(sim):
        for coach in sim.coaches.values():
            coach.start_play()
        sim.run(seconds=0.5)
        change(sim)
        sim.run(seconds=0.5)

    record_run(
        path,
        overrides={**NOISY, "teams.cyan.strategy": "startpose", "teams.magenta.strategy": "startpose"},
        script=sneaky,
    )
    verdict = verify(path, mode="strategies")
    assert not verdict.identical
    # the placement behind the recorder's back came between steps 99 and 100: the world's inputs of step 100
    assert (verdict.component.step, verdict.component.component) == (100, "inputs"), verdict.describe()
    return verdict.first_difference


def test_the_first_difference_is_named(tmp_path):
    path = tmp_path / "sneaky.mcap"
    diff = _verify_a_run_changed_behind_the_recorder(
        path, lambda sim: sim.simulator.set_model_state("magenta/2", x=3.0, y=-2.5)
    )
    assert (diff.step, diff.model, diff.field) == (100, "magenta/2", "x")
    assert diff.recorded == 3.0 and diff.simulated == pytest.approx(3.5, abs=0.05)  # near its start pose
    proc = subprocess.run(
        SIMATCH + ["replay", str(path), "--verify", "strategies"], capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 1
    assert re.search(
        r"^NOT reproduced: differs from step 100 \(t=0\.500 s\): first in the world's inputs \(.*\) — "
        r"then at step 100 \(t=0\.500 s\): magenta/2 x 3\.0 recorded, (\d+\.\d+) here",
        proc.stdout,
    ), proc.stdout
    shown = float(re.search(r"recorded, (\d+\.\d+) here", proc.stdout).group(1))
    assert shown == diff.simulated


def test_a_difference_below_float32_is_caught_by_the_fingerprint(tmp_path):
    """Recorded states are float32; the fingerprint of the exact float64 ones keeps the check bit for bit."""

    def nudge(sim):
        x = sim.model_states()["magenta/2"].x
        sim.simulator.set_model_state("magenta/2", x=x + 1e-9)  # far below float32 (2.4e-7 at 2 m)

    diff = _verify_a_run_changed_behind_the_recorder(tmp_path / "nudge.mcap", nudge)
    assert (diff.step, diff.model, diff.field) == (100, "(every model)", "fingerprint of the exact states")
    assert diff.recorded != diff.simulated


def test_a_judges_manual_action_is_reproduced(tmp_path):
    path = tmp_path / "judge.mcap"
    overrides = {"judge.kind": "tests.record.operator_judge:ManualBallJudge"}
    with simatch.Simulation("msl_5v5", seed=1, overrides=overrides) as sim:
        with Recorder.for_run(sim, path):
            sim.run(seconds=0.3)
            sim.judge.drop_ball(2.0, -1.0)
            sim.run(seconds=0.3)
    verdict = verify(path, mode="strategies")
    assert verdict.identical and verdict.operator_commands == 1
    assert verify(path).identical  # and from the world inputs (the ball placement among them)


def test_a_recording_that_missed_the_start_is_refused(tmp_path):
    path = tmp_path / "late.mcap"
    with simatch.Simulation("omni_circle") as sim:
        sim.run(seconds=0.1)
        with Recorder.for_run(sim, path):
            sim.run(seconds=0.1)
    for mode in ("auto", "inputs", "strategies"):
        with pytest.raises(VerifyError, match="started at t=0.100 s"):
            verify(path, mode=mode)


class _Console(Node):
    """Like a viewer's control node: carries out queued operator requests inside a step (JUDGE phase)."""

    phase = Phase.JUDGE
    name = "test/console"

    def __init__(self, sim):
        self.sim, self.period, self.queue = sim, sim.dt, []

    def tick(self, now: float) -> None:
        while self.queue:
            self.queue.pop(0)()


def test_requests_carried_out_inside_a_step_are_reproduced(tmp_path):
    path = tmp_path / "console.mcap"
    with simatch.Simulation("msl_5v5", seed=2, overrides={"judge.kind": "none"}) as sim:
        with Recorder.for_run(sim, path):
            console = sim.clock.add(_Console(sim))
            sim.run(seconds=0.2)
            console.queue.append(lambda: sim.coaches["cyan"].start_play())
            console.queue.append(lambda: sim.set_model_state("ball", x=-1.5, y=1.0, vx=-0.5))
            sim.run(seconds=0.3)
            console.queue.append(lambda: sim.coaches["magenta"].send(15, max_vel=2.0))
            sim.run(seconds=0.3)
    verdict = verify(path, mode="strategies")
    assert verdict.identical and verdict.operator_commands == 3, verdict.describe()
    assert verify(path).identical


def test_a_match_that_changes_ends_is_recorded_and_reproduced(tmp_path):
    """A whole refereed match (short halves, nubot on both sides) changes ends at half time: the recording
    has the game states saying so and the 3D field again with the goals' new colours, and it re-simulates bit
    for bit across the change."""
    from simatch.record import Recording
    from simatch.record.scene3d import SceneBuilder

    path = tmp_path / "ends.mcap"
    with simatch.Simulation("msl_5v5", seed=5, overrides={"match.half_duration": 3.0, "match.half_time": 0.5}) as sim:
        with Recorder.for_run(sim, path, command_line=["pytest"]):
            sim.run()
        assert sim.done and sim.game["attacks"] == {"cyan": "-x", "magenta": "+x"}
        spec = sim.scene.spec
    rec = Recording(path)
    fields = list(rec.raw(topics=["scene/field"]))
    builder = SceneBuilder(spec)
    assert [data for _, _, data in fields] == [builder.field_update(), builder.field_update({"cyan": -1, "magenta": 1})]
    assert fields[1][1] == 3_000_000_000  # written when the first half ended
    sides = {(round(t / 1e9, 3) < 3.0, tuple(m.attacks)) for _, t, m in rec.messages(topics=["game_state"])}
    assert sides == {(True, ("+x", "-x")), (False, ("-x", "+x"))}
    for mode in ("inputs", "strategies"):  # from the recorded world inputs, and by playing the match again
        verdict = verify(path, mode=mode)
        assert verdict.identical and verdict.complete, (mode, verdict.describe())
