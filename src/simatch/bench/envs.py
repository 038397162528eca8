"""The speed of the learning environments (``simatch bench --only envs``; needs the ``learn`` extra).

For ``striker_1v0`` (one robot, the drill judge) and ``msl_5v5`` (one learner among nine nubot robots, the
referee): the Gymnasium env stepped with random actions for ``seconds`` simulated seconds, episodes reset as
they end, first one env in this process, then N envs in N subprocesses (Gymnasium's `AsyncVectorEnv`, N = the
cores of the machine). One env step is one control period (25 ms).

* ``envs_<scene>_steps_per_cpu_s``: env steps per CPU second of this process (the machine is shared: wall time
  would count the others' work too); the goal for msl_5v5 is 1,000 (25 simulated seconds per second, one core);
* ``envs_<scene>_steps_per_s``: the same against the wall clock;
* ``envs_<scene>_vec<N>_steps_per_s``: all N subprocess envs together, wall clock, and ``..._scaling``: that over
  the one env's wall figure (N would be linear);
* ``envs_msl_5v5_parallel_steps_per_cpu_s``: the PettingZoo env with the five cyan robots learning.
"""

from __future__ import annotations

import os
import time

import numpy as np

SCENES = ("striker_1v0", "msl_5v5")
PERIOD = 0.025


def _one(scene: str, steps: int) -> tuple[float, float]:
    import simatch.envs

    env = simatch.envs.SimatchEnv(scene)
    env.action_space.seed(0)
    actions = [env.action_space.sample() for _ in range(256)]
    try:
        env.reset(seed=0)
        cpu, wall = time.process_time(), time.perf_counter()
        for k in range(steps):
            *_, terminated, truncated, _ = env.step(actions[k % len(actions)])
            if terminated or truncated:
                env.reset()
        return steps / (time.process_time() - cpu), steps / (time.perf_counter() - wall)
    finally:
        env.close()


def _parallel(scene: str, steps: int) -> float:
    import simatch.envs

    env = simatch.envs.parallel_env(scene)
    rng = np.random.default_rng(0)
    try:
        env.reset(seed=0)
        cpu = time.process_time()
        for _ in range(steps):
            env.step({a: rng.uniform(-1, 1, 6).astype(np.float32) for a in env.agents})
            if not env.agents:
                env.reset()
        return steps / (time.process_time() - cpu)
    finally:
        env.close()


def _make(scene: str):
    def thunk():
        import simatch.envs

        return simatch.envs.SimatchEnv(scene)

    return thunk


def _vector(scene: str, n: int, steps: int) -> float:
    from gymnasium.vector import AsyncVectorEnv

    # the workers start from a fresh interpreter (forkserver), not as forks of this process: a fork copies the
    # locks other threads of this process hold (a test session's browser driver, a bus), and a worker hung on
    # one of them under Python 3.13 (the default start method forks on Linux until Python 3.14)
    envs = AsyncVectorEnv([_make(scene) for _ in range(n)], context="forkserver")
    try:
        envs.reset(seed=0)
        envs.action_space.seed(0)
        envs.step(envs.action_space.sample())  # every worker warm
        wall = time.perf_counter()
        for _ in range(steps):
            envs.step(envs.action_space.sample())
        return n * steps / (time.perf_counter() - wall)
    finally:
        envs.close()


def run(seconds: float | None = None) -> dict:
    seconds = seconds or 60.0
    steps = max(1, round(seconds / PERIOD))
    n = max(2, os.cpu_count() or 1)
    out: dict = {"envs_vector_workers": n}
    for scene in SCENES:
        _one(scene, 50)  # warm-up: compiled kernels, every code path once
        cpu_rate, wall_rate = _one(scene, steps)
        out[f"envs_{scene}_steps_per_cpu_s"] = round(cpu_rate, 1)
        out[f"envs_{scene}_steps_per_s"] = round(wall_rate, 1)
        vec = _vector(scene, n, max(1, steps // n))
        out[f"envs_{scene}_vec{n}_steps_per_s"] = round(vec, 1)
        out[f"envs_{scene}_vec{n}_scaling"] = round(vec / wall_rate, 2)
    out["envs_msl_5v5_parallel_steps_per_cpu_s"] = round(_parallel("msl_5v5", steps), 1)
    return out
