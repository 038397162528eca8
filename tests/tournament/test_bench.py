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
    for key in ("speedup_all_cores", "ray_overhead_pct", "ray_cpu_overhead_pct", "ray_start_s", "ray_start_cpu_s"):
        assert isinstance(out[f"tournament_{key}"], float), key
    # where Ray's CPU went: the driver, the workers (one per slot, reused match after match) and Ray's own
    # processes, which add up to the run's CPU time
    assert out["tournament_ray1_workers"] == 1 and 1 <= out["tournament_ray_all_workers"] <= out["tournament_cores"]
    for key in ("ray1", "ray_all"):
        kinds = out[f"tournament_{key}_cpu_by_process"]
        assert {"driver", "worker", "raylet", "gcs_server"} <= set(kinds), kinds
        assert kinds["worker"] > 0 and all(v >= 0 for v in kinds.values()), kinds
        assert sum(kinds.values()) == pytest.approx(out[f"tournament_{key}_cpu_s"], abs=0.05)
