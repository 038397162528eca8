"""The speed of the encirclement scene (``encirclement_9v7``: 16 robots deciding at 20 Hz, the judge):
whole runs as ``simatch run`` makes them, seeds 0, 1, 2, ... until ``seconds`` of simulated time are done.

``encirclement_rtf`` is simulated seconds per CPU second of this process (the machine is shared: wall-clock
time would count the others' work too); ``encirclement_wall_rtf`` is the same runs against the wall clock.
"""

from __future__ import annotations

import statistics
import time


def one_run(scene: str, seed: int, overrides: dict | None = None) -> tuple[float, float, float, dict]:
    """A whole run of ``scene`` as ``simatch run`` makes it: (simulated s, CPU s, wall s, the judge's result)."""
    from ..simulation import Simulation

    with Simulation(scene, seed=seed, overrides=overrides) as sim:
        cpu, wall = time.process_time(), time.perf_counter()
        sim.run()
        cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
        return sim.time, cpu, wall, sim.judge.result()


def _one(seed: int) -> tuple[float, float, float, dict]:
    return one_run("encirclement_9v7", seed)


def run(seconds: float | None = None) -> dict:
    seconds = seconds or 60.0
    _one(0)  # warm-up: compiled kernels, every code path once
    sim = cpu = wall = 0.0
    times, captured, runs = [], 0, 0
    while sim < seconds:
        t, c, w, result = _one(runs)
        sim, cpu, wall, runs = sim + t, cpu + c, wall + w, runs + 1
        captured += result["captured"] == result["targets"]
        if result["capture_time_s"] is not None:
            times.append(result["capture_time_s"])
    return {
        "encirclement_rtf": round(sim / cpu, 1),
        "encirclement_wall_rtf": round(sim / wall, 1),
        "encirclement_sim_seconds": round(sim, 3),
        "encirclement_runs": runs,
        "encirclement_all_captured": captured,
        "encirclement_capture_time_median_s": round(statistics.median(times), 2) if times else None,
    }
