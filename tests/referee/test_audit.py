"""scripts/referee_audit.py end to end: seeded matches of both pairings, every call counted by rule, and sample
situations written as scenes that `simatch run` takes."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_the_audit_counts_every_call_and_writes_scenes_that_run(tmp_path):
    out = tmp_path / "audit"
    proc = subprocess.run(
        [sys.executable, "scripts/referee_audit.py", "--matches", "1", "--half", "20", "--samples", "1"]
        + ["--out", str(out), "--json", "--nice", "0"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout)
    matches = report["matches"]
    assert [(m["cyan"], m["magenta"]) for m in matches] == [("nubot", "nubot"), ("nubot", "simple")]
    assert all(m["sim_seconds"] == pytest.approx(50.0, abs=0.05) for m in matches)  # 2 x 20 s and the break
    calls = report["calls"]
    for kind, row in report["counts"].items():  # the counts are the calls, per match
        assert row == [sum(1 for c in calls if c["type"] == kind and c["match"] == m["index"]) for m in matches]
    assert json.loads((out / "audit.json").read_text()) == report
    scenes = sorted((out / "scenarios").glob("*.toml"))
    assert {p.name.rsplit("_", 1)[0] for p in scenes} == set(report["counts"])  # a sample of every kind of call
    for path in scenes:
        text = path.read_text()
        assert "simatch run THIS_FILE --view" in text and "the referee:" in text
        run = subprocess.run(
            [sys.executable, "-m", "simatch", "run", str(path), "--duration", "0.5", "--json", "--quiet"],
            capture_output=True,
            text=True,
            cwd=ROOT,
            timeout=300,
        )
        assert run.returncode == 0, f"{path.name}: {run.stderr}"
