"""`simatch bench --only record` reports its figures (never judged here: speed is the bench's business)."""

from __future__ import annotations


def test_the_recording_benchmark_reports_its_figures():
    from simatch.bench.record import run

    out = run(0.5)
    for label in ("match", "scripted"):
        assert out[f"record_{label}_same_digest"] is True  # recording never changes a run
        for key in (
            "rtf_plain",
            "rtf_recorded",
            "overhead_pct",
            "main_overhead_pct",
            "wall_overhead_pct",
            "ms_per_sim_s",
            "main_ms_per_sim_s",
            "plain_ms_per_sim_s",
            "mb_per_sim_minute",
        ):
            assert isinstance(out[f"record_{label}_{key}"], float), key
        topics = out[f"record_{label}_topics_mb_per_sim_minute"]
        assert {"model_states", "OmniVisionInfo", "VelCmd", "scene"} <= set(topics)
        assert out[f"record_{label}_mb_per_sim_minute"] > 0
