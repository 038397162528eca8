"""MuJoCo's profiling clock is replaced by a native zero clock in simatch's runs, unless the process has its
own clock or asks for MuJoCo's timers; the world moves the same either way."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import mujoco

from simatch.config.loader import load_scene
from simatch.sim.simulator import Simulator
from simatch.sim.timers import keep_timers_off


def _run(code: str, **env) -> str:
    out = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, **env},
        check=True,
    )
    return out.stdout.strip()


def test_a_simulator_turns_the_timers_off_and_they_still_count():
    sim = Simulator(load_scene("msl_5v5").spec, seed=0)
    assert mujoco.get_mjcb_time() is not None
    assert keep_timers_off()  # a second call keeps what the first installed
    before = int(sim.d.timer[mujoco.mjtTimer.mjTIMER_STEP].number)
    sim.step(10)
    step = sim.d.timer[mujoco.mjtTimer.mjTIMER_STEP]
    assert int(step.number) == before + 10
    assert step.duration == 0.0


_DIGEST = """
    import hashlib, mujoco, numpy as np
    from simatch.config.loader import load_scene
    from simatch.sim.simulator import Simulator
    {prelude}
    sim = Simulator(load_scene("msl_5v5").spec, seed=3)
    sim.command_all(np.tile([2.0, 0.5, 1.0], (sim.n, 1)), np.ones(sim.n, dtype=bool))
    sim.step(400)
    print(mujoco.get_mjcb_time() is None, hashlib.sha256(sim.d.qpos.tobytes() + sim.d.qvel.tobytes()).hexdigest())
    {tail}
"""


def test_an_own_clock_or_the_environment_keeps_mujocos_timers_and_the_world_moves_the_same():
    off = _run(_DIGEST.format(prelude="", tail=""))
    kept = _run(_DIGEST.format(prelude="", tail=""), SIMATCH_MUJOCO_TIMERS="1")
    assert off.split()[0] == "False" and kept.split()[0] == "True"
    assert off.split()[1] == kept.split()[1]
    own = _run(
        _DIGEST.format(
            prelude="import ctypes, time\n    own = ctypes.CFUNCTYPE(ctypes.c_double)(time.perf_counter)\n"
            "    mujoco.set_mjcb_time(own)",
            tail="print(mujoco.get_mjcb_time() is own, sim.d.timer[mujoco.mjtTimer.mjTIMER_STEP].duration > 0)",
        )
    )
    first, second = own.splitlines()
    assert first.split()[1] == off.split()[1]
    assert second == "True True"
