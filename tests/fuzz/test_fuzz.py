"""The fuzzing campaign's deterministic slice: every target of tests/fuzz/targets.py with a few derandomized
Hypothesis examples (each one a seed and its variants), and the campaign script itself, briefly, on every target
and on a target that crashes and hangs on purpose (it must find, save and replay both)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from .targets import COUNTS, TARGETS

ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]
EXAMPLES = {"cdr": 40, "bundle": 40, "websocket": 20, "scene": 15, "recording": 6, "commands": 12}


@pytest.mark.parametrize("name", sorted(TARGETS))
def test_target(name):
    before = COUNTS[name]
    TARGETS[name].test(max_examples=EXAMPLES[name], derandomize=True)()
    assert COUNTS[name] > before


@pytest.mark.slow
def test_the_campaign_counts_inputs_finds_crashes_and_hangs(tmp_path):
    fuzz = [sys.executable, str(ROOT / "scripts" / "fuzz.py")]
    proc = subprocess.run(
        fuzz + ["--minutes", "0.25", "--json", "--out", str(tmp_path), "--targets", "cdr,bundle,scene"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    report = json.loads(proc.stdout)
    assert proc.returncode == 0 and report["crashes"] == 0, proc.stdout
    assert report["inputs"] > 1000 and set(report["targets"]) == {"cdr", "bundle", "scene"}
    assert 0 < report["coverage"]["lines_percent"] <= 100
    proc = subprocess.run(
        fuzz + ["--minutes", "0.15", "--hang", "1", "--json", "--out", str(tmp_path), "--targets", "selftest"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    report = json.loads(proc.stdout)
    crashes = report["targets"]["selftest"]["crashes"]
    assert proc.returncode == 1 and {c["kind"] for c in crashes} == {"ZeroDivisionError", "hang"}, proc.stdout
    crash = next(c for c in crashes if c["kind"] == "ZeroDivisionError")
    again = subprocess.run(fuzz + ["--replay", crash["file"]], capture_output=True, text=True, timeout=60)
    assert again.returncode == 1 and "the selftest's crash" in again.stderr
