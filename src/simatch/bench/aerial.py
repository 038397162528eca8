"""The speed of the aerial scenes, whole runs as ``simatch run`` makes them (seeds 0, 1, 2, ... until
``seconds`` of simulated time are done for each), on one core:

* ``aerial_encirclement``: nine ground chasers, three drones (their flight controller inside every physics
  step), seven targets, eight obstacles, sight lines and camera cones every control tick (goal: 20 times
  real time);
* ``pursuit_evasion_3d``: four drones among obstacles under a ceiling;
* ``quadrotor_flight``: the flight test, one drone (the cost of a flying body and its controller alone).

``*_rtf`` is simulated seconds per CPU second of this process (the machine may be shared: wall-clock time
would count the others' work too); ``*_wall_rtf`` the same runs against the wall clock.
"""

from __future__ import annotations

from .encirclement import one_run

SCENES = {
    "aerial_encirclement": "aerial_encirclement",
    "pursuit_3d": "pursuit_evasion_3d",
    "flight": "quadrotor_flight",
}


def run(seconds: float | None = None) -> dict:
    seconds = seconds or 60.0
    out: dict = {}
    for key, scene in SCENES.items():
        one_run(scene, 0, {"judge.hover": 1.0} if scene == "quadrotor_flight" else None)  # warm-up
        sim = cpu = wall = 0.0
        runs = 0
        while sim < seconds:
            t, c, w, _ = one_run(scene, runs)
            sim, cpu, wall, runs = sim + t, cpu + c, wall + w, runs + 1
        out[f"{key}_rtf"] = round(sim / cpu, 1)
        out[f"{key}_wall_rtf"] = round(sim / wall, 1)
        out[f"{key}_sim_seconds"] = round(sim, 3)
        out[f"{key}_runs"] = runs
    return out
