"""What the automatic referee costs per physics step, in a busy ``msl_5v5`` run: the physics benchmark's
scripted drivers (patterns across the field, scrums of all ten robots on the ball, kicks and lobs), which
ignore the referee's commands, so the referee keeps judging, stopping, placing the ball and restarting.

Two figures from the same script, run once with the referee and once without (``judge.kind = none``), in
CPU time of this process (the machine is shared; wall-clock time would count the others' work too):

* ``referee_us_per_step``: the referee's own time (its node tick and its ball-contact callback);
* ``referee_overhead_us_per_step``: the difference of the two whole runs, which adds what the simulator
  spends publishing ``model_states`` and ``ball_contacts`` because the referee listens.
"""

from __future__ import annotations

import time

import numpy as np

from .physics import _script, _state


def _run(kind: str, seconds: float) -> tuple[float, float, int, object]:
    from ..simulation import Simulation

    overrides = {"teams.cyan.strategy": "none", "teams.magenta.strategy": "none", "judge.kind": kind}
    if kind == "msl_referee":      # no cards: every robot stays on the field, as in the run without the referee
        overrides.update({"judge.charging_card": None, "judge.charging_red_speed": None})
    sim = Simulation("msl_5v5", seed=1, overrides=overrides)
    own = [0.0]
    judge = sim.judge
    if kind == "msl_referee":
        tick, contacts = judge.tick, judge.m.touches.on_contacts

        def timed_tick(now, tick=tick):
            t = time.process_time()
            tick(now)
            own[0] += time.process_time() - t

        def timed_contacts(msg, contacts=contacts):
            t = time.process_time()
            contacts(msg)
            own[0] += time.process_time() - t

        judge.tick = timed_tick
        judge.m.touches.on_contacts = timed_contacts
    rng, state = np.random.default_rng(1), _state(sim.simulator)
    control = sim.simulator.control_steps
    steps = round(seconds / sim.dt) // control * control
    t0 = time.process_time()
    for _ in range(steps // control):
        _script(sim.simulator, sim.time, rng, state)
        sim.step(control)
    wall = time.process_time() - t0
    sim.close()
    return wall, own[0], steps, judge


def run(seconds: float | None = None) -> dict:
    seconds = seconds or 60.0
    _run("msl_referee", 5.0)                          # warm-up: kernels, every code path once
    base, _, steps, _ = _run("none", seconds)
    wall, own, steps, judge = _run("msl_referee", seconds)
    kinds: dict[str, int] = {}
    for ev in judge.log:
        kinds[ev.type] = kinds.get(ev.type, 0) + 1
    return {
        "referee_us_per_step": round(own / steps * 1e6, 2),
        "referee_overhead_us_per_step": round((wall - base) / steps * 1e6, 2),
        "referee_run_us_per_step": round(wall / steps * 1e6, 2),
        "referee_baseline_us_per_step": round(base / steps * 1e6, 2),
        "referee_sim_seconds": round(steps * judge.dt, 3),
        "referee_decisions": {k: v for k, v in sorted(kinds.items()) if k not in ("command", "ball_placed")},
    }
