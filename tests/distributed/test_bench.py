"""`simatch bench --only distributed_rtt` reports the round trip and its parts (never judged here: speed is
the bench's business)."""

from __future__ import annotations

import pytest


@pytest.mark.slow
def test_the_round_trip_benchmark_reports_the_whole_and_its_parts():
    from simatch.bench.distributed import rtt

    out = rtt(seconds=2.0)
    assert out["distributed_rtt_samples"] == 80  # every tick of 2 s answered
    for name in ("", "_feed", "_processing", "_transit"):
        p50, p99 = out[f"distributed_rtt{name}_p50_ms"], out[f"distributed_rtt{name}_p99_ms"]
        assert 0.0 < p50 <= p99 < 1000.0, name
    parts = sum(out[f"distributed_rtt_{n}_p50_ms"] for n in ("feed", "processing", "transit"))
    assert parts < 3 * out["distributed_rtt_p50_ms"]  # parts of the same round trips


@pytest.mark.slow
def test_the_lockstep_benchmark_reports_cpu_time_per_tick_of_every_process():
    from simatch.bench.distributed import lockstep

    out = lockstep(seconds=2.0)
    assert out["distributed_lockstep_digest_equal"]
    cpu = [
        out[f"distributed_lockstep_{name}_cpu_ms_per_tick"]
        for name in ("embedded", "server_main", "server_zenoh", "team")
    ]
    assert all(0.0 < ms < 1000.0 for ms in cpu), cpu
    # the three processes' CPU against the embedded run's, from the same figures
    assert out["distributed_lockstep_cpu_ratio"] >= (cpu[1] + cpu[2] + cpu[3]) / cpu[0] - 0.01
