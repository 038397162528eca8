"""`simatch bench --only ros1` reports its figures (never judged here: speed is measured, not asserted)."""

from __future__ import annotations

import json
import subprocess

import pytest

from tests.ros1.conftest import ROOT, SIMATCH

pytestmark = pytest.mark.slow


def test_the_ros1_benchmark_reports_real_time_and_lockstep():
    out = subprocess.run(
        [*SIMATCH, "bench", "--only", "ros1", "--seconds", "2", "--json"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert out.returncode == 0, out.stderr[-3000:]
    figures = json.loads(out.stdout.strip().splitlines()[-1])
    assert figures["ros1_robot_stacks"] == 10
    assert figures["ros1_realtime_commands"] > 0 and figures["ros1_realtime_unmatched"] == 0
    assert figures["ros1_realtime_latency_p50_ms"] > 0 and figures["ros1_lockstep_answers_p50_ms"] > 0
    assert figures["ros1_lockstep_digest_equal"] is True
