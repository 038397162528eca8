"""Dataset export speed (issue 21): ``simatch export`` of a recorded match against the run that recorded it.

Both are timed as a user runs them, each command in a process of its own (start-up and imports included):
``simatch run msl_5v5 --duration S --record F.mcap`` (its writer process included), then ``simatch export
F.mcap`` to Parquet and to CSV. CPU time (user + system of the command and its children) moves less than
wall time on a shared machine; both are reported, and the fastest of ``REPEATS`` runs of each counts. The
figure the issue asks for is ``export_parquet_vs_run`` (wall time of the export / wall time of the run):
at most 1.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .host import cpu_times, steal_pct

REPEATS = 2


def _timed(argv: list[str]) -> tuple[float, float]:
    """(wall, CPU) seconds of a command run to its end (CPU: its own and its children's)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def run(seconds: float | None = None) -> dict:
    seconds = seconds or 120.0
    simatch = [sys.executable, "-m", "simatch"]
    times: dict[str, list[tuple[float, float]]] = {"run": [], "parquet": [], "csv": []}
    size = 0
    steal0 = cpu_times()
    with tempfile.TemporaryDirectory(prefix="simatch-bench-export-") as tmp:
        for rep in range(REPEATS):
            path = Path(tmp) / f"match{rep}.mcap"
            times["run"].append(
                _timed(simatch + ["run", "msl_5v5", "--duration", str(seconds), "--record", str(path), "--quiet"])
            )
            size = os.path.getsize(path)
            for fmt in ("parquet", "csv"):
                out = Path(tmp) / f"{fmt}{rep}"
                times[fmt].append(_timed(simatch + ["export", str(path), "--format", fmt, "--out", str(out)]))
    best = {k: (min(w for w, _ in v), min(c for _, c in v)) for k, v in times.items()}
    out: dict = {"export_recording_sim_seconds": seconds, "export_recording_mb": round(size / 1e6, 1)}
    for kind, (wall, cpu) in best.items():
        out[f"export_{kind}_wall_s"] = round(wall, 2)
        out[f"export_{kind}_cpu_s"] = round(cpu, 2)
    for fmt in ("parquet", "csv"):
        out[f"export_{fmt}_vs_run"] = round(best[fmt][0] / best["run"][0], 2)
        out[f"export_{fmt}_cpu_vs_run"] = round(best[fmt][1] / best["run"][1], 2)
    out["export_host_steal_pct"] = steal_pct(steal0, cpu_times())
    return out
