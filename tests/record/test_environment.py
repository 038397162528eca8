"""A recording says what made it (software and machine), and a re-simulation that does not reproduce it
names what differs in the same line as the first difference."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from simatch.record import environment
from simatch.record.reader import Recording
from simatch.record.reproduce import verify

from .conftest import NOISY, record_run

SHARED = Path(__file__).resolve().parents[3] / "shared" / "reference" / "recordings"


def test_the_environment_names_software_and_machine():
    env = environment.describe()
    for key in ("python", "commit", "simatch", "mujoco-core", "numpy", "numba", "machine", "cpu", "cpu_flags", "os"):
        assert env[key] and isinstance(env[key], str), key
    assert env["python"].endswith(".".join(map(str, sys.version_info[:3])))
    assert env["mujoco-core"] != "not installed"


def test_differences_name_what_changes_results_first():
    here = environment.describe()
    there = {**here, "python": "CPython 3.99.0", "cpu_flags": here["cpu_flags"] + " avx512f", "numpy": "1.0"}
    found = environment.differences(there, here)
    assert found[0] == "CPU vector extensions (avx512f there, not here)"
    assert found[1] == f"python CPython 3.99.0 there, {here['python']} here"
    assert any(d.startswith("numpy 1.0 there") for d in found)
    assert environment.differences(here, here) == []


def test_a_recording_keeps_its_environment(recording):
    path, _ = recording
    assert environment.recorded(Recording(path).metadata) == environment.describe()


def test_a_recording_made_elsewhere_that_does_not_reproduce_says_what_differs(tmp_path, monkeypatch):
    """Made in a (pretended) other environment, and changed behind the recorder so that it does not
    reproduce here: the verdict's one line holds the first difference and the environment's differences."""
    here = environment.describe()
    elsewhere = {**here, "cpu_flags": here["cpu_flags"] + " avx512f", "python": "CPython 3.99.0"}
    monkeypatch.setattr(environment, "describe", lambda: elsewhere)

    def sneaky(sim):
        sim.run(seconds=0.3)
        sim.simulator.set_model_state("magenta/2", x=3.0, y=-2.5)  # below the API: the strategies did not
        sim.run(seconds=0.2)

    path = tmp_path / "elsewhere.mcap"
    record_run(path, overrides={**NOISY, "teams.magenta.strategy": "startpose"}, script=sneaky)
    monkeypatch.setattr(environment, "describe", lambda: here)
    assert json.loads(Recording(path).metadata["environment"]) == elsewhere
    verdict = verify(path, mode="strategies")
    assert not verdict.identical
    line = verdict.describe().splitlines()[0]
    assert line.startswith("NOT reproduced: differs from step 60 (t=0.300 s): first in the world's inputs"), line
    assert "then at step 60 (t=0.300 s): magenta/2" in line, line
    assert "made in another environment: CPU vector extensions (avx512f there, not here), python CPython 3.99.0" in line
    assert verdict.as_dict()["environment"] == environment.differences(elsewhere, here)


@pytest.mark.skipif(not SHARED.is_dir(), reason="the shared recordings made on another machine are not here")
@pytest.mark.parametrize("name", ["msl_5v5-seed5-20s.mcap", "aerial_encirclement-seed0-20s.mcap"])
def test_the_recordings_made_on_another_machine_are_verified_or_refused_with_the_reason(name):
    proc = subprocess.run(
        [sys.executable, "-m", "simatch", "replay", str(SHARED / name), "--verify"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    first = proc.stdout.strip().splitlines()[0] if proc.stdout.strip() else proc.stderr
    if proc.returncode == 0:
        assert first.startswith("reproduced bit for bit"), first
    else:
        # (recorded before the component fingerprints: the step, and why no component is named)
        assert first.startswith("NOT reproduced: differs from step "), proc.stdout + proc.stderr
        assert "predates component fingerprints" in first and "made in another environment" in first, first
