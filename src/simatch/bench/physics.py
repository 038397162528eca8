"""Physics-only speed of the ``msl_5v5`` world: ten robots driven by scripted commands, no strategies, no
referee, no perception, no bus. It is the ceiling for a full match on the same machine.

The script repeats a 20 s cycle (simulated time), shaped like play:
  0-12 s   open play: every robot runs its own pattern (wide curves across the field, turning as it goes,
           crossing the others' paths);
  12-17 s  scrum: all ten converge on the ball at up to 3 m/s with their dribblers on and push;
  17-20 s  the robot holding (or nearest) the ball kicks it, ground and lob in turn; everybody chases it.
Commands change every control period (0.025 s), as a strategy would send them. A scrum is chaotic: a
tiny change anywhere changes who holds the ball when, so the figure comes from three seeds. The scrum
phases are also timed on their own (``physics_scrum_rtf``): ten robots pushing into one point is the
worst case of the physics.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..config.loader import load_scene
from ..sim.simulator import Simulator

CYCLE = 20.0
OPEN, SCRUM_END = 12.0, 17.0


def _script(sim: Simulator, t: float, rng: np.random.Generator, state: dict) -> None:
    """One control period of the scripted drivers (vectorised over the ten robots)."""
    q = sim.robot_positions()  # (N, 3) view: x y yaw
    bx, by = sim.ball_position()[:2]
    phase = t % CYCLE
    yaw = q[:, 2]
    c, s = np.cos(yaw), np.sin(yaw)
    V = state["V"]
    if phase < OPEN:
        # patterns: each robot follows a slowly turning velocity field, kept off the boards
        ang = state["spread"] + 0.7 * t
        vxw = 2.5 * np.cos(ang) - 2.4 * np.clip(q[:, 0] * 0.125, -1, 1) ** 3
        vyw = 2.5 * np.sin(ang) - 2.4 * np.clip(q[:, 1] * 0.2, -1, 1) ** 3
        V[:, 2] = 1.5
        dribble = state["off"]
    else:
        dx, dy = bx - q[:, 0], by - q[:, 1]
        dist = np.hypot(dx, dy) + 1e-9
        k = np.minimum(3.0, 2.0 * dist) / dist
        vxw, vyw = dx * k, dy * k
        V[:, 2] = np.clip(3.0 * (np.remainder(np.arctan2(dy, dx) - yaw + math.pi, 2 * math.pi) - math.pi), -6.0, 6.0)
        dribble = state["on"]
        if phase >= SCRUM_END and not state["kicked"]:
            holder = sim.ball.holder
            i = holder if holder >= 0 else int(np.argmin(dist))
            sim.command_action(i, True, 8.0, bool(state["lobs"] % 2))
            if sim.mechanics["kick"] > state["kicks_seen"]:
                state["kicked"] = True
                state["kicks_seen"] = sim.mechanics["kick"]
                state["lobs"] += 1
    V[:, 0] = c * vxw + s * vyw
    V[:, 1] = c * vyw - s * vxw
    sim.command_all(V, dribble)
    if phase < SCRUM_END:
        state["kicked"] = False
    # a ball that leaves the field is put back in play near the centre
    if abs(bx) > 11.5 or abs(by) > 7.5:
        sim.set_model_state(
            "ball", x=float(rng.uniform(-3, 3)), y=float(rng.uniform(-2, 2)), z=0.11, vx=0.0, vy=0.0, vz=0.0
        )


def _state(sim: Simulator) -> dict:
    return {
        "spread": np.arange(sim.n) * (2 * math.pi / sim.n),
        "kicked": False,
        "kicks_seen": 0,
        "lobs": 0,
        "V": np.zeros((sim.n, 3)),
        "on": np.ones(sim.n, dtype=bool),
        "off": np.zeros(sim.n, dtype=bool),
    }


def _loop(sim: Simulator, seconds: float, rng: np.random.Generator, state: dict, stats: dict) -> None:
    control = sim.control_steps
    d = sim.d
    clock = time.perf_counter
    for _ in range(round(seconds / sim.dt) // control):
        scrum = OPEN <= sim.time % CYCLE < SCRUM_END
        t0 = clock()
        _script(sim, sim.time, rng, state)
        sim.step(control)
        nc = d.ncon  # contacts sampled once per control period
        stats["contacts"] += nc
        stats["ticks"] += 1
        if scrum:
            stats["scrum_wall"] += clock() - t0
            stats["scrum_ticks"] += 1
            stats["scrum_contacts"] += nc


def _stats() -> dict:
    return {"contacts": 0, "ticks": 0, "scrum_ticks": 0, "scrum_contacts": 0, "scrum_wall": 0.0}


SEEDS = (1, 2, 3)


def run(seconds: float | None = None) -> dict:
    """Three runs of ``seconds`` (default 60 s each, three cycles) with different seeds; the scrums are
    chaotic, so one run alone would say as much about its own luck as about the simulator."""
    seconds = seconds or 60.0
    scene = load_scene("msl_5v5").spec
    # warm-up, not timed: loads (or compiles) the simulator's kernels and runs every code path once
    warm = Simulator(scene, seed=99)
    _loop(warm, CYCLE, np.random.default_rng(99), _state(warm), _stats())
    stats = _stats()
    sim_time = wall = cpu = 0.0
    steps = kicks = catches = 0
    rtfs = []
    for seed in SEEDS:
        sim = Simulator(scene, seed=seed)
        t0, c0 = time.perf_counter(), time.process_time()
        _loop(sim, seconds, np.random.default_rng(seed), _state(sim), stats)
        w = time.perf_counter() - t0
        cpu += time.process_time() - c0
        rtfs.append(round(sim.time / w, 1))
        wall += w
        sim_time += sim.time
        steps += sim.step_index
        kicks += sim.mechanics["kick"]
        catches += sim.mechanics["dribble_start"]
    scrums = stats["scrum_ticks"]  # none in a run shorter than the first scrum (--seconds): no figure
    return {
        "physics_rtf": round(sim_time / wall, 1),
        # per second of this process's CPU time (compare with match_cpu_rtf on a machine shared with other work)
        "physics_cpu_rtf": round(sim_time / max(cpu, 1e-9), 1),
        "physics_rtf_per_seed": rtfs,
        "physics_scrum_rtf": round(scrums * sim.control_steps * sim.dt / stats["scrum_wall"], 1) if scrums else None,
        "physics_steps_per_s": round(steps / wall),
        "physics_us_per_step": round(wall / steps * 1e6, 2),
        "physics_sim_seconds": round(sim_time, 3),
        "physics_mean_contacts": round(stats["contacts"] / max(1, stats["ticks"]), 2),
        "physics_scrum_mean_contacts": round(stats["scrum_contacts"] / scrums, 2) if scrums else None,
        "physics_kicks": int(kicks),
        "physics_ball_catches": int(catches),
    }
