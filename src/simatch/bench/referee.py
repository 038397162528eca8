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

from ..scene.referee import MslReferee
from .physics import _script, _state


class TimedReferee(MslReferee):
    """The referee, adding up the CPU time of its own work (its tick and its ball-contact callback)."""

    cpu = 0.0

    def tick(self, now: float) -> None:
        t = time.process_time()
        super().tick(now)
        self.cpu += time.process_time() - t

    def _on_contacts(self, msg) -> None:
        t = time.process_time()
        super()._on_contacts(msg)
        self.cpu += time.process_time() - t


def _run(kind: str, seconds: float) -> tuple[float, int, object]:
    from ..simulation import Simulation

    overrides = {"teams.cyan.strategy": "none", "teams.magenta.strategy": "none", "judge.kind": kind}
    if kind != "none":  # no cards: every robot stays on the field, as in the run without the referee
        overrides.update({"judge.charging_card": None, "judge.charging_red_speed": None})
    sim = Simulation("msl_5v5", seed=1, overrides=overrides)
    judge = sim.judge
    rng, state = np.random.default_rng(1), _state(sim.simulator)
    control = sim.simulator.control_steps
    steps = round(seconds / sim.dt) // control * control
    t0 = time.process_time()
    for _ in range(steps // control):
        _script(sim.simulator, sim.time, rng, state)
        sim.step(control)
    cpu = time.process_time() - t0
    sim.close()
    return cpu, steps, judge


def run(seconds: float | None = None) -> dict:
    seconds = seconds or 60.0
    timed = f"{__name__}:TimedReferee"
    _run(timed, 5.0)  # warm-up: kernels, every code path once
    base, steps, _ = _run("none", seconds)
    wall, steps, judge = _run(timed, seconds)
    own = judge.cpu
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
