"""`simatch bench --only envs` and scripts/compare_envs.py report their figures (speed itself is never judged by
a test); the compare script's simatch rows run here, the peers' venvs are the script's business."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_the_envs_benchmark_reports_one_env_and_subprocess_envs():
    from simatch.bench import BENCHMARKS
    from simatch.bench.envs import run

    assert BENCHMARKS["envs"] == "simatch.bench.envs:run"
    out = run(0.5)
    n = out["envs_vector_workers"]
    for scene in ("striker_1v0", "msl_5v5"):
        for key in ("steps_per_cpu_s", "steps_per_s", f"vec{n}_steps_per_s", f"vec{n}_scaling"):
            assert out[f"envs_{scene}_{key}"] > 0, key
    assert out["envs_msl_5v5_parallel_steps_per_cpu_s"] > 0


def test_compare_envs_measures_simatch_and_refuses_missing_peer_venvs(tmp_path):
    script = str(ROOT / "scripts/compare_envs.py")
    proc = subprocess.run(
        [sys.executable, script, "--seconds", "0.5", "--only", "simatch", "--json"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    rows = json.loads(proc.stdout)
    assert set(rows) == {"simatch msl_5v5", "simatch striker_1v0"}
    assert rows["simatch msl_5v5"]["agents"] == 5 and rows["simatch msl_5v5"]["sim_seconds"] == pytest.approx(0.5)
    proc = subprocess.run(
        [sys.executable, script, "--only", "vmas", "--no-install", "--peers-dir", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode != 0 and "run without --no-install" in proc.stderr
