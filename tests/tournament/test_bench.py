"""`simatch bench --only tournament` reports its figures (never judged here: speed is the bench's business)."""

from __future__ import annotations

import pytest


@pytest.mark.slow
def test_the_tournament_benchmark_reports_its_figures():
    from simatch.bench.tournament import run

    out = run(2.0)  # matches of two 1 s halves: the figures mean nothing, their presence is checked
    assert out["tournament_same_digests"] is True  # a plain loop and Ray play the same matches
    assert out["tournament_matches"] == 4 and out["tournament_cores"] >= 1
    for key in ("plain", "ray1", "ray_all"):
        assert out[f"tournament_{key}_wall_s"] > 0 and out[f"tournament_{key}_cpu_s"] > 0
        assert out[f"tournament_{key}_matches_per_hour"] > 0
    for key in ("speedup_all_cores", "ray_overhead_pct", "ray_cpu_overhead_pct", "ray_start_s"):
        assert isinstance(out[f"tournament_{key}"], float), key
