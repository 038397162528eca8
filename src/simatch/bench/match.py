"""Full-match speed (``match_rtf``): the shipped ``msl_5v5`` scene as a user runs it — physics at 200 Hz,
both teams' default strategies, the scene's judge (the automatic referee), no recording — from the
kick-off on, in this process.

It is measured in the same ``simatch bench`` run as the physics-only figure (``physics_rtf``), so the two
can be compared: the difference is what the strategies, perception, bus and referee cost. Besides the
real-time factor it reports where the time goes per control tick (the robots' decisions, in microseconds
per robot and tick), so that a slow-down can be traced to a part.
"""

from __future__ import annotations

import math
import time

from ..config.loader import load_scene
from ..simulation import Simulation
from ..strategy.node import RobotNode
from ..strategy.nubot.warm import load_kernels as load_nubot_kernels

WARM_UP = 5.0  # simulated seconds run first, untimed (compiled kernels load, caches fill)


def timed_decisions(sim: Simulation, clock=time.perf_counter) -> list[float]:
    """Wrap every robot's decide to add up its time (by ``clock``, wall time by default) in the returned
    one-element list."""
    total = [0.0]
    for node in sim.robot_nodes.values():
        if not isinstance(node, RobotNode):
            continue
        decide = node.strategy.decide

        def timed(world, decide=decide):
            t0 = clock()
            try:
                return decide(world)
            finally:
                total[0] += clock() - t0

        node.strategy.decide = timed
    return total


def load_kernels(scene) -> None:
    """Load (or, on a fresh clone, compile and cache) the compiled kernels a match may first need late, so
    that no compilation falls into the timed part: a throwaway run of the scene in which a robot, driven
    by hand, catches the ball, holds it while turning, and kicks it (the ball mechanisms' kernels; the
    strategies' and perception's run in the warm-up of the timed match itself), and the default team's
    kernels that only open play needs (the warm-up may end before the kick-off is taken)."""
    load_nubot_kernels()
    with Simulation(scene, seed=0) as sim:
        name = next(iter(sim.robot_nodes))
        me = sim.model_states()[name]
        sim.take_control(name)
        sim.set_model_state(
            "ball", x=me.x + 0.45 * math.cos(me.yaw), y=me.y + 0.45 * math.sin(me.yaw), z=0.11, vx=0.0, vy=0.0, vz=0.0
        )
        sim.send_action(name, dribble=True)
        sim.send_vel(name, 0.3, 0.0, 0.0)
        sim.run(seconds=0.5, until_done=False)
        sim.send_vel(name, 0.0, 0.0, 1.0)
        sim.run(seconds=0.3, until_done=False)
        sim.send_action(name, dribble=False, kick=3.0)
        sim.run(seconds=0.2, until_done=False)


def run(seconds: float | None = None) -> dict:
    seconds = seconds or 120.0
    scene = load_scene("msl_5v5")
    load_kernels(scene)
    with Simulation(scene, seed=1) as sim:
        sim.run(seconds=WARM_UP)
        decisions = timed_decisions(sim)
        robots = len(sim.robot_nodes)
        ticks0 = sim.clock.step_index
        t0, c0 = time.perf_counter(), time.process_time()
        sim.run(seconds=seconds, until_done=False)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        simulated = (sim.clock.step_index - ticks0) * sim.dt
        control_ticks = simulated / scene.spec.control.period
        result = sim.result()["result"]
    out = {
        "match_rtf": round(simulated / wall, 1),
        # simulated seconds per second of this process's CPU time: what match_rtf would be on an idle core
        # (on a machine shared with other work, wall time also counts the time others held the core)
        "match_cpu_rtf": round(simulated / max(cpu, 1e-9), 1),
        "match_sim_seconds": round(simulated, 3),
        "match_wall_seconds": round(wall, 3),
        "match_ms_per_sim_second": round(wall / simulated * 1e3, 2),
        "match_decide_us_per_robot_tick": round(decisions[0] / max(1.0, control_ticks * robots) * 1e6, 1),
        "match_decide_share": round(decisions[0] / wall, 3),
    }
    if isinstance(result, dict) and "score" in result:
        out["match_score"] = result["score"]
    return out
