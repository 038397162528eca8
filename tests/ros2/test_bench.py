"""`simatch bench --only ros2` reports its figures (never judged here: speed is measured, not asserted)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from ..distributed.cluster import ROOT
from .conftest import ros_env

pytestmark = pytest.mark.slow


def test_the_ros2_benchmark_reports_latency_and_the_observers_cost(ros_interfaces):
    out = subprocess.run(
        [sys.executable, "-m", "simatch", "bench", "--only", "ros2", "--seconds", "2", "--json"],
        cwd=ROOT,
        env=ros_env(),
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert out.returncode == 0, out.stderr[-3000:]
    figures = json.loads(out.stdout.strip().splitlines()[-1])
    assert figures["ros2_latency_robots"] == 10
    assert 0 < figures["ros2_latency_applied"] <= figures["ros2_latency_published"]
    assert 0 < figures["ros2_latency_p50_ms"] <= figures["ros2_latency_p99_ms"] <= figures["ros2_latency_max_ms"]
    # applied at the next physics step: never before it arrived
    assert figures["ros2_applied_latency_p50_ms"] >= figures["ros2_latency_p50_ms"]
    assert figures["ros2_applied_latency_p50_ms"] <= figures["ros2_applied_latency_p99_ms"]
    assert figures["ros2_observer_rtf_without"] > 0 and figures["ros2_observer_rtf_with"] > 0
    assert figures["ros2_observer_cpu_ms_per_sim_s_with"] > 0
    assert figures["ros2_domain_id"] == int(ros_env()["ROS_DOMAIN_ID"])
